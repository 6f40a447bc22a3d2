"""A research user's own variants of the texture experiment: strategies, ablations of a file's own skin policy, and
the outputs they leave (trials replaced by synthetic rows, so each test takes a second)."""

import json
from dataclasses import asdict

import numpy as np
import pytest

from bench.campaigns import engine
from bench.experiments import experiment as E
from bench.reporting.experiment_report import write_outputs


def _synthetic_sweep(tasks, **_):
    """Rows as the rig gives them: each texture its own means, a little noise from the trial's seed."""
    rows = []
    for t in tasks:
        rng = np.random.default_rng(t.seed)
        row = asdict(t)
        row.update(traction=0.2 + 0.05 * (t.texture % 7) + 0.01 * rng.standard_normal(),
                   roughness=5.0 + 0.3 * (t.texture % 5) + 0.05 * rng.standard_normal(),
                   fineness=5.0 + 0.2 * (t.texture % 3) + 0.05 * rng.standard_normal(),
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


def test_the_comparison_names_only_the_baselines_that_ran(no_rig, tmp_path):
    result = E.run_experiment(_spec(strategies=["bayesian", "random"]), cache_dir=None, progress=False,
                              log=lambda m: None)
    write_outputs(result, tmp_path)
    report = (tmp_path / "report.md").read_text()
    assert "at least as accurate as random choice and" in report and "cycling" not in report
    assert isinstance(_strict((tmp_path / "summary.json").read_text())["bayesian_beats_baselines_on"], int)


@pytest.mark.parametrize("strategies", [["cycle", "random"], ["random"], ["bayesian", "bayesian"]])
def test_strategies_without_bayesian_or_twice_are_refused_before_any_trial(strategies):
    """Without "bayesian" the experiment ran every stage and then ended in a KeyError traceback, its out folder
    half written; a strategy listed twice ran twice and was counted once."""
    with pytest.raises(E.ExperimentError) as e:
        _spec(strategies=strategies)
    assert f"exploration.strategies = {strategies!r}" in str(e.value) and '"bayesian"' in str(e.value)


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


@pytest.mark.parametrize("training, off", [({"replace_skin": False}, "training.replace_skin = false"),
                                           ({"wear": False}, "training.wear = false")])
def test_replace_at_with_no_replacement_is_a_contradiction(training, off):
    """The replacement level was ignored silently when no skin is ever replaced."""
    with pytest.raises(E.ExperimentError) as e:
        E.parse_experiment({"experiment": {"name": "x"}, "training": {"replace_at": 0.1, **training}}, "x.toml")
    assert f"training.replace_at = 0.1 with {off}" in str(e.value)
    assert E.parse_experiment({"experiment": {"name": "x"}, "training": training}, "x.toml")  # alone: fine
