"""A research user's own variants of the texture experiment: strategies, ablations of a file's own skin policy, and
the outputs they leave (trials replaced by synthetic rows, so each test takes a second)."""

import json
import re
from dataclasses import asdict

import numpy as np
import pytest

from bench.campaigns import engine
from bench.experiments import experiment as E
from bench.reporting.experiment_report import write_outputs
from bench.tomlfile import spelled


def _synthetic_sweep(tasks, **_):
    """Rows as the rig gives them: each texture its own means, a little noise from the trial's seed."""
    rows = []
    for t in tasks:
        rng = np.random.default_rng(t.seed)
        row = asdict(t)
        row.update(traction=0.2 + 0.05 * (t.texture % 7) + 0.01 * rng.standard_normal(),
                   roughness=5.0 + 0.3 * (t.texture % 5) + 0.05 * rng.standard_normal(),
                   fineness=5.0 + 0.2 * (t.texture % 3) + 0.05 * rng.standard_normal(),
                   pac_at_rails=3 if t.texture == 100 else 0,  # burlap's PAC clipped, as a coarse weave's may be
                   rejected_samples=0,
                   true_normal_N=t.force_N, start_position_m=0.0, simulated_s=1.0, wall_s=0.0)
        rows.append(row)
    return rows


@pytest.fixture
def no_rig(monkeypatch):
    monkeypatch.setattr(E, "sweep", _synthetic_sweep)
    monkeypatch.setattr(engine, "connect", lambda spec: None)
    monkeypatch.setattr(engine, "close", lambda client: None)


def _spec(**exploration):
    return E.parse_experiment({"experiment": {"name": "mine", "seed": 5},
                               "pilot": {"textures": [43, 46, 100], "trials": 2, "movements": [0, 7, 14]},
                               "training": {"textures": [43, 46, 100, 101, 102], "trials": 2},
                               "validation": {"pairs": [[101, 102]], "trials": 2},
                               "exploration": {"pair_simulations": 20, "identification_simulations": 20,
                                               **exploration}}, "mine.toml")


def _strict(text: str):
    """JSON as jq, Go or JavaScript read it: no NaN or Infinity."""
    return json.loads(text, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))


def test_bayesian_alone_is_compared_with_no_baseline_and_summary_json_is_standard(no_rig, tmp_path):
    """strategies = ["bayesian"]: the report had said Bayesian exploration was at least as accurate as cycling and
    random choice, strictly better on every texture, with neither run; with 2 training trials the spread check's
    leave-one-out σ is undefined, and summary.json held NaN (not JSON)."""
    result = E.run_experiment(_spec(strategies=["bayesian"]), cache_dir=None, progress=False, log=lambda m: None)
    write_outputs(result, tmp_path)
    summary = _strict((tmp_path / "summary.json").read_text())
    _strict((tmp_path / "trials.json").read_text())
    assert summary["bayesian_beats_baselines_on"] is None
    assert summary["bayesian_strictly_beats_baselines_on"] is None
    assert summary["spread_check"]["all"]["ratio"] is None  # undefined, said as null
    report = (tmp_path / "report.md").read_text()
    assert "No baseline strategy (cycle, random) was run" in report and "cycling" not in report
    spread = report[report.index("| property | validation | leave-one-out | ratio |"):].split("\n\n")[0]
    assert "nan" not in spread.lower() and "| — |" in spread, spread  # undefined, said so, not "nan"
    assert "— : undefined" in report


def test_the_comparison_names_only_the_baselines_that_ran(no_rig, tmp_path):
    result = E.run_experiment(_spec(strategies=["bayesian", "random"]), cache_dir=None, progress=False,
                              log=lambda m: None)
    write_outputs(result, tmp_path)
    report = (tmp_path / "report.md").read_text()
    assert "at least as accurate as random choice and" in report and "cycling" not in report
    summary = _strict((tmp_path / "summary.json").read_text())
    good, strict = summary["bayesian_beats_baselines_on"], summary["bayesian_strictly_beats_baselines_on"]
    assert isinstance(good, int) and isinstance(strict, int)
    # the sentence accounts for every identified texture: strictly better, tied, or worse — "the rest tie" had read
    # as if no texture were worse
    m = re.search(r"no more movements on (\d+) of (\d+) identified textures; it is strictly better than it .*? on "
                  r"(\d+) of them, and ties with it on the other (\d+); on (\d+) it is less accurate or slower than "
                  r"it\.", report)
    assert m, report
    g, n, s_, tied, worse = map(int, m.groups())
    assert (g, s_, tied) == (good, strict, good - strict) and s_ + tied + worse == n


@pytest.mark.parametrize("strategies", [["cycle", "random"], ["random"], ["bayesian", "bayesian"]])
def test_strategies_without_bayesian_or_twice_are_refused_before_any_trial(strategies):
    """Without "bayesian" the experiment ran every stage and then ended in a KeyError traceback, its out folder
    half written; a strategy listed twice ran twice and was counted once."""
    with pytest.raises(E.ExperimentError) as e:
        _spec(strategies=strategies)
    assert f"exploration.strategies = {spelled(strategies)}" in str(e.value) and '"bayesian"' in str(e.value)


def test_unreplaced_wear_turns_wear_on_in_a_file_that_has_it_off():
    """"skin wear on, never replaced" on a file with wear = false changed only replace_skin, so the variant was the
    baseline under the ablation's name."""
    spec = E.parse_experiment({"experiment": {"name": "x"}, "training": {"wear": False}}, "x.toml")
    variant, what = E.ablated(spec, "unreplaced-wear")
    assert variant.wear and not variant.replace_skin
    assert "wear False → True" in what and "same as the baseline" not in what
    default, what = E.ablated(E.parse_experiment({"experiment": {"name": "x"}}, "x.toml"), "unreplaced-wear")
    assert what == "skin wear on, never replaced: replace_skin True → False"  # only what changes is listed


def test_the_probability_evolution_plot_says_how_many_textures_it_chooses_among(no_rig, tmp_path, monkeypatch):
    """Its title said "117-way" whatever the experiment's training textures (here 5)."""
    from contextlib import contextmanager

    from bench.reporting import experiment_report

    titles, figure_file = {}, experiment_report.figure_file

    @contextmanager
    def noting_titles(path, *args, **kw):
        with figure_file(path, *args, **kw) as (fig, axes):
            yield fig, axes
            titles[path.name] = fig._suptitle.get_text() if fig._suptitle else ""

    monkeypatch.setattr(experiment_report, "figure_file", noting_titles)
    write_outputs(E.run_experiment(_spec(), cache_dir=None, progress=False, log=lambda m: None), tmp_path)
    assert titles["probability_evolution.png"].startswith("Bayesian exploration (5-way)")


def test_the_accuracy_table_says_how_many_textures_identification_chooses_among(no_rig, tmp_path):
    """A research group's 5-texture experiment: the table's identification row stood as "identification" beside
    D's 117-way figure, as if the two were the same task."""
    write_outputs(E.run_experiment(_spec(), cache_dir=None, progress=False, log=lambda m: None), tmp_path)
    rows = [line for line in (tmp_path / "report.md").read_text().splitlines() if line.startswith("| identification")]
    assert [r.split("|")[1:3] for r in rows] == [[" identification (5-way) ", " bayesian "],
                                                 [" identification (5-way) ", " cycle "],
                                                 [" identification (5-way) ", " random "]]
    assert rows[0].endswith("| 95.4 %, median 5 (117-way) |")


def test_the_report_and_summary_count_the_trials_whose_pac_was_clipped(no_rig, tmp_path):
    """A trial whose PAC sat at the ADC's rails in its measurement window has the roughness and fineness of a clipped
    vibration: nothing said so (a coarse texture of one's own clipped in a third of the window, unremarked)."""
    result = E.run_experiment(_spec(), cache_dir=None, progress=False, log=lambda m: None)
    write_outputs(result, tmp_path)
    rows = [*result.pilot_rows, *result.training_rows, *result.validation_rows]
    clipped = sum(1 for r in rows if r["texture"] == 100)
    assert clipped and _strict((tmp_path / "summary.json").read_text())["trials_with_pac_at_rails"] == clipped
    assert (f"Clipped: {clipped} of {len(rows)} trials had PAC at the ADC's rails (code 0 or 4095) in their "
            "measurement window") in (tmp_path / "report.md").read_text()


def test_accuracy_per_texture_is_in_percent_as_accuracy_csv(no_rig, tmp_path):
    """accuracy.csv said accuracy_% (100.0) while accuracy_per_texture.csv held fractions (1.0, 0.88) under a name
    without a unit: a group merging the two tables read 1 % for a perfect texture."""
    import csv

    result = E.run_experiment(_spec(), cache_dir=None, progress=False, log=lambda m: None)
    write_outputs(result, tmp_path)
    s = E.summary(result)
    with open(tmp_path / "accuracy_per_texture.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [k for k in rows[0] if k not in ("texture", "name")] == [f"{k}_accuracy_%" for k in s]
    for row in rows:
        for k, v in s.items():
            if int(row["texture"]) in v["per_texture_accuracy"]:
                assert float(row[f"{k}_accuracy_%"]) == pytest.approx(
                    100 * v["per_texture_accuracy"][int(row["texture"])], abs=1e-4)
    with open(tmp_path / "accuracy.csv", newline="") as f:
        overall = {f"{r['task']}/{r['strategy']}": float(r["accuracy_%"]) for r in csv.DictReader(f)}
    assert overall == {k: pytest.approx(100 * v["accuracy"], abs=1e-4) for k, v in s.items()}


def test_a_pilot_pick_tied_with_other_movements_says_so(no_rig, tmp_path, monkeypatch):
    """A small pilot of textures far apart: roughness separates them perfectly at every movement (U = 0 at each), and
    the report named the lowest grid id as the least uncertain movement without saying the others were as good."""
    def far_apart(tasks, **_):
        rows = _synthetic_sweep(tasks)
        for r in rows:  # roughness 100 σ apart at every movement: no overlap left to compute
            r["roughness"] = 5.0 + 10.0 * [43, 46, 100, 101, 102].index(r["texture"]) + 0.01 * (r["trial"] - 0.5)
        return rows

    monkeypatch.setattr(E, "sweep", far_apart)
    result = E.run_experiment(_spec(), cache_dir=None, progress=False, log=lambda m: None)
    write_outputs(result, tmp_path)
    picks = _strict((tmp_path / "summary.json").read_text())["pilot_picks_against_d"]
    assert picks["roughness"]["pick_U"] == 0.0 and int(result.best_movements[1]) == 0
    assert picks["roughness"]["tied_with"] == [E.movement_label(7), E.movement_label(14)]
    assert picks["traction"]["tied_with"] == []  # the synthetic traction's noise differs per movement
    report = (tmp_path / "report.md").read_text()
    assert (f"| roughness | {E.movement_label(0)} (U = 0; tied with {E.movement_label(7)}, {E.movement_label(14)}, "
            "the lowest grid id taken) |") in report
    assert "tied" not in next(line for line in report.splitlines() if line.startswith("| traction |"))


def test_the_properties_plot_gives_each_texture_a_slot_and_its_units(no_rig, tmp_path, monkeypatch):
    """Plotted against the texture number, T100..T102 sat beside T43/T46 at a fiftieth of the axis (and a library's
    T950 900 numbers away, its neighbours' bars run together); the y axes named no unit."""
    from contextlib import contextmanager

    from bench.reporting import experiment_report

    seen, figure_file = {}, experiment_report.figure_file

    @contextmanager
    def noting_axes(path, *args, **kw):
        with figure_file(path, *args, **kw) as (fig, axes):
            yield fig, axes
            if path.name == "properties_at_optimal_movements.png":
                seen.update({ax.get_ylabel(): ([t.get_text() for t in ax.get_xticklabels()],
                                               list(ax.get_xticks())) for ax in axes})

    monkeypatch.setattr(experiment_report, "figure_file", noting_axes)
    write_outputs(E.run_experiment(_spec(), cache_dir=None, progress=False, log=lambda m: None), tmp_path)
    assert sorted(seen) == ["fineness (ln Hz)", "roughness (ln bits²)", "traction (A)"]
    for labels, ticks in seen.values():
        assert labels == ["43", "46", "100", "101", "102"] and ticks == [0, 1, 2, 3, 4]


def test_identification_simulations_is_the_total_over_every_texture_identified(no_rig):
    """identify_all_textures: the total was divided by the pairs' textures alone (2 here), so each of the 5
    textures ran 10 and 50 ran where the file asked for 20."""
    result = E.run_experiment(_spec(identify_all_textures=True), cache_dir=None, progress=False, log=lambda m: None)
    for strategy, results in result.identification_results.items():
        assert sorted(int(r.true_texture) for r in results) == [43, 46, 100, 101, 102]
        assert [len(r) for r in results] == [4] * 5, strategy  # 20 in all
    assert E.summary(result)["identification/bayesian"]["simulations"] == 20
    # a total the textures do not divide is still the total run (22 over 5 had run 20: floor division)
    result = E.run_experiment(_spec(identify_all_textures=True, identification_simulations=22), cache_dir=None,
                              progress=False, log=lambda m: None)
    assert [len(r) for r in result.identification_results["bayesian"]] == [5, 5, 4, 4, 4]
    assert E.simulation_shares(3, 4) == [1, 1, 1, 1]  # at least one each: every texture identified has a figure


@pytest.mark.parametrize("training, off", [({"replace_skin": False}, "training.replace_skin = false"),
                                           ({"wear": False}, "training.wear = false")])
def test_replace_at_with_no_replacement_is_a_contradiction(training, off):
    """The replacement level was ignored silently when no skin is ever replaced."""
    with pytest.raises(E.ExperimentError) as e:
        E.parse_experiment({"experiment": {"name": "x"}, "training": {"replace_at": 0.1, **training}}, "x.toml")
    assert f"training.replace_at = 0.1 with {off}" in str(e.value)
    assert E.parse_experiment({"experiment": {"name": "x"}, "training": training}, "x.toml")  # alone: fine


MY_LIBRARY = """
[[texture]]
number = 5
name = "my paper"
group = "paper-like"
rms_height_um = 3.0
correlation_length_um = 80.0
hurst = 0.7
mu_static = 0.6
mu_kinetic = 0.5
modulus_MPa = 30.0
material = "paper"
seed = {seed}
source = "mine"
""" + "".join(f"""
[[texture]]
number = {n}
name = "{name}"
group = "{group}"
rms_height_um = {rms}
correlation_length_um = 300.0
hurst = 0.7
mu_static = 0.55
mu_kinetic = 0.47
modulus_MPa = 0.5
material = "cotton fabric"
seed = {n}
source = "mine"
""" for n, name, group, rms in ((6, "my rough paper", "paper-like", 6.0), (74, "my cotton", "cottons and silks", 20.0),
                                (75, "my coarse cotton", "cottons and silks", 40.0),
                                (950, "my test felt", "test surfaces", 80.0)))


def _my_experiment(tmp_path, seed=5):
    (tmp_path / "lib").mkdir(exist_ok=True)
    (tmp_path / "lib" / "mine.toml").write_text(MY_LIBRARY.format(seed=seed))
    experiment = tmp_path / "mine.toml"
    experiment.write_text('[experiment]\nname = "mine"\nlibrary = "lib/mine.toml"\n'
                          '[pilot]\ntextures = [5, 74, 950]\ntrials = 2\nmovements = [0, 7, 14]\n'
                          '[training]\ntextures = "all"\ntrials = 2\n'
                          '[validation]\nn_pairs = 2\npair_choice = "random-within-group"\ntrials = 2\n'
                          '[exploration]\npair_simulations = 20\nidentification_simulations = 20\n')
    return E.load_experiment(experiment)


def test_an_experiment_on_a_texture_library_of_ones_own(no_rig, tmp_path):
    """[experiment] library (relative to the experiment file): its textures are the experiment's — validated, slid
    by the trials, paired, named in the outputs.  There was no way to run the experiment on one's own library."""
    spec = _my_experiment(tmp_path)
    assert spec.library == str((tmp_path / "lib" / "mine.toml").resolve())
    result = E.run_experiment(spec, cache_dir=None, progress=False, log=lambda m: None)
    assert {r["texture"] for r in result.pilot_rows} == {5, 74, 950}  # T950: only in this library
    assert {r["texture"] for r in result.training_rows} == {5, 6, 74, 75}  # "all": the library's 1..117
    assert {r["library"] for r in result.pilot_rows + result.training_rows + result.validation_rows} == {spec.library}
    assert sorted(map(sorted, result.pairs)) == [[5, 6], [74, 75]]
    write_outputs(result, tmp_path / "out")
    assert "my coarse cotton" in (tmp_path / "out" / "report.md").read_text()
    import hashlib
    import json

    digest = hashlib.sha256((tmp_path / "lib" / "mine.toml").read_bytes()).hexdigest()
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["library"] == {
        "path": spec.library, "sha256": digest, "shipped": False}  # named by path and content, as a scene's is
    assert f"Texture library: {spec.library} (SHA-256 {digest[:16]}…)" in (tmp_path / "out" / "report.md").read_text()


def test_a_library_edited_between_the_stages_is_refused_after_them(no_rig, tmp_path):
    """Each stage reads the library file as it starts (its trials on their workers): an edit between the pilot and
    the training had each stage consistent with itself, while the outputs named the library as read at the start —
    the one neither the training nor the validation ran. The experiment refuses, naming the file and both hashes."""
    from bench.errors import TextureError

    spec = _my_experiment(tmp_path)

    def log(message):
        if message.startswith("training:"):  # between the pilot's trials and the training's
            (tmp_path / "lib" / "mine.toml").write_text(MY_LIBRARY.format(seed=8))

    with pytest.raises(TextureError, match=r"changed while the experiment's stages ran \(SHA-256 \w{16}… at the "
                                           r"start, \w{16}… now\)"):
        E.run_experiment(spec, cache_dir=None, progress=False, log=log)
    _my_experiment(tmp_path)  # unedited: it runs
    assert E.run_experiment(spec, cache_dir=None, progress=False, log=lambda m: None).library["shipped"] is False


def test_a_trial_slides_the_texture_of_its_own_library(monkeypatch):
    from bench.experiments import trials
    from bench.textures import library

    asked = []

    def texture(number, path=None):
        asked.append((number, path))
        raise RuntimeError("enough")

    monkeypatch.setattr(library, "texture", texture)
    for lib in ("/somewhere/mine.toml", ""):
        with pytest.raises(RuntimeError, match="enough"):
            trials.run_trial_task(trials.TrialTask(5, 0.5, 0.025, 0, 1, library=lib))
    assert asked == [(5, "/somewhere/mine.toml"), (5, None)]


def test_a_stage_is_run_again_when_its_library_file_changes(tmp_path, monkeypatch):
    ran = []
    monkeypatch.setattr(E, "sweep", lambda tasks, **kw: ran.append(len(tasks)) or _synthetic_sweep(tasks))
    spec = _my_experiment(tmp_path)
    tasks = [E.TrialTask(5, 0.5, 0.025, k, k, 14, library=spec.library) for k in range(2)]
    for _ in range(2):
        E.run_stage("pilot", tasks, tmp_path / "cache", progress=False, log=lambda m: None)
    assert ran == [2]  # the second from the cache
    _my_experiment(tmp_path, seed=55)  # the same path, another surface for T5
    E.run_stage("pilot", tasks, tmp_path / "cache", progress=False, log=lambda m: None)
    assert ran == [2, 2]


def test_a_library_of_ones_own_that_is_broken_or_missing_is_named_with_the_field(tmp_path):
    experiment = tmp_path / "x.toml"
    for value, words in (('"nothere.toml"', "cannot read the file"), ("3", "the path of a texture library file")):
        experiment.write_text(f'[experiment]\nname = "x"\nlibrary = {value}\n')
        with pytest.raises(E.ExperimentError) as e:
            E.load_experiment(experiment)
        assert f"experiment.library = {value}" in str(e.value)  # as the file spells it
        assert words in str(e.value)
    (tmp_path / "bad.toml").write_text(MY_LIBRARY.format(seed=5).replace("hurst = 0.7", "hurst = 7", 1))
    experiment.write_text('[experiment]\nname = "x"\nlibrary = "bad.toml"\n')
    with pytest.raises(E.ExperimentError, match=r'experiment.library = "bad.toml" \(.*bad.toml\): T5 "my paper": '
                                                r"hurst = 7: allowed range is 0.1 to 1"):
        E.load_experiment(experiment)
