"""``biotac-bench cheetah serve``'s sensor count: the scene's with SCENE (as ``bridge --scene``), 3 without, and
``--sensors`` when given; its help says so."""

from __future__ import annotations

import pytest

from bench.cli import main as cli

pytestmark = pytest.mark.firmware

TWO_SENSORS = """
[scene]
name = "pair"
duration_s = 0.5
[[stimulus]]
kind = "tap"
sensor = 2
at_s = 0.2
peak_N = 0.5
"""


@pytest.fixture
def served(monkeypatch):
    """The number of sensors on the bus of each adapter ``cheetah serve`` starts."""
    from bench.hosts import cheetah_server

    counts = []

    class Recorded(cheetah_server.CheetahBench):
        def start(self):
            counts.append(len(self.bus.ports))
            return super().start()

    monkeypatch.setattr(cheetah_server, "CheetahBench", Recorded)
    return counts


@pytest.mark.parametrize("args, n", [((), 3), (("SCENE",), 2), (("SCENE", "--sensors", "4"), 4)],
                         ids=["no scene: 3", "a scene of 2: 2", "a scene of 2 with --sensors 4: 4"])
def test_cheetah_serve_serves_the_scenes_sensor_count_by_default(tmp_path, capsys, served, args, n):
    scene = tmp_path / "pair.toml"
    scene.write_text(TWO_SENSORS)
    argv = ["cheetah", "serve", *(str(scene) if a == "SCENE" else a for a in args), "--seconds", "0.05"]
    assert cli.main(argv) == 0
    err = capsys.readouterr().err
    assert served == [n] and f"with {n} emulated sensor(s)" in err, (served, err)


def test_cheetah_serve_help_states_the_default_sensor_count(capsys):
    with pytest.raises(SystemExit):
        cli.main(["cheetah", "serve", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "(default: the scene's count with SCENE, else 3; with SCENE at least its count)" in text, text
