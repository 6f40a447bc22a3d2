"""Scenes without sliding keep their codes bit for bit (issue 8 item 8): every shipped scene that does not slide is run
at the default profile and each channel's codes are compared with the fingerprints committed in
fixtures/fingerprints/scenes_default.json (about 3 s for all of them)."""

from __future__ import annotations

import json

import pytest

from bench.paths import REPO, SCENES_DIR
from bench.scenes.scene import load_scene
from bench.verification.benchmark import (SCENE_FINGERPRINT_COMMAND, SCENE_FINGERPRINT_FIXTURE, channel_fingerprints,
                                          fingerprint_environment, scene_slides)

pytestmark = pytest.mark.unit

FIXTURE = json.loads(SCENE_FINGERPRINT_FIXTURE.read_text(encoding="utf-8"))
FIXTURE_NAME = SCENE_FINGERPRINT_FIXTURE.relative_to(REPO)


def changes(scene_name: str, committed: dict, now: dict) -> list[str]:
    """One line per difference between a scene's committed and recomputed fingerprints, naming sensor and channel."""
    out = [] if committed["status"] == now["status"] else [
        f"{scene_name}: run status {committed['status']!r} -> {now['status']!r}"]
    was, got = committed["channels"], now["channels"]
    for channel in sorted(set(was) | set(got)):
        if channel not in got:
            out.append(f"{scene_name} {channel}: no longer recorded")
        elif channel not in was:
            out.append(f"{scene_name} {channel}: recorded now, not in {FIXTURE_NAME}")
        elif was[channel]["codes"] != got[channel]["codes"]:
            out.append(f"{scene_name} {channel}: {was[channel]['codes']} codes -> {got[channel]['codes']}")
        elif was[channel]["sha256"] != got[channel]["sha256"]:
            out.append(f"{scene_name} {channel}: codes changed (sha256 {was[channel]['sha256']} -> "
                       f"{got[channel]['sha256']}, {got[channel]['codes']} codes)")
    return out


def explain(lines: list[str]) -> str:
    env, made = fingerprint_environment(), FIXTURE["made_with"]
    platform = "" if env == made else f"\n(the fixture was made with {made}, this run uses {env}: floating point may differ)"
    return ("\n".join(lines) + f"\nA scene without sliding must keep its codes bit for bit. If the change is intended, "
            f"regenerate {FIXTURE_NAME} with `{SCENE_FINGERPRINT_COMMAND}` and say why in the commit." + platform)


def test_the_fixture_covers_exactly_the_shipped_scenes_that_do_not_slide():
    not_sliding = {p.stem for p in SCENES_DIR.glob("*.toml") if not scene_slides(load_scene(p))}
    assert len(not_sliding) >= 8, not_sliding
    assert set(FIXTURE["scenes"]) == not_sliding, explain(
        [f"{name}: a shipped scene without sliding, not in {FIXTURE_NAME}" for name in sorted(not_sliding -
                                                                                               set(FIXTURE["scenes"]))]
        + [f"{name}: in {FIXTURE_NAME} but not a shipped scene without sliding" for name in
           sorted(set(FIXTURE["scenes"]) - not_sliding)])


@pytest.mark.parametrize("scene_name", sorted(FIXTURE["scenes"]))
def test_a_scene_without_sliding_keeps_its_codes_bit_for_bit(scene_name):
    scene = load_scene(SCENES_DIR / f"{scene_name}.toml")
    scene.fidelity = FIXTURE["profile"]
    lines = changes(scene_name, FIXTURE["scenes"][scene_name], channel_fingerprints(scene))
    assert not lines, explain(lines)


def test_a_changed_code_is_named_by_scene_and_channel():
    committed = FIXTURE["scenes"]["rest"]
    now = json.loads(json.dumps(committed))
    now["channels"]["sensor1/PDC"]["sha256"] = "0" * 16
    now["channels"]["sensor1/E7"]["codes"] += 1
    del now["channels"]["sensor1/TDC"]
    lines = changes("rest", committed, now)
    assert lines == ["rest sensor1/E7: {0} codes -> {1}".format(committed["channels"]["sensor1/E7"]["codes"],
                                                               now["channels"]["sensor1/E7"]["codes"]),
                     f"rest sensor1/PDC: codes changed (sha256 {committed['channels']['sensor1/PDC']['sha256']} -> "
                     f"{'0' * 16}, {committed['channels']['sensor1/PDC']['codes']} codes)",
                     "rest sensor1/TDC: no longer recorded"], lines


def test_write_fixture_rewrites_the_fixture_and_refuses_other_arguments(tmp_path, monkeypatch, capsys):
    from bench.verification import benchmark

    target = tmp_path / "fingerprints" / "scenes_default.json"
    monkeypatch.setattr(benchmark, "SCENE_FINGERPRINT_FIXTURE", target)
    monkeypatch.setattr(benchmark, "non_sliding_scene_fingerprints", lambda: FIXTURE["scenes"])  # not the 3 s run
    assert benchmark._fingerprints_main(["--write-fixture"]) == 0
    doc = json.loads(target.read_text(encoding="utf-8"))
    assert doc["scenes"] == FIXTURE["scenes"] and doc["profile"] == "default"
    assert SCENE_FINGERPRINT_COMMAND in doc["regenerate"] and doc["made_with"] == fingerprint_environment()
    assert str(target) in capsys.readouterr().out
    for argv in (["--write-fixture", "out.json"], ["--write-fixture", "--scenes", str(tmp_path)], []):
        with pytest.raises(SystemExit) as e:
            benchmark._fingerprints_main(argv)
        assert e.value.code == 2, argv
        assert "--write-fixture" in capsys.readouterr().err
    assert list(target.parent.iterdir()) == [target]  # written atomically, no temporary left
