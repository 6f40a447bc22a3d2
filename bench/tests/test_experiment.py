"""The texture experiment end to end (reduced, same code path as fishel2012.toml): stages, caching by content
hash, outputs, and the experiment file's validation."""

import json

import numpy as np
import pytest

from bench.campaigns.engine import ClusterSpec
from bench.cli import main as cli
from bench.experiments import experiment as E
from bench.paths import FIXTURES
from bench.reporting.trials_file import read_trials

pytestmark = pytest.mark.unit
QUICK = FIXTURES / "experiments" / "quick.toml"


def test_shipped_experiment_files_validate():
    full = E.load_experiment(FIXTURES / "experiments" / "fishel2012.toml")
    assert full.pilot_trials == 6 and full.training_trials == 5 and full.pair_simulations == 1000
    assert full.identification_simulations == 8000 and full.training_textures is None  # all 117
    assert len(full.pilot_textures) == 10
    assert full.pair_choice == "similar-description" and full.pairs is None  # D's kind of pairs (pairs.py)
    # README: "thresholds 99.9 % for pairs and 99 % for 117-way, at most 10 movements"; 8 pairs, 5 trials each
    assert (full.pair_threshold, full.identification_threshold, full.max_moves) == (0.999, 0.99, 10)
    assert (full.n_pairs, full.validation_trials, full.exclude_high_power) == (8, 5, True)
    every = E.load_experiment(FIXTURES / "experiments" / "fishel2012_all.toml")
    assert every.identify_all_textures and vars(every) | {"identify_all_textures": False, "name": full.name,
                                                          "source": full.source,
                                                          "identification_simulations": 8000} == vars(full)
    assert every.identification_simulations == 117 * 500  # a total: 500 per texture, as its published figures ran


@pytest.mark.parametrize("data, words", [
    ({"pilot": {"textures": [999]}}, ["pilot.textures", "999"]),
    ({"pilot": {"trials": 6}}, ["[experiment] table with a name is missing"]),
    ({"pilot": {"trials": 1}}, ["pilot.trials = 1"]),
    ({"exploration": {"strategies": ["psychic"]}}, ["exploration.strategies"]),
    ({"exploration": {"pair_threshold": 1.5}}, ["exploration.pair_threshold = 1.5"]),
    ({"trainig": {}}, ["unknown table [trainig]"]),
    ({"training": {"trails": 5}}, ['training: unknown field "trails"']),
    ({"validation": {"pairs": [[2, 3, 4]]}}, ["validation.pairs"]),
    ({"pilot": {"movements": [0, 99, 1]}}, ["pilot.movements[1] = 99: must be a grid id, a whole number 0 to 35"]),
    ({"training": {"replace_at": 0.0}}, ["training.replace_at = 0.0", "0.01 to 1.0"]),
    ({"validation": {"pair_choice": "nearest"}}, ['validation.pair_choice = "nearest"', '"similar-description"']),
    ({"validation": {"pairs": [[2, 2]]}}, ["validation.pairs", "[[2, 2]]", "with itself"]),
    ({"validation": {"pairs": [[2, 3], [3, 4]]}}, ["validation.pairs", "[3]", "disjoint"]),
    ({"training": {"textures": [2, 3, 4, 5]}, "validation": {"pairs": [[2, 3], [4, 9]]}},
     ["validation.pairs", "[9]", "not among the training textures"]),
    # found by a hostile pass: each was accepted, or refused only after the pilot and training had run
    ({"experiment": {"name": "../escaped"}}, ['experiment.name = "../escaped"', "not a path"]),
    ({"experiment": {"name": "."}}, ['experiment.name = "."']),
    ({"experiment": {"name": "x" * 300}}, ["experiment.name", "1 to 100"]),
    ({"pilot": {"textures": [30]}}, ["pilot.textures = [30]", "at least 2"]),
    ({"pilot": {"movements": [True, False, 5]}}, ["pilot.movements[0] = true", "pilot.movements[1] = false"]),
    ({"validation": {"pairs": [[True, 2]]}}, ["validation.pairs"]),
    ({"exploration": {"pair_simulations": 1}}, ["exploration.pair_simulations = 1", "2 to"]),
    ({"exploration": {"pair_simulations": 999}}, ["exploration.pair_simulations = 999", "even"]),
    ({"training": {"textures": [1, 2, 3, 4]}, "validation": {"n_pairs": 8}},
     ["validation.n_pairs = 8", "only 1 disjoint pairs", "similar-description"]),
    ({"training": {"textures": [1, 2, 3, 4]}, "validation": {"n_pairs": 3, "pair_choice": "most-confused"}},
     ["validation.n_pairs = 3", "most-confused"]),
    # a research group's own selection: "only 0 disjoint pairs" said neither why nor what to do
    ({"training": {"textures": [10, 30, 43, 46, 84, 100]}, "validation": {"n_pairs": 1}},
     ["validation.n_pairs = 1", "only 0 disjoint pairs", "within a group here: T43/T46: different thermal materials)",
      "name them with pairs = [[a, b], ...]"]),
    # a second hostile pass: a traceback, and a pilot whose every movement is excluded found only after it ran
    ({"exploration": {"strategies": [["bayesian"]]}}, ['exploration.strategies = [["bayesian"]]']),
    ({"exploration": {"strategies": [{"a": 1}]}}, ["exploration.strategies"]),
    ({"pilot": {"movements": [35, 34, 29]}}, ["pilot.movements = [35, 34, 29]", "every one is a high-power movement",
                                             "exclude_high_power = false"]),
    ({"validation": {"pairs": [[2, 3]], "n_pairs": 4}}, ["validation.pairs is given, with validation.n_pairs"]),
    ({"validation": {"pairs": [[2, 3]], "pair_choice": "most-confused"}}, ["with validation.pair_choice"]),
])
def test_bad_experiment_files_name_field_and_value(data, words):
    with pytest.raises(E.ExperimentError) as e:
        E.parse_experiment(data, "x.toml")
    for w in words:
        assert w in str(e.value)


def test_pairs_listed_in_the_file_are_the_pairs_counted():
    """With pairs = [[a, b], [c, d]], summary.json's spec said n_pairs = 8 (the default, unused) beside two pairs."""
    spec = E.parse_experiment({"experiment": {"name": "x"}, "training": {"textures": [2, 3, 4, 5]},
                               "validation": {"pairs": [[2, 3], [4, 5]]}}, "x.toml")
    assert spec.pairs == [(2, 3), (4, 5)] and spec.n_pairs == 2


def test_all_pilot_textures_means_the_117_and_whole_numbers_serve_as_floats():
    spec = E.parse_experiment({"experiment": {"name": "x"}, "pilot": {"textures": "all"},
                               "sensor": {"noise_scale": 2}, "training": {"replace_at": 1}}, "x.toml")
    assert spec.pilot_textures == list(range(1, 118))
    assert spec.noise_scale == 2.0 and spec.replace_at == 1.0


def test_an_ablation_changes_the_experiment_as_given_and_says_so():
    """'double-noise' doubles the file's own noise scale (a file at 2 runs at 4, not again at 2), and a variant
    that changes nothing is labelled the same as the baseline."""
    spec = E.parse_experiment({"experiment": {"name": "x"}, "sensor": {"noise_scale": 2.0},
                               "training": {"trials": 2}}, "x.toml")
    noisy, what = E.ablated(spec, "double-noise")
    assert noisy.noise_scale == 4.0 and "noise_scale 2.0 → 4.0" in what
    fewer, what = E.ablated(spec, "fewer-trials")
    assert fewer == spec and "(the same as the baseline)" in what
    smooth, what = E.ablated(spec, "smooth-skin")
    assert not smooth.fingerprints and "same" not in what


def test_quick_experiment_runs_end_to_end_and_caches_its_stages(tmp_path, monkeypatch):
    spec = E.load_experiment(QUICK)
    result = E.run_experiment(spec, cache_dir=tmp_path / "cache", cluster=ClusterSpec(workers=2), progress=False,
                              log=lambda m: None)
    assert len(result.pilot_rows) == 4 * 6 * 2
    assert len(result.pairs) == 2 and all(a != b for a, b in result.pairs)
    s = E.summary(result)
    for key in ("pairs/bayesian", "pairs/cycle", "pairs/random", "identification/bayesian"):
        assert 0.0 <= s[key]["accuracy"] <= 1.0 and s[key]["simulations"] > 0
    # what ran is what the file and D ask for (a mutation hunt found each of these unguarded)
    assert (spec.pair_threshold, spec.identification_threshold) == (0.999, 0.99)  # D: 99.9 % pairs, 99 % 117-way
    validated = len({n for p in result.pairs for n in p})
    for strategy in spec.strategies:
        pairs, ident = result.pair_results[strategy], result.identification_results[strategy]
        assert {(r.strategy, r.threshold) for r in pairs} == {(strategy, 0.999)}
        assert {(r.strategy, r.threshold) for r in ident} == {(strategy, 0.99)}
        assert sum(len(r) for r in pairs) == len(result.pairs) * spec.pair_simulations  # half with each as truth
        assert sum(len(r) for r in ident) == spec.identification_simulations and len(ident) == validated
    for r in result.pair_results["cycle"] + result.identification_results["cycle"]:  # the pilot's three picks
        for step in range(min(3, int(r.n_moves.min()))):
            assert set(r.movement[:, step]) == {result.best_movements[step]} and set(r.prop[:, step]) == {step}
    # the pilot's U table: rows of movements the pilot did not run stay NaN
    not_run = sorted(set(range(36)) - set(spec.pilot_movements))
    assert np.isnan(result.pilot_uncertainty[not_run]).all()
    assert np.isfinite(result.pilot_uncertainty[[m for m in spec.pilot_movements
                                                 if m not in E.excluded_movements(spec, spec.pilot_movements)]]).all()
    # validation goes on with the training session's skin (D: one session), not a fresh one
    last, first = result.training_rows[-1], result.validation_rows[0]
    assert first["skin_serial"] > last["skin_serial"] or (
        first["skin_serial"] == last["skin_serial"] and first["ridge_height_m"] < last["ridge_height_m"])
    # a second run with other exploration settings reads every stage from the cache: no trial runs
    import bench.experiments.experiment as module

    monkeypatch.setattr(module, "sweep", lambda *a, **k: pytest.fail("a cached stage ran trials again"))
    again = E.run_experiment(E.ExperimentSpec(**{**vars(spec), "max_moves": 5}), cache_dir=tmp_path / "cache",
                             cluster=ClusterSpec(workers=1), progress=False, log=lambda m: None)
    assert again.training_rows == result.training_rows
    from bench.reporting.experiment_report import write_outputs

    files = write_outputs(result, tmp_path / "out")
    readme_outputs = ("report.md", "summary.json", "accuracy.csv", "accuracy_per_texture.csv", "confusion.csv",
                      "trials.csv", "trials.json", "pilot_uncertainty.csv", "properties_at_optimal_movements.png",
                      "probability_evolution.png")  # README, the texture experiment's outputs: every one, no other
    assert sorted(files) == sorted(readme_outputs)
    for name in readme_outputs:
        assert (tmp_path / "out" / name).stat().st_size > 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert set(summary["best_movements"]) == {"traction", "roughness", "fineness"}
    report = (tmp_path / "out" / "report.md").read_text()
    assert "99.6" in report  # D's number stands beside ours
    identified = len({int(r.true_texture) for r in result.identification_results["bayesian"]})
    assert f"of {identified} identified textures" in report
    _check_tables_against_the_result(tmp_path / "out", result, summary)
    # beyond D: every training texture identified; the report counts them all, not just the pairs' textures
    monkeypatch.undo()  # this one needs validation trials for every texture
    every = E.run_experiment(E.ExperimentSpec(**{**vars(spec), "identify_all_textures": True}),
                             cache_dir=tmp_path / "cache", cluster=ClusterSpec(workers=1), progress=False,
                             log=lambda m: None)
    write_outputs(every, tmp_path / "every")
    assert f"of {len(spec.training_textures)} identified textures" in (tmp_path / "every" / "report.md").read_text()
    # identification_simulations is the total over the textures identified, all of them here (not only the pairs')
    for strategy in spec.strategies:
        assert sum(len(r) for r in every.identification_results[strategy]) == spec.identification_simulations
        assert len(every.identification_results[strategy]) == len(spec.training_textures)


def test_explore_command_reports_bad_input_without_traceback(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[pilot]\ntextures = [999]\n")
    assert cli.main(["explore", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "pilot.textures" in err and "Traceback" not in err


def test_texture_sweep_writes_its_table_and_plot(tmp_path, capsys):
    out = tmp_path / "sweep"
    assert cli.main(["texture-sweep", "--textures", "902,T30", "--movements", "0,35", "--trials", "1",
                     "--workers", "1", "--out", str(out), "--quiet"]) == 0
    rows = _csv(out / "trials.csv")
    assert {(r["texture"], r["movement_id"]) for r in rows} == {("902", "0"), ("902", "35"), ("30", "0"), ("30", "35")}
    assert (out / "properties.png").stat().st_size > 0 and (out / "wear.csv").exists()
    wear = _csv(out / "wear.csv")
    assert float(wear[1]["ridge_lost_m"]) > float(wear[0]["ridge_lost_m"])  # 2 N @ 10 cm/s wears more
    # foam at 2 N, 10 cm/s drives PAC to the ADC's rails: the row counts the samples, the summary says so
    rails = {(r["texture"], r["movement_id"]): int(r["pac_at_rails"]) for r in rows}
    assert rails[("30", "35")] > 0 and rails[("902", "0")] == 0
    # no SPI fault declared: none, and no sample rejected, in every row
    assert {(r["spi_faults"], r["rejected_samples"]) for r in rows} == {("", "0")}
    clipped = sum(1 for v in rails.values() if v)
    assert f"note: {clipped} of 4 trials had PAC at the ADC's rails" in capsys.readouterr().out


@pytest.mark.parametrize("argv, flag", [
    (["texture-sweep", "--textures", "902", "--trials", "0"], "--trials"),
    (["texture-sweep", "--textures", "902", "--movements", "0,99"], "--movements"),
    (["texture-sweep", "--textures", "no such thing"], "no such thing"),
    (["texture-sweep", "--textures", "902", "--workers", "0"], "--workers"),
    (["explore", "fixtures/experiments/quick.toml", "--workers", "0"], "--workers"),
])
def test_sweep_and_explore_name_the_bad_flag(argv, flag, capsys):
    try:  # a bad value is argparse's usage error, or the command's own
        status = cli.main(argv)
    except SystemExit as e:
        status = e.code
    assert status == 2
    err = capsys.readouterr().err
    assert flag in err and "Traceback" not in err


def test_row_tables_with_different_columns_are_written_whole(tmp_path):
    from bench.reporting.experiment_report import write_rows_csv

    write_rows_csv(tmp_path / "t.csv", [{"texture": 1, "pairs": 0.5}, {"texture": 2, "identification": 0.9}])
    rows = _csv(tmp_path / "t.csv")
    assert rows == [{"texture": "1", "pairs": "0.5", "identification": ""},
                    {"texture": "2", "pairs": "", "identification": "0.9"}]


def test_the_double_noise_ablation_doubles_every_noise_source():
    """The 'double-noise' ablation scales every noise source of the sensor ×2 in amplitude: every parameter named
    as a noise, RMS or hum amplitude, and the bridge's Johnson noise (R ×4); so every source line of the noise
    budget doubles (quantization, a property of the ADC, does not)."""
    import dataclasses

    from bench.experiments.trials import _params
    from emulator.noise_budget import budget
    from emulator.params import SensorParams

    p, q = SensorParams(), _params(2.0)
    noisy = [f.name for f in dataclasses.fields(SensorParams)
             if any(w in f.name for w in ("noise", "rms", "amplitude"))]
    assert len(noisy) >= 9
    for name in noisy:  # the current noise flows through the bridge: i·R, not i, doubles
        scale = 2 if name != "amp_current_noise_A_per_rtHz" else 0.5
        assert getattr(q, name) == pytest.approx(scale * getattr(p, name)), name
    assert q.bridge_resistance_ohm == pytest.approx(4 * p.bridge_resistance_ohm)
    for one, two in zip(budget(p), budget(q)):
        if "total" in one.source or "quantization" in one.source:
            continue
        assert two.pac_bits == pytest.approx(2 * one.pac_bits, rel=1e-9), one.source


def test_replace_at_sets_how_worn_a_skin_gets_before_it_is_replaced():
    """The skin policy of the experiment file reaches the session: by default a fresh skin at the first visible
    wear; a larger fraction, fewer and more worn skins."""
    from bench.experiments.trials import FIRST_VISIBLE_WEAR, TrialTask, schedule_skin

    tasks = [TrialTask(2, 2.0, 0.01, k, k) for k in range(600)]  # 2 N @ 1 cm/s: the hardest kept movement
    spec = E.parse_experiment({"experiment": {"name": "x"}, "training": {"replace_at": 0.1}}, "x.toml")
    assert spec.replace_at == 0.1 and E.ExperimentSpec().replace_at == FIRST_VISIBLE_WEAR
    for fraction in (FIRST_VISIBLE_WEAR, spec.replace_at):
        scheduled, _ = schedule_skin(tasks, replace_at=fraction)
        lowest = min(t.ridge_height_m for t in scheduled)
        assert lowest >= (1 - fraction) * scheduled[0].ridge_height_m * 0.99
        assert lowest < (1 - fraction) * scheduled[0].ridge_height_m * 1.01  # it does get that worn
    assert len({t.skin_serial for t in schedule_skin(tasks)[0]}) > \
        len({t.skin_serial for t in schedule_skin(tasks, replace_at=0.1)[0]}) > 1


def test_the_wear_law_meets_d_wear_observations_with_its_calibrated_knobs():
    """Calibrated (k: training, β: pilot): D's training (117 × 3 × 5 trials of power level 6) uses 3 skins replaced
    at the first visible wear; after a pilot's worth (60 trials) no kept movement (level ≤ 7) shows visible wear and
    every level-8 one does; the shipped knobs are the centred solution, rounded, and β lies inside its allowed range.
    Without the power factor (β = 0) the pilot condition fails."""
    from dataclasses import replace

    from bench.experiments import trials as T
    from emulator.skin import Skin

    cal = T.wear_calibration()
    assert cal["training_trials"] == 1755 and cal["training_skins"] == 3
    assert cal["pilot_kept_worst"] < 1.0 <= cal["pilot_level8_mildest"]
    assert cal["solved"]["wear_coefficient"] == pytest.approx(Skin().wear_coefficient, rel=0.02)
    assert cal["solved"]["wear_power_exponent"] == pytest.approx(Skin().wear_power_exponent, rel=0.02)
    low, high = cal["beta_range"]
    assert low < Skin().wear_power_exponent < high
    flat = [r["worn_fraction"] for r in T.wear_per_movement([T.movement_grid()[i] for i in (11, 35)])]
    assert flat[0] >= T.FIRST_VISIBLE_WEAR and flat[1] == 1.0  # 0.32 N @ 10 cm/s (level 8) and 2 N @ 10 cm/s
    # β = 0 with k re-set by the training count: the mildest level-8 movement stays far from visible wear
    skin = Skin(wear_power_exponent=0.0)
    area = lambda N: T.contact_patch_area_m2(N, 2.5e-3)  # noqa: E731
    unit = sum(skin.height_lost(t.force_N, 0.05, area(t.force_N), t.velocity_m_per_s) for t in T.d_training_tasks())
    k = 2.5 * T.FIRST_VISIBLE_WEAR * skin.ridge_height_new_m / unit * skin.wear_coefficient
    flat_law = replace(skin, wear_coefficient=k)
    assert 60 * flat_law.height_lost(0.317, 0.05, area(0.317), 0.1) < 0.2 * T.FIRST_VISIBLE_WEAR * 2e-4


# ------------------------------------------------------------------------- the validation pairs (D: "similar")

#: the eight pairs the shipped rule takes from the 117 (a change to the rule or the library shows here first)
SHIPPED_PAIRS = [(85, 86), (4, 5), (59, 64), (101, 114), (74, 75), (116, 117), (48, 50), (14, 15)]


def test_the_description_scales_are_the_117_textures_spreads_whatever_test_surfaces_the_library_holds():
    """pairs.feature_scales: each feature's spread over the library's 117 textures (D's set), so the test surfaces
    a library may add (numbers 900–999) move no scale and no pair; here ten extreme ones (a 3 mm RMS, 50 mm
    correlation, µ 3 surface) that would widen every spread.  (A mutation hunt: scales over every texture of the
    library passed, the shipped library's two test surfaces moving them by < 1 %.)"""
    import dataclasses

    from bench.experiments import pairs as P
    from bench.textures.library import load_library

    lib = {n: t for n, t in load_library().items() if n <= 117}
    odd = dataclasses.replace(lib[1], group="test surfaces", rms_height_m=3e-3, correlation_length_m=0.05,
                              mu_static=3.0, mu_kinetic=3.0)
    with_tests = {**lib, **{900 + k: dataclasses.replace(odd, number=900 + k, seed=10_000 + k) for k in range(10)}}
    np.testing.assert_array_equal(P.feature_scales(with_tests), P.feature_scales(lib))
    assert P.similar_description_pairs(range(1, 118), 8, with_tests) == P.similar_description_pairs(range(1, 118), 8, lib)


def test_similar_pairs_meet_their_definition_and_are_taken_nearest_first():
    from bench.experiments import pairs as P
    from bench.textures.library import load_library

    lib = load_library()
    chosen = P.similar_description_pairs(range(1, 118), 8, lib)
    assert chosen == SHIPPED_PAIRS
    scales = P.feature_scales(lib)
    dist = [P.description_distance(lib[a], lib[b], scales) for a, b in chosen]
    assert dist == sorted(dist)  # greedy: nearest first
    used, groups = set(), set()
    for (a, b), d in zip(chosen, dist):
        ta, tb = lib[a], lib[b]
        assert ta.group == tb.group and ta.material == tb.material and bool(ta.periodic) == bool(tb.periodic)
        e = sorted([ta.modulus_Pa, tb.modulus_Pa])
        assert e[0] >= P.RIGID_MODULUS_PA or e[1] <= P.COMPLIANCE_RATIO * e[0]
        assert not {a, b} & used and ta.group not in groups  # disjoint, one pair per group
        # no nearer admissible pair was free when this one was taken
        for i in range(1, 118):
            for j in range(i + 1, 118):
                if {i, j} & used or lib[i].group in groups or P.admissible(lib[i], lib[j]) is not None:
                    continue
                assert P.description_distance(lib[i], lib[j], scales) >= d
        used |= {a, b}
        groups.add(ta.group)


@pytest.mark.parametrize("a, b, reason", [
    (14, 15, None),                                        # 220- and 400-grit sandpaper: both rigid
    (116, 117, None),                                      # rabbit and faux fur: 2 and 3 kPa, a factor 1.5
    (1, 2, "periodic relief"),                             # copy paper / linen paper (ridged)
    (47, 54, "thermal materials"),                         # rubber / silicone
    (67, 70, "compliance"),                                # smooth leather 15 MPa / suede 2 MPa
    (4, 16, "groups"),                                     # newsprint / cork
])
def test_similar_pair_admissibility_names_what_differs(a, b, reason):
    from bench.experiments.pairs import admissible
    from bench.textures.library import load_library

    lib = load_library()
    got = admissible(lib[a], lib[b])
    assert (got is None) if reason is None else (reason in got)


def test_too_few_similar_pairs_is_an_experiment_error_naming_n_pairs():
    model = E.ex.TextureModel(textures=np.array([4, 5, 16]), movements=np.arange(3), mean=np.zeros((3, 3, 3)),
                              sigma=np.ones((3, 3, 3)), n_trials=np.full((3, 3, 3), 5))
    assert E._pick_pairs(model, np.arange(3), 1, "similar-description", 0) == [(4, 5)]
    with pytest.raises(E.ExperimentError, match="validation.n_pairs = 2"):
        E._pick_pairs(model, np.arange(3), 2, "similar-description", 0, "x.toml")


@pytest.mark.parametrize("choice", ["random-within-group", "most-confused"])
def test_too_few_pairs_by_confusion_or_chance_is_an_experiment_error_too(choice):
    model = E.ex.TextureModel(textures=np.array([4, 5, 16]), movements=np.arange(3), mean=np.zeros((3, 3, 3)),
                              sigma=np.ones((3, 3, 3)), n_trials=np.full((3, 3, 3), 5))
    assert E._pick_pairs(model, np.arange(3), 1, choice, 0) == [(4, 5)]  # 16 is of another group
    with pytest.raises(E.ExperimentError, match=f"validation.n_pairs = 2.*only 1.*{choice}"):
        E._pick_pairs(model, np.arange(3), 2, choice, 0, "x.toml")


def test_pair_separation_is_the_largest_mean_difference_over_the_pooled_sigma():
    from bench.experiments.pairs import pair_separation_sigma

    mean = np.zeros((2, 3, 3))
    mean[1, 2, 1] = 6.0  # roughness differs by 6 at movement 2, by 1 at movement 0
    mean[1, 0, 1] = -1.0
    sigma = np.ones((2, 3, 3))
    sigma[1] = 7.0 ** 0.5  # pooled σ √((1 + 7)/2) = 2
    model = E.ex.TextureModel(textures=np.array([4, 5]), movements=np.arange(3), mean=mean, sigma=sigma,
                              n_trials=np.full((2, 3, 3), 5))
    assert pair_separation_sigma(model, [(4, 5)]) == [[0.0, 3.0, 0.0]]


def test_the_stepper_noise_ablation_is_the_sensors_own_resting_pac_noise_in_pascals():
    """Derived (design.py's stated choice): 0.52 Pa RMS is PAC's 1.4-bit resting noise (SENSOR.md) at the PAC
    path's Pa per bit (PDC's ÷ the stage-2 gain), within 2 %."""
    from emulator.params import SensorParams
    from emulator.units import derived

    p = SensorParams()
    pac_pa_per_bit = derived(p)["PDC_Pa_per_bit"] / p.stage2_gain
    spec = E.parse_experiment({"experiment": {"name": "x"}}, "x.toml")
    noisy, _ = E.ablated(spec, "stepper-noise")
    assert noisy.stepper_noise_Pa == pytest.approx(1.4 * pac_pa_per_bit, rel=0.02)


def _csv(path):
    import csv

    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _check_tables_against_the_result(out, result, summary):
    """The written tables hold what the result holds, in the units their columns name (consistency: each was found
    wrong-but-unnoticed by a mutation: validation rows dropped, fractions under accuracy_%, a U column of another
    property, ridge loss in mm under µm, the replacement count one high, decisions outside the true set lost, and in
    report.md fractions printed as percent or the validation-spread columns swapped)."""
    assert len(_csv(out / "trials.csv")) == len(read_trials(out / "trials.json")["rows"]) == (
        len(result.pilot_rows) + len(result.training_rows) + len(result.validation_rows))
    s = E.summary(result)
    for row in _csv(out / "accuracy.csv"):
        assert float(row["accuracy_%"]) == pytest.approx(100 * s[f"{row['task']}/{row['strategy']}"]["accuracy"],
                                                         abs=1e-4)
    for row in _csv(out / "pilot_uncertainty.csv"):
        m = int(row["movement_id"])
        for k, prop in enumerate(("traction", "roughness", "fineness")):
            want = result.pilot_uncertainty[m, k]
            got = float(row[f"U_{prop}"]) if row[f"U_{prop}"] not in ("", "nan") else np.nan
            assert got == pytest.approx(want, rel=1e-9, nan_ok=True), (m, prop)
        assert float(row["ridge_lost_um_per_pilot_worth"]) == pytest.approx(result.wear[m]["ridge_lost_m"] * 1e6,
                                                                            rel=1e-9)
    assert summary["skin_replacements"] == max(h["skin"] for h in result.skin_history) - 1
    confusion = _csv(out / "confusion.csv")
    decided = {int(d) for r in result.identification_results["bayesian"] for d in r.decided}
    assert decided <= {int(k) for k in confusion[0] if k != "true"}
    per_truth = {}
    for r in result.identification_results["bayesian"]:
        per_truth[int(r.true_texture)] = per_truth.get(int(r.true_texture), 0) + len(r.decided)
    assert {int(row["true"]): sum(int(v) for k, v in row.items() if k != "true") for row in confusion
            if int(row["true"]) in per_truth} == per_truth
    # report.md's accuracy table is in percent (its "%" cells, to the printed 0.1 %), and its validation-spread
    # table's columns are under their headers (validation, then leave-one-out; to the printed 0.01)
    lines = (out / "report.md").read_text().splitlines()
    for line in lines[lines.index("| task | strategy | accuracy | median movements | dissertation |") + 2:]:
        if not line.startswith("|"):
            break
        task, strategy, accuracy = (c.strip() for c in line.strip("|").split("|")[:3])
        task = task.removesuffix(f" ({E.identified_among(result)}-way)")  # identification (N-way)
        assert float(accuracy.rstrip(" %")) == pytest.approx(100 * s[f"{task}/{strategy}"]["accuracy"], abs=0.051)
    if summary["spread_check"]:
        i = lines.index("| property | validation | leave-one-out | ratio |")
        for line, (prop, v) in zip(lines[i + 2:], summary["spread_check"].items()):
            cells = [c.strip() for c in line.strip("|").split("|")]
            assert cells[0] == prop
            assert [float(x) for x in cells[1:3]] == pytest.approx(
                [v["validation_median_abs_z"], v["leave_one_out_median_abs_z"]], abs=0.0051)


def test_an_empty_pairs_list_is_refused_before_any_trial_not_replaced_by_chosen_pairs():
    # `pairs = []` had passed validation and then meant "choose n_pairs = 8 pairs" (spec.pairs or _pick_pairs): the
    # experiment ran its pilot and training, then failed naming an n_pairs the file never gave, or silently
    # validated 8 pairs the file did not ask for
    text = '[experiment]\nname = "a"\n[validation]\npairs = []\n'
    import tomllib

    with pytest.raises(E.ExperimentError, match=r"validation.pairs = \[\]: a list of at least one"):
        E.parse_experiment(tomllib.loads(text), "x.toml")


def test_noise_scale_takes_zero_for_a_noise_free_sensor_and_refuses_what_the_sensor_cannot_express(tmp_path, capsys):
    """[sensor] noise_scale = 0 runs the trials with every noise source off (it divided by zero in every trial);
    a scale the sensor's parameter ranges cannot express (0.1: the bridge's Johnson noise scales through its
    resistance, ×k², below its 100 Ω floor) is refused by the file's validation, and a double-noise ablation
    past the range (10 → 20) before anything runs or any folder is made (it had failed in every trial)."""
    from bench.experiments.trials import TrialTask, noise_sources, run_trial_task
    from emulator.sensor import NoiseSources

    assert E.parse_experiment({"experiment": {"name": "x"}, "sensor": {"noise_scale": 0}}, "x.toml").noise_scale == 0
    with pytest.raises(E.ExperimentError, match=r"sensor.noise_scale = 0.1: .*bridge_resistance_ohm.*0 \(every noise"):
        E.parse_experiment({"experiment": {"name": "x"}, "sensor": {"noise_scale": 0.1}}, "x.toml")
    assert noise_sources(0.0) == NoiseSources.none() and noise_sources(0.5) == NoiseSources()
    row = run_trial_task(TrialTask(texture=30, force_N=0.5, velocity_m_per_s=0.025, trial=0, seed=3,
                                   fidelity="fast", noise_scale=0.0))
    assert all(np.isfinite(row[p]) for p in ("traction", "roughness", "fineness")) and "undefined" not in row
    loud = tmp_path / "loud.toml"
    loud.write_text(QUICK.read_text().replace("[exploration]", "[sensor]\nnoise_scale = 10.0\n\n[exploration]"))
    out = tmp_path / "out"
    assert cli.main(["explore", str(loud), "--ablation", "double-noise", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "--ablation double-noise" in err and "10.0 → 20.0" in err and "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize("changed", [{}, {"pac_path_noise_rms_bits": 5.0}, {"amp_current_noise_A_per_rtHz": 5e-10},
                                     {"bridge_resistance_ohm": 1e5}])
def test_the_noise_scale_hint_gives_scales_the_sensor_takes_and_names_what_limits_each_end(changed):
    """The hint named the bridge's resistance as the only limit, and its ends (0.141…14.1) were rounded outward: 0.141
    was refused.  For the nominal sensor and for sensors (valid parameter sets, as a unit might have) where another
    scaled parameter binds first — a noisier PAC path at the top, a larger amplifier current noise (×1/k) at the
    bottom — the printed ends are taken, and just past each one the parameter the sensor refuses is the one named."""
    import re

    from bench.experiments.trials import _params, noise_scale_problem
    from emulator.params import SensorParams

    base = SensorParams().replace(**changed)
    hint = noise_scale_problem(1e-6, base)
    m = re.search(r"give 0 \(every noise source off\) or ([0-9.e+-]+)…([0-9.e+-]+) \(", hint)
    assert m, hint
    lo, hi = float(m.group(1)), float(m.group(2))
    assert noise_scale_problem(lo, base) is None and noise_scale_problem(hi, base) is None, (lo, hi)
    for k, end in ((lo * 0.99, "below"), (hi * 1.01, "above")):
        with pytest.raises(ValueError) as e:
            _params(k, base)
        refused = re.match(r"sensor\.(\w+) = ", str(e.value)).group(1)
        assert re.search(rf"{end} [0-9.e+-]+, {refused} ", hint), (k, str(e.value), hint)


def test_an_experiment_files_noise_scale_hint_offers_only_scales_the_file_takes():
    """The file's [sensor] noise_scale is at most 10, below the sensor's own top (14.1): the hint's upper end is the
    file's, said so, and a scale just past it is refused by the file."""
    import re

    with pytest.raises(E.ExperimentError) as e:
        E.parse_experiment({"experiment": {"name": "x"}, "sensor": {"noise_scale": 0.1}}, "x.toml")
    m = re.search(r"or ([0-9.e+-]+)…([0-9.e+-]+) \(below .*; above [0-9.e+-]+, (.*?)[;)]", str(e.value))
    assert m and float(m.group(2)) == 10 and "experiment file" in m.group(3), str(e.value)
    for k, refused in ((float(m.group(1)), False), (10.0, False), (10.01, True)):
        data = {"experiment": {"name": "x"}, "sensor": {"noise_scale": k}}
        if refused:
            with pytest.raises(E.ExperimentError, match=r"sensor.noise_scale = 10.01: allowed range is 0.0 to 10.0"):
                E.parse_experiment(data, "x.toml")
        else:
            assert E.parse_experiment(data, "x.toml").noise_scale == k


def test_a_trial_with_an_undefined_property_is_kept_in_the_cache_and_refused_by_name_from_the_normals(tmp_path):
    """A trial row whose codes left a property undefined (null, with the reason) is a trial's result: the stage
    cache keeps it (a null without a reason is not one), and the trial table refuses it by texture, movement and
    trial rather than fit a normal without it or with a NaN."""
    task = E.TrialTask(texture=46, force_N=0.2, velocity_m_per_s=0.01, trial=1, seed=5, movement_id=0,
                       stage="pilot")
    from dataclasses import asdict
    row = dict(asdict(task), traction=0.1, roughness=-6.9, fineness=None, rejected_samples=0,
               undefined={"fineness": "PAC is constant over the measurement window"})
    path = tmp_path / "pilot.json"
    path.write_text(json.dumps([row]))
    assert E._cached_rows(path, [task]) == ([row], "")
    path.write_text(json.dumps([dict(row, undefined={})]))
    assert E._cached_rows(path, [task])[0] is None
    good = dict(row, fineness=5.5, trial=0)
    good.pop("undefined")
    with pytest.raises(E.ExperimentError, match=r"(?s)pilot trials.*1 of 2 trials.*T46 movement 0 trial 1: fineness "
                                                r"\(PAC is constant"):
        E.table_from_rows([good, row])
    assert len(E.table_from_rows([good])) == 3


@pytest.mark.parametrize("section, expected", [
    ({"pilot": {"trials": 2.5}}, ["pilot.trials = 2.5: must be a whole number (2 to 100)"]),
    ({"pilot": {"trials": 101}}, ["pilot.trials = 101: allowed range is 2 to 100"]),
    ({"training": {"replace_at": "half"}}, ['training.replace_at = "half": must be a number (0.01 to 1.0)']),
    ({"training": {"wear": 1}}, ["training.wear = 1: must be true or false"]),
    ({"experiment": {"fidelity": 3}}, ["experiment.fidelity = 3: one of fast, default, reference"]),
    ({"pilot": {"movements": [0, 1, "2", 3.0]}},
     ['pilot.movements[2] = "2": must be a grid id, a whole number 0 to 35',
      "pilot.movements[3] = 3.0: must be a grid id, a whole number 0 to 35"]),
    ({"pilot": {"textures": [1, 2, [3]]}}, ["pilot.textures[2] = [3]: must be a texture number (a whole number)"]),
    ({"pilot": {"movements": [0, 1, 2] + [-1] * 9}},
     [f"pilot.movements[{i}] = -1: must be a grid id, a whole number 0 to 35" for i in range(3, 8)]
     + ["pilot.movements: 4 more item(s) refused for the same reason"]),
])
def test_an_experiment_files_messages_name_kinds_in_words_and_each_bad_item_of_a_list(section, expected):
    """A field of the wrong kind is named in words as a scene's are ("a whole number", not Python's "int"), a value
    out of range says the range, and a bad item of a list is named by index and value (at most five of them, then
    how many more): "pilot.movements = [...]: a list of grid ids" left the user to find which."""
    data = {**section, "experiment": {"name": "x", **section.get("experiment", {})}}
    with pytest.raises(E.ExperimentError) as e:
        E.parse_experiment(data, "x.toml")
    assert e.value.problems == expected, e.value.problems


def test_the_double_noise_hint_gives_the_range_of_the_files_own_noise_scale():
    """The double-noise ablation doubles the file's noise_scale, so the file's value may be at most half the sensor's
    top (14.1 / 2 = 7.07): the hint gave the sensor's range (…14.1), which the file's value, doubled, leaves.  The
    hint's ends, typed into the file, run the ablation; just past its top end, the ablation is refused again."""
    import re

    def spec(k):
        return E.parse_experiment({"experiment": {"name": "x"}, "sensor": {"noise_scale": k}}, "x.toml")

    with pytest.raises(E.ExperimentError) as e:
        E.ablated(spec(8.0), "double-noise")
    m = re.search(r"give 0 \(every noise source off\) or ([0-9.e+-]+)…([0-9.e+-]+) \(values before ×2; ", str(e.value))
    assert m, str(e.value)
    lo, hi = float(m.group(1)), float(m.group(2))
    assert hi == 7.07 and "passes its maximum 1e+06 Ω once ×2" in str(e.value), str(e.value)
    for k in (lo, hi):
        assert E.ablated(spec(k), "double-noise")[0].noise_scale == 2 * k
    with pytest.raises(E.ExperimentError):
        E.ablated(spec(hi * 1.001), "double-noise")
