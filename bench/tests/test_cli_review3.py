"""Small command-line mismatches (review 3): ``record``'s exit status when nothing arrives agrees with its help
(2, as bad input), ``rtl lint`` says "lint clean" whenever Verilator exits 0, ``bridge --scene`` serves the
scene's sensor count by default, and ``run`` prints — and record.json and report.md hold — the serial each
sensor answers (a BioTac SP's "BTSP…" one, as on the wire)."""

from __future__ import annotations

import json
import subprocess

import pytest

from bench.cli import main as cli
from bench.paths import SCENES_DIR
from bench.tests.cli_runs import run_cli

SP_SCENE = """
[scene]
name = "sp"
duration_s = {duration}
seed = 5
[sensor]
variant = "biotac-sp"
unit = 17
[[sensors]]
index = 2
variant = "biotac-sp"
unit = 18
"""
#: ... and a third sensor, sensor 1's twin (no serial of its own), that feels a tap
TWIN_TAP = '[[stimulus]]\nkind = "tap"\nat_s = 0.1\npeak_N = 1.0\nsensor = 3\n'


def sp_scene(tmp_path, duration_s: float = 2.0, extra: str = ""):
    """A scene file of two BioTac SPs, units 17 and 18, seed 5 (``extra``: more TOML)."""
    path = tmp_path / "sp.toml"
    path.write_text(SP_SCENE.format(duration=duration_s) + extra)
    return path


# --- 4. record: nothing received is exit status 2, as its help says ---------------------------------------------


@pytest.mark.firmware
def test_record_exits_2_when_the_bridge_answers_but_no_frame_arrives(tmp_path, capsys, monkeypatch):
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.driver import BridgeDriver

    monkeypatch.setattr(BridgeDriver, "frames", lambda self, **kw: iter(()))  # START acknowledged, then silence
    out = tmp_path / "rec.npz"
    with FirmwareBench(1) as fb:
        status = cli.main(["record", fb.port, "--seconds", "0.5", "--out", str(out), "--quiet",
                           "--idle-timeout", "0.2"])
    err = capsys.readouterr().err
    assert status == 2, err
    assert "error: no data for 0.2 s; nothing received, no file written" in err and "Traceback" not in err
    assert not out.exists()
    assert "2 bad arguments, nothing received" in run_cli("record", "--help").stdout  # what the help promises


# --- 5. rtl lint: "lint clean" whenever Verilator exits 0 -------------------------------------------------------

REPORT = ("- V e r i l a t i o n   R e p o r t: rev v5\n"
          "- Verilator: Built from 0.136 MB sources in 3 modules, into 0.976 MB in 3 C++ files\n")


@pytest.mark.unit
def test_rtl_lint_says_lint_clean_when_verilator_exits_0_and_shows_warnings_otherwise(monkeypatch, capsys):
    from emulator.rtl import build

    def verilator_says(code: int, text: str) -> None:
        monkeypatch.setattr(build, "lint", lambda out_dir, sp=0: subprocess.CompletedProcess([], code, "", text))

    verilator_says(0, REPORT)  # Verilator's report is never empty
    assert cli.main(["rtl", "lint"]) == 0
    out = capsys.readouterr().out
    assert REPORT.strip() in out and out.strip().endswith("lint clean: verilator --lint-only -Wall"), out
    warning = ("%Warning-WIDTH: biotac_spi.sv:10:5: Operator ASSIGNW expects 2 bits\n"
               "%Error: Exiting due to 1 warning(s)\n")
    verilator_says(1, warning + REPORT)
    assert cli.main(["rtl", "lint"]) == 1
    out = capsys.readouterr().out
    assert "%Warning-WIDTH" in out and "lint clean" not in out, out


@pytest.mark.rtl
def test_rtl_lint_on_the_shipped_rtl_says_lint_clean(capsys):
    assert cli.main(["rtl", "lint"]) == 0
    assert "lint clean" in capsys.readouterr().out


# --- 6. bridge --scene: the scene's sensor count by default ------------------------------------------------------


@pytest.mark.firmware
def test_bridge_serves_the_scenes_sensor_count_unless_told_otherwise(tmp_path, capsys):
    scene = sp_scene(tmp_path)
    assert cli.main(["bridge", "--scene", str(scene), "--fast", "--seconds", "0.2"]) == 0
    assert "bridge firmware running with 2 emulated sensor(s) built from scene 'sp'" in capsys.readouterr().out
    assert cli.main(["bridge", "--scene", str(scene), "--sensors", "3", "--fast", "--seconds", "0.2"]) == 0
    assert "running with 3 emulated sensor(s)" in capsys.readouterr().out  # more: sensor 1's twins
    assert cli.main(["bridge", "--scene", str(scene), "--sensors", "1", "--fast", "--seconds", "0.2"]) == 2
    err = capsys.readouterr().err
    assert "the scene describes 2 sensors" in err and "not 1" in err and "Traceback" not in err, err
    assert cli.main(["bridge", "--fast", "--seconds", "0.2"]) == 0  # the one seed convention, from 0 (README)
    assert "running with 1 emulated sensor(s) at rest (seed 0: sensor k draws 0 + k - 1)" in capsys.readouterr().out
    assert cli.main(["bridge", "--fast", "--seconds", "0.2", "--sensors", "2", "--seed", "7"]) == 0
    assert "running with 2 emulated sensor(s) at rest (seed 7: sensor k draws 7 + k - 1)" in capsys.readouterr().out


# --- 7. run: the serial each sensor answers, printed and recorded ----------------------------------------------


@pytest.mark.unit
def test_the_serial_reported_is_the_one_the_sensors_port_answers(tmp_path):
    """sensor_serial agrees with what each sensor's SPI port answers as its serial property, on a bus."""
    from bench.hosts.scene_sensors import sensors_from_scene
    from bench.reporting.report import sensor_serial
    from bench.scenes.scene import load_scene, parse_scene
    from emulator.spi.model import PROP_SERIAL, SensorPort

    for scene, serials in ((load_scene(sp_scene(tmp_path, extra=TWIN_TAP)),
                            ["BTSP000000000017", "BTSP000000000018", "BTSP01EMU0000003"]),
                           (parse_scene({"scene": {"name": "nominal", "duration_s": 1.0}, "sensors": [{"index": 2}]}),
                            ["BT0101EMU0000001", "BT0101EMU0000002"])):
        sensors = sensors_from_scene(scene, scene.n_sensors)
        answered = [SensorPort(sensors[k], k).properties[PROP_SERIAL][0].decode() for k in sorted(sensors)]
        assert answered == serials
        assert [sensor_serial(scene.sensor_spec(k), k) for k in sorted(sensors)] == serials


def test_run_prints_and_records_the_serial_each_sensor_answers(tmp_path):
    """Sensor 3, undescribed, is sensor 1's twin: unit 17's parameters but no serial of its own (its port's
    default).  Its record, report and line say so (``twin_of``): they said "unit 17" beside a serial that is not
    unit 17's, as if it were that unit (which one finger only can be)."""
    out = tmp_path / "out"
    r = run_cli("run", sp_scene(tmp_path, 0.2, TWIN_TAP), "--out", out, "--quiet", "--no-plots", timeout=300)
    assert r.returncode == 0, r.stderr
    assert "for sensor 2 (unit 18, serial BTSP000000000018," in r.stdout, r.stdout
    assert ("for sensor 3 (sensor 1's twin (unit 17's parameters), serial BTSP01EMU0000003 (its port's default),"
            in r.stdout), r.stdout
    record = json.loads((out / "record.json").read_text())
    assert record["sensor"] == {"index": 1, "unit": "17", "variant": "biotac-sp", "serial": "BTSP000000000017"}
    assert {k: (v["unit"], v["serial"], v.get("twin_of")) for k, v in record["sensors"].items()} == {
        "sensor2": ("18", "BTSP000000000018", None), "sensor3": ("17", "BTSP01EMU0000003", 1)}
    assert json.loads((out / "sensor2" / "record.json").read_text())["sensor"]["serial"] == "BTSP000000000018"
    assert json.loads((out / "sensor3" / "record.json").read_text())["sensor"] == {
        "index": 3, "unit": "17", "twin_of": 1, "variant": "biotac-sp", "serial": "BTSP01EMU0000003"}
    report = (out / "report.md").read_text()
    assert "- sensor 1: biotac-sp, unit 17, serial `BTSP000000000017`" in report
    assert "`sensor2/`: ok, serial `BTSP000000000018`" in report and "serial `BTSP01EMU0000003`" in report
    assert ("- sensor 3: biotac-sp, sensor 1's twin (unit 17's parameters), serial `BTSP01EMU0000003` (its port's "
            "default)") in (out / "sensor3" / "report.md").read_text()


@pytest.mark.unit
@pytest.mark.parametrize("spi, signal_name, status", [("rtl", "SIGINT", 130), ("software", "SIGTERM", 143)])
def test_a_bridge_stopped_while_it_builds_says_so(capsys, monkeypatch, spi, signal_name, status):
    """A first `bridge --spi rtl` compiles for a minute; Ctrl-C (or SIGTERM) then ends it with a line saying what
    was going on and that no port was opened — it used to exit 130 silently, and 130 for SIGTERM too."""
    from bench.cli.args import Terminated
    from bench.hosts import bridge

    def building(*args, **kwargs):
        raise Terminated() if signal_name == "SIGTERM" else KeyboardInterrupt()

    monkeypatch.setattr(bridge.FirmwareBench, "__init__", building)
    assert cli.main(["bridge", "--spi", spi, "--fast", "--seconds", "0.2"]) == status
    out, err = capsys.readouterr()
    assert out == "" and err.strip() == (f"{signal_name} while the bridge was starting (building the firmware"
                                         f"{' and the RTL' if spi == 'rtl' else ''}): no port was opened"), err


@pytest.mark.unit
def test_a_scene_path_with_a_folder_is_never_taken_for_a_shipped_scene(tmp_path, monkeypatch, capsys):
    """`./rest.toml` that is not there is an error (it silently ran the shipped rest); `rest.toml` falls back to the
    shipped scene with a note naming the file; `rest` does so quietly, as the help says."""
    monkeypatch.chdir(tmp_path)
    assert cli.main(["validate", "./rest.toml"]) == 1
    err = capsys.readouterr().err
    assert "./rest.toml" in err and "No such file or directory" in err and "close matches: rest" in err, err
    assert cli.main(["validate", "rest.toml", "rest"]) == 0
    out, err = capsys.readouterr()
    assert out.count("ok (rest, 10.0 s") == 2
    assert err.strip() == "note: no rest.toml here: the shipped scene " + str(SCENES_DIR / "rest.toml"), err


def test_bridge_takes_a_shipped_scene_by_name_as_run_does(capsys):
    assert cli.main(["bridge", "--scene", "taps", "--fast", "--seconds", "0.2"]) == 0
    assert "built from scene 'taps'" in capsys.readouterr().out


@pytest.mark.unit
@pytest.mark.parametrize("argv, words", [
    (["textures", "--group", "glass", "--show", "10"], "--show 10 prints one texture and --group glass filters"),
    (["explore", "fishel2012", "--no-cache", "--cache", "elsewhere"], "--cache elsewhere with --no-cache"),
])
def test_options_one_of_which_would_be_ignored_are_refused(argv, words, capsys, tmp_path, monkeypatch):
    """Each pair used to run with one option silently ignored (the group, the cache folder)."""
    monkeypatch.chdir(tmp_path)
    assert cli.main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and words in err and "give one or the other" in err and "Traceback" not in err, err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.unit
def test_a_folder_named_like_a_shipped_scene_does_not_hide_it(tmp_path, monkeypatch, capsys):
    """A folder "taps" in the working directory: `validate taps` runs the shipped scene, saying so (it failed with
    "Is a directory"); a folder given as a path is one line naming it."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "taps").mkdir()
    assert cli.main(["validate", "taps"]) == 0
    out, err = capsys.readouterr()
    assert "ok (taps," in out
    assert err.strip() == f"note: taps here is a folder: the shipped scene {SCENES_DIR / 'taps.toml'}"
    assert cli.main(["validate", str(tmp_path / "taps")]) == 1
    assert "Is a directory" in capsys.readouterr().err
