"""``biotac-bench validate``'s "ok" line says what a user should know before running: the SPI side when it is the
RTL, and the texture library (path, SHA-256 prefix) when the scene slides — nothing more for a scene that does
neither."""

from __future__ import annotations

import hashlib
import shutil

import pytest

from bench.cli import main as cli
from bench.paths import SCENES_DIR
from bench.textures.library import LIBRARY_PATH

pytestmark = pytest.mark.unit

SLIDE = SCENES_DIR / "sandpaper_smooth.toml"


def _ok_line(argv, capsys) -> str:
    status = cli.main([str(a) for a in argv])
    out = capsys.readouterr()
    assert status == 0, out.err
    (line,) = out.out.splitlines()
    return line


def _with_library(tmp_path, extra_scene: str = "", slides: bool = True) -> str:
    """A copy of the sliding scene (or, ``slides`` False, the same with its slide removed) naming its own library
    lib.toml (a copy of the shipped one) in ``tmp_path``; returns the library's SHA-256."""
    shutil.copy(LIBRARY_PATH, tmp_path / "lib.toml")
    text = SLIDE.read_text().replace("[scene]\n", f'[scene]\nlibrary = "lib.toml"\n{extra_scene}', 1)
    if not slides:
        text = text[:text.index("[[stimulus]]")]
    (tmp_path / "scene.toml").write_text(text)
    return hashlib.sha256((tmp_path / "lib.toml").read_text().encode("utf-8")).hexdigest()


def test_a_scene_that_does_not_slide_keeps_the_short_line(capsys):
    assert _ok_line(["validate", "taps"], capsys) == "taps: ok (taps, 6.0 s, 5 stimuli, fidelity default)"


def test_a_sliding_scene_names_its_texture_library_and_hash(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    digest = _with_library(tmp_path)
    assert _ok_line(["validate", "scene.toml"], capsys).endswith(f", textures lib.toml sha256 {digest[:16]})")
    shipped = hashlib.sha256(LIBRARY_PATH.read_text().encode("utf-8")).hexdigest()
    assert _ok_line(["validate", SLIDE], capsys).endswith(f", textures {LIBRARY_PATH} sha256 {shipped[:16]})")


def test_a_library_named_but_not_slid_on_is_not_shown_and_the_rtl_is(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    _with_library(tmp_path, slides=False)
    assert _ok_line(["validate", "scene.toml"], capsys).endswith(", 0 stimuli, fidelity default)")
    (tmp_path / "scene.toml").write_text((tmp_path / "scene.toml").read_text() + '\n[host]\nspi = "rtl"\n')
    assert _ok_line(["validate", "scene.toml"], capsys).endswith(", fidelity default, SPI rtl)")


def test_a_scene_of_several_fingers_counts_sensor_1s_stimuli_and_all_of_them(tmp_path, monkeypatch, capsys):
    """With several fingers the first count is sensor 1's alone: a scene whose only tap is on sensor 4 read
    "0 stimuli, ..., 4 sensors (1 stimuli in all)", as if the scene had none."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "hand.toml").write_text('[scene]\nname = "hand"\nduration_s = 0.5\n[[sensors]]\nindex = 2\n'
                                        '[[stimulus]]\nkind = "tap"\nsensor = 4\nat_s = 0.2\npeak_N = 1.0\n')
    assert _ok_line(["validate", "hand.toml"], capsys) == ("hand.toml: ok (hand, 0.5 s, 0 stimuli on sensor 1, fidelity "
                                                           "default, 4 sensors (1 stimulus in all))")
