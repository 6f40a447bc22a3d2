"""Sliding in scene files: the `slide` and `replace_skin` kinds and the [skin] table — every start time honoured,
one skin that wears from trial to trial, and clear errors for what cannot run."""

import pytest

from bench.errors import SceneError
from bench.scenes.scene import parse_scene
from emulator.sliding import Slide

pytestmark = pytest.mark.unit


def _scene(*stimuli, skin=None, duration=20.0):
    data = {"scene": {"name": "s", "duration_s": duration}, "stimulus": list(stimuli)}
    if skin is not None:
        data["skin"] = skin
    return parse_scene(data)


def _slide(**kw):
    d = {"kind": "slide", "start_s": 0.5, "texture": "3 mm grating", "force_N": 0.5, "velocity_mm_per_s": 20,
         "distance_mm": 20}
    d.update(kw)
    return d


def _problems(*stimuli, **kw):
    with pytest.raises(SceneError) as e:
        _scene(*stimuli, **kw)
    return "\n".join(e.value.problems)


def test_every_start_time_is_a_trial_on_one_skin_that_wears():
    sc = _scene(_slide(start_s=[0.5, 3.0, 5.5], force_N=1.26, velocity_mm_per_s=63.1, distance_mm=50))
    slides = [s for s in sc.stimuli if isinstance(s, Slide)]
    assert [s.start_s for s in slides] == [0.5, 3.0, 5.5]
    heights = [st["ridge_height_m"] for st in sc.trial_skins]
    assert heights[0] == sc.skin_before["ridge_height_m"] > heights[1] > heights[2] > sc.skin_after["ridge_height_m"]
    assert [s.skin.ridge_height_m for s in slides] == heights  # each trial slides on the skin as it was then
    assert len({s.start_position_m for s in slides}) == 3  # each lands somewhere else on the texture


def test_a_skin_replacement_restores_the_ridges_and_wear_can_be_switched_off():
    sc = _scene(_slide(start_s=[0.5, 3.0], force_N=1.26, velocity_mm_per_s=63.1, distance_mm=50),
                {"kind": "replace_skin", "at_s": 2.9})
    assert sc.trial_skins[1]["ridge_height_m"] == sc.skin_before["ridge_height_m"]
    assert sc.trial_skins[1]["serial"] == 2
    still = _scene(_slide(start_s=[0.5, 3.0]), skin={"wear": False})
    assert still.skin_after["ridge_height_m"] == still.skin_before["ridge_height_m"]
    smooth = _scene(_slide(), skin={"fingerprints": False})
    assert smooth.stimuli[0].skin.ridge_factor == 0.0


def test_the_skin_tables_ridge_height_and_wear_coefficient_reach_the_skin_that_slides():
    """README: `[skin] ridge_height_um` starts the session on a worn skin and `wear_coefficient` sets Archard's k:
    the first trial slides on ridges of the height given, and a tenfold k wears tenfold as much over the same
    trials (the worn depth, Archard: ∝ k·N·distance)."""
    from emulator.skin import Skin

    worn = _scene(_slide(), skin={"ridge_height_um": 120})
    assert worn.skin_before["ridge_height_m"] == pytest.approx(120e-6) == worn.stimuli[0].skin.ridge_height_m
    k = Skin().wear_coefficient
    lost = {}
    for factor in (1, 10):
        sc = _scene(_slide(start_s=[0.5, 3.0], force_N=1.26, velocity_mm_per_s=63.1, distance_mm=50),
                    skin={"wear_coefficient": k * factor})
        lost[factor] = sc.skin_before["ridge_height_m"] - sc.skin_after["ridge_height_m"]
    assert lost[10] == pytest.approx(10 * lost[1], rel=0.05) and lost[1] > 0


@pytest.mark.parametrize("stimulus, words", [
    (_slide(texture="no such cloth"), ["stimulus[0].texture", "no such cloth"]),
    ({k: v for k, v in _slide().items() if k != "texture"}, ["stimulus[0].texture is missing"]),
    (_slide(force_N=-1), ["stimulus[0].force_N", "-1"]),
    (_slide(velocity_mm_per_s="fast"), ["stimulus[0].velocity_mm_per_s", "'fast'"]),
    (_slide(distance_mm=0.5, velocity_mm_per_s=100), ["stimulus[0].distance_mm", "acceleration"]),
    (_slide(start_s=19.0), ["ends at", "after the end of the scene"]),
    (_slide(grip=True), ["unknown field 'grip'"]),
])
def test_bad_slides_are_named_with_field_and_value(stimulus, words):
    text = _problems(stimulus)
    for w in words:
        assert w in text


def test_overlapping_slides_and_replacements_during_a_slide_are_rejected():
    assert "overlaps" in _problems(_slide(start_s=0.5), _slide(start_s=1.0))
    assert "falls during the slide" in _problems(_slide(start_s=0.5), {"kind": "replace_skin", "at_s": 1.5})
    assert "skin.ridge_height_um" in _problems(_slide(), skin={"ridge_height_um": 500})
    assert "skin = " in _problems(_slide(), skin=[1])


def test_run_help_teaches_sliding(capsys):
    from bench.cli import main as cli

    with pytest.raises(SystemExit):
        cli.main(["run", "--help"])
    out = capsys.readouterr().out
    for word in ("slide", "velocity_mm_per_s", "replace_skin", "[skin]", "biotac-bench\n                  textures"):
        assert word in out


def test_a_sliding_scene_run_reports_properties_per_trial_and_the_skin(tmp_path):
    import json

    from bench.cli import main as cli
    from bench.paths import SCENES_DIR

    assert cli.main(["run", str(SCENES_DIR / "grating.toml"), "--out", str(tmp_path), "--quiet", "--no-plots"]) == 0
    record = json.loads((tmp_path / "record.json").read_text())
    trials = record["sliding"]["trials"]
    assert [t["force_N"] for t in trials] == [0.5, 1.5, 0.5]
    for t in trials:
        for key in ("traction", "roughness", "fineness"):
            assert isinstance(t[key], float)
        assert t["true_normal_N"] == pytest.approx(t["force_N"], rel=0.02)  # force-controlled slides
    # more force, more traction (the stage current follows the tangential load)
    assert trials[1]["traction"] > trials[0]["traction"]
    assert record["sliding"]["skin_after"]["ridge_height_m"] < record["sliding"]["skin_before"]["ridge_height_m"]
    assert record["stimuli"][0]["texture"] == {"number": 902, "name": "3 mm grating"}
    assert "Sliding trials" in (tmp_path / "report.md").read_text()


def test_each_slide_reads_the_motor_current_through_its_own_noise():
    """Two identical slides of one scene (the rig's motor current of each, the real StageMotor, watched): the
    current-sense noise each slide's traction is read through is its own stream of the scene's seed — unit variance
    around the load's line, uncorrelated between the slides (|r| < 0.3 over their ~155 readings at the force log's
    100 Hz, ~3.7 σ; one shared stream would give r = 1) and the same again from the same seed."""
    import numpy as np

    from bench.running.runner import run_scene
    from bench.textures.stage import StageMotor

    real = StageMotor.current_A

    def run() -> list[np.ndarray]:
        noises = []

        def watched(motor, tangential_N, rng):
            current = real(motor, tangential_N, rng)
            noises.append((current - motor.idle_A - motor.A_per_N * np.abs(tangential_N)) / motor.noise_A)
            return current

        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(StageMotor, "current_A", watched)
            rec = run_scene(_scene(_slide(start_s=[0.2, 1.9], distance_mm=10), skin={"wear": False}, duration=3.5),
                            progress=False)
        assert rec.status == "ok" and len(rec.slides) == 2, rec.error
        return noises

    first, again = run(), run()
    n = min(map(len, first))
    assert n > 100 and all(np.std(x) == pytest.approx(1, abs=0.25) for x in first)
    assert abs(np.corrcoef(first[0][:n], first[1][:n])[0, 1]) < 0.3
    assert all(np.array_equal(a, b) for a, b in zip(first, again))
