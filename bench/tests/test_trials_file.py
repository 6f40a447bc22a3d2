"""trials.json: texture-sweep and explore write one schema (bench/reporting/trials_file.py), whose rows read back
are trials.csv's, and a file that is not one is refused in one line naming it and the field."""

import csv
import json

import pytest

from bench.cli import main as cli
from bench.reporting.trials_file import TRIALS_FORMAT, TRIALS_VERSION, TrialsFileError, read_trials
from bench.tests.test_sweep_review import TINY

pytestmark = pytest.mark.unit


def _as_csv_text(value) -> str:
    """A JSON row value as trials.csv holds it (None: an empty cell; an object or a list: its JSON text)."""
    if isinstance(value, (dict, list)):
        return json.dumps(value)
    return "" if value is None else str(value)


def _same_rows_as_the_csv(out) -> dict:
    """trials.json of ``out`` read back: the envelope checked and its rows trials.csv's, field for field, in order."""
    doc = read_trials(out / "trials.json")
    with open(out / "trials.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert table and len(doc["rows"]) == len(table)
    for row, text in zip(doc["rows"], table):
        assert list(row) == list(text)  # the same fields, in the same order
        assert {k: _as_csv_text(v) for k, v in row.items()} == text
    assert (doc["format"], doc["version"]) == (TRIALS_FORMAT, TRIALS_VERSION)
    assert list(doc) == ["format", "version", "command", "library", "wall_s", "workers", "rows"]
    assert doc["library"]["shipped"] is True and len(doc["library"]["sha256"]) == 64
    assert doc["workers"] == "LocalCluster, 1 worker(s)" and doc["wall_s"] > 0
    return doc


def test_texture_sweep_and_explore_write_one_schema_whose_rows_are_the_csvs(tmp_path):
    """Both commands on Dask (one worker): each trials.json is the documented envelope, and its rows are those of
    trials.csv beside it; the two commands' rows have the same fields."""
    sweep = tmp_path / "sweep"
    assert cli.main(["texture-sweep", "--textures", "902", "--movements", "7,14", "--trials", "1", "--workers", "1",
                     "--fidelity", "fast", "--quiet", "--out", str(sweep)]) == 0
    swept = _same_rows_as_the_csv(sweep)
    assert swept["command"] == "texture-sweep" and len(swept["rows"]) == 2
    experiment = tmp_path / "tiny.toml"
    experiment.write_text(TINY.format(max_moves=10).replace('seed = 3', 'seed = 3\nfidelity = "fast"'))
    explored_out = tmp_path / "explore"
    assert cli.main(["explore", str(experiment), "--no-cache", "--workers", "1", "--quiet",
                     "--out", str(explored_out)]) == 0
    explored = _same_rows_as_the_csv(explored_out)
    assert explored["command"] == "explore"
    stages = json.loads((explored_out / "summary.json").read_text())["wall_s"]  # the wall time of each stage
    assert explored["wall_s"] == pytest.approx(stages["pilot"] + stages["training"] + stages["validation"])
    assert {r["stage"] for r in explored["rows"]} == {"pilot", "training", "validation"}
    assert list(explored["rows"][0]) == list(swept["rows"][0])


def _envelope(**changes) -> str:
    doc = {"format": TRIALS_FORMAT, "version": TRIALS_VERSION, "command": "explore",
           "library": {"path": "x", "sha256": "0" * 64, "shipped": True}, "wall_s": 1.0, "workers": "w",
           "rows": [{"texture": 1}]}
    doc.update(changes)
    return json.dumps({k: v for k, v in doc.items() if v is not ...})


@pytest.mark.parametrize("text, message", [
    ('[{"texture": 1}]', 'no "format" field: not a trials.json of this schema'),
    (_envelope(format="something else"), 'format = "something else": expected "biotac-bench trials"'),
    (_envelope(version=2), "version = 2: this biotac-bench reads version 1"),
    (_envelope(command="run"), 'command = "run": one of texture-sweep, explore'),
    (_envelope(rows=...), "rows is missing: must be a list"),
    (_envelope(wall_s=True), "wall_s = true: must be a number"),
    (_envelope(library="mine.toml"), 'library = "mine.toml": must be an object'),
    (_envelope(rows=[{"texture": 1}, 7]), "rows[1] = 7: must be an object (one trial)"),
    ("{not json", "not JSON"),
    # values shown as every message shows them (bench.tomlfile.spelled), not as json.dumps wrote them: text as
    # written, an object as {key = value}, a long value cut saying its length
    (_envelope(format="Bühl"), 'format = "Bühl": expected'),
    (_envelope(library=[{"path": "x"}]), 'library = [{path = "x"}]: must be an object'),
    (_envelope(command="x" * 100), f'command = "{"x" * 54}… (102 characters): one of'),
])
def test_a_file_that_is_not_a_trials_json_is_refused_naming_the_file_and_the_field(tmp_path, text, message):
    path = tmp_path / "trials.json"
    path.write_text(text)
    with pytest.raises(TrialsFileError) as e:
        read_trials(path)
    assert str(e.value).startswith(f"{path}: ") and message in str(e.value) and "\n" not in str(e.value)


def test_a_trial_whose_property_is_undefined_keeps_the_reason_as_json_in_trials_csv(tmp_path):
    """A row's ``undefined`` ({property: why}, beside the property's empty cell) is JSON text in trials.csv, so a
    reader of the CSV gets the same object trials.json holds (it had been Python's repr, with single quotes)."""
    from bench.reporting.experiment_report import write_rows_csv

    why = {"fineness": "PAC is constant over the measurement window 1.9…3.3 s: spectral centroid undefined"}
    rows = [{"texture": 902, "fineness": None, "undefined": why}, {"texture": 901, "fineness": 5.5}]
    write_rows_csv(tmp_path / "trials.csv", rows)
    with open(tmp_path / "trials.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert json.loads(table[0]["undefined"]) == why and table[0]["fineness"] == "" and table[1]["undefined"] == ""
    assert table[0]["undefined"] == _as_csv_text(why)  # (what the comparison of whole files above expects)
