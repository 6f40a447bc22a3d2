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
    (_slide(velocity_mm_per_s="fast"), ["stimulus[0].velocity_mm_per_s", '"fast"']),
    (_slide(distance_mm=0.5, velocity_mm_per_s=100), ["stimulus[0].distance_mm", "acceleration"]),
    (_slide(start_s=19.0), ["ends at", "after the end of the scene"]),
    (_slide(grip=True), ['unknown field "grip"']),
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


def test_a_ridge_height_on_a_skin_without_fingerprints_is_a_contradiction():
    """It was taken silently: the ridges had no effect, while the report and record.json gave the skin that height."""
    text = _problems(_slide(), skin={"fingerprints": False, "ridge_height_um": 100})
    assert "skin.ridge_height_um = 100 with skin.fingerprints = false" in text
    assert not _scene(_slide(), skin={"fingerprints": False}).skin_before["fingerprints"]
    assert _scene(_slide(), skin={"fingerprints": True, "ridge_height_um": 100}).skin_before["ridge_height_m"] > 0


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


@pytest.fixture(scope="module")
def two_slides():
    """Two 20 mm slides at 20 mm/s, 1 N, on a skin whose ridges start at 150 µm (``[skin] ridge_height_um``) and
    wear; run with its record."""
    from bench.reporting.report import build_record
    from bench.running.runner import run_scene

    sc = _scene(_slide(start_s=[0.3, 2.6], force_N=1.0), skin={"ridge_height_um": 150}, duration=5.0)
    rec = run_scene(sc, progress=False)
    assert rec.status == "ok" and len(rec.slides) == 2, rec.error
    return sc, rec, build_record(rec, [])


def test_each_trials_ridge_height_is_its_own_skins_as_it_wears(two_slides):
    """One skin that wears from trial to trial (the README): each trial row's ridge height is the skin it met —
    150 µm for the first (the [skin] table's, within 1 %), less for the second (the first trial wore it)."""
    _, rec, _ = two_slides
    first, second = (r["ridge_height_m"] for r in rec.slides)
    assert first == pytest.approx(150e-6, rel=0.01)
    assert second < first


def test_the_reports_skin_line_gives_the_worn_skin_after_the_trials(two_slides):
    """report.md's "Skin before … after …" line: after = the skin the two trials left (2 trials on it, 2 × 20 mm =
    0.04 m slid, ridges no higher than before); before = the fresh one. Distances to the printed 0.01 m."""
    import re

    from bench.reporting.report import markdown_report

    _, _, record = two_slides
    text = markdown_report(record)
    m = re.search(r"Skin before: serial (\d+), ridge height ([\d.]+) µm; after: serial (\d+), ridge height ([\d.]+) "
                  r"µm \((\d+) trials? on it, ([\d.]+) m slid\)", text)
    assert m, text
    assert float(m[2]) == pytest.approx(150.0, abs=0.05) and float(m[4]) <= float(m[2])  # (0.1 µm printed)
    assert int(m[5]) == 2 and float(m[6]) == pytest.approx(0.04, abs=0.005)


def test_the_sliding_table_prints_the_true_normal_force_and_the_ridge_height_in_um(two_slides):
    """report.md's sliding table under its header: "true normal force (N)" is the force measured on the skin
    while sliding (the record's true_normal_N, not the commanded 1 N echoed; to the printed 1e-3 N), and
    "ridge height (µm)" the skin's in micrometres (≈ 150 µm, the [skin] table's, within 1 %); "velocity (cm/s)" the
    fixture's 20 mm/s as 2 cm/s (a mutation hunt: the speed printed ten times too small passed)."""
    from bench.reporting.report import markdown_report

    _, _, record = two_slides
    lines = markdown_report(record).splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("| trial |"))
    head = [c.strip() for c in lines[i].strip("|").split("|")]
    for trial, line in zip(record["sliding"]["trials"], lines[i + 2:i + 4]):
        row = dict(zip(head, (c.strip() for c in line.strip("|").split("|"))))
        assert float(row["true normal force (N)"]) == pytest.approx(trial["true_normal_N"], abs=6e-4)
        assert row["true normal force (N)"] != f"{trial['force_N']:.3f}"  # measured, not the command
        assert float(row["ridge height (µm)"]) == pytest.approx(150.0, rel=0.01)
        assert float(row["velocity (cm/s)"]) == pytest.approx(2.0, rel=1e-9)


def test_the_sliding_plots_give_slip_in_cm_per_s_and_ridges_in_um(two_slides, tmp_path, monkeypatch):
    """forces.png's slip panel is in cm/s: while the stage runs at 20 mm/s (between the slides' accelerations) the
    finger slips at about 2 cm/s (median within 25 %); properties.png's ridge panel is in µm (≈ 150, within 1 %)."""
    import contextlib

    import numpy as np

    from bench.reporting import plots
    from bench.reporting.report import baselines

    kept, real = {}, plots.figure_file

    @contextlib.contextmanager
    def keeping(path, *args, **kw):
        with real(path, *args, **kw) as (fig, axes):
            kept[path.name] = axes
            yield fig, axes

    monkeypatch.setattr(plots, "figure_file", keeping)
    sc, rec, _ = two_slides
    drawn = dict(plots.scene_plots(rec, baselines(rec)))
    for name in ("forces.png", "properties.png"):
        drawn[name](tmp_path / name)
    slip = kept["forces.png"][1].get_lines()[0]
    t, v = np.asarray(slip.get_xdata()), np.asarray(slip.get_ydata())
    slides = [s for s in sc.stimuli if isinstance(s, Slide)]
    steady = np.zeros(t.size, bool)
    for s in slides:
        steady |= (t > s.slide_start_s + s.accel_s + 0.1) & (t < s.slide_end_s - s.accel_s)
    assert kept["forces.png"][1].get_ylabel() == "slip velocity (cm/s)"
    assert np.median(v[steady]) == pytest.approx(2.0, rel=0.25)
    ridge = kept["properties.png"][3].get_lines()[0].get_ydata()
    assert list(ridge) == pytest.approx([150.0, 150.0], rel=0.01)


def test_a_slide_the_run_stopped_in_has_no_row():
    """A run stopped at 2 s (its second chunk boundary), inside a slide that slides from 1.1 s to 2.15 s: the slide
    has no row (a row per slide the run reached, SlideRecorder.finish; half a slide's roughness and fineness would
    pass for a whole trial's), status "interrupted"."""
    from bench.running.runner import run_scene

    sc = _scene(_slide(start_s=0.3), duration=3.0)
    s = next(x for x in sc.stimuli if isinstance(x, Slide))
    assert s.slide_start_s < 2.0 < s.slide_end_s
    asked = []
    rec = run_scene(sc, progress=False, should_stop=lambda: bool(asked.append(1)) or len(asked) >= 2)
    assert rec.status == "interrupted" and rec.error is None and rec.simulated_s == pytest.approx(2.0, abs=1e-3)
    assert rec.slides == []


def test_a_slide_whose_ramps_meet_records_finite_true_forces():
    """distance = velocity × accel_s (allowed: the ramps meet, no cruise): the trial's true normal and mean
    tangential force are means over the properties' measurement window, finite (the cruise's empty mean had gone
    into record.json as NaN)."""
    import json
    import math

    from bench.reporting.report import _json_default, build_record
    from bench.running.runner import run_scene

    sc = _scene(_slide(start_s=0.1, force_N=1.0, velocity_mm_per_s=10, distance_mm=1, accel_s=0.1, hold_s=0.5,
                       texture="T30"), duration=1.4)
    rec = run_scene(sc, progress=False)
    assert rec.status == "ok", rec.error
    (row,) = rec.slides
    assert math.isfinite(row["true_normal_N"]) and row["true_normal_N"] == pytest.approx(1.0, rel=0.05)
    assert math.isfinite(row["mean_tangential_N"]) and row["mean_tangential_N"] > 0
    json.dumps(build_record(rec, []), allow_nan=False, default=_json_default)  # strict JSON: no NaN anywhere


def test_a_property_undefined_for_a_trials_codes_is_null_and_the_run_stands(tmp_path):
    """Every noise source off, a 0.01 N slide at 0.1 mm/s on polished aluminum with a smooth skin: PAC reads one
    constant code over the measurement window, so the fineness (a spectral centroid) is undefined. That trial's
    fineness is null with the reason, its traction and roughness are numbers, and the run ends "ok" (it had
    failed after simulating the whole scene, every trial's row lost)."""
    import json

    from bench.cli import main as cli

    scene = tmp_path / "quiet.toml"
    scene.write_text('[scene]\nname = "quiet"\nduration_s = 4.0\n[host]\nsequence = ["PAC", "PDC"]\n'
                     '[noise]\njohnson = false\namplifier = false\nmains_hum = false\nadc = false\n'
                     'spi_coupling = false\nthermistor = false\n[skin]\nfingerprints = false\n'
                     '[[stimulus]]\nkind = "slide"\nstart_s = 0.1\ntexture = "T46"\nforce_N = 0.01\n'
                     'velocity_mm_per_s = 0.1\ndistance_mm = 0.3\nhold_s = 0.11\n')
    out = tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet", "--no-plots"]) == 0
    record = json.loads((out / "record.json").read_text())
    assert record["status"] == "ok"
    (row,) = record["sliding"]["trials"]
    assert row["fineness"] is None and "constant" in row["undefined"]["fineness"]
    assert isinstance(row["traction"], float) and isinstance(row["roughness"], float)
    assert "| — |" in (out / "report.md").read_text()


def test_scene_values_in_mm_and_um_become_the_nearest_si_value():
    """A scene's millimetres and micrometres are converted by dividing by the exact 1e3 and 1e6, so 100 µm is the
    double nearest 1e-4 m (as record.json then shows it), not 100 × 1e-6 = 9.999999999999999e-05."""
    sc = _scene(_slide(velocity_mm_per_s=9, distance_mm=13, start_position_mm=9), skin={"ridge_height_um": 100})
    assert repr(sc.skin_before["ridge_height_m"]) == "0.0001"  # (100 × 1e-6 = 9.999999999999999e-05)
    (slide,) = sc.stimuli
    assert (repr(slide.velocity_m_per_s), repr(slide.distance_m), repr(slide.start_position_m)) == \
        ("0.009", "0.013", "0.009")  # (9 × 1e-3 = 0.009000000000000001, 13 × 1e-3 = 0.013000000000000001)
