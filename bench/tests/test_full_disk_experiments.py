"""A disk that fills while texture-sweep or explore writes its results (or explore its stage cache): one line naming
the file that could not be written and the folder, exit status 1 (results not written, not bad input), and the
trials kept — in the out folder's trials.json, else in one saved in the system's temporary folder — never a bare
"[Errno 28]" with exit status 2; a stage cache that cannot be written is a note, not the end of the experiment."""

import errno
import os
import re
import tempfile

import pytest

from bench import atomic
from bench.cli import main as cli
from bench.experiments import trials as T
from bench.reporting.trials_file import read_trials
from bench.tests import test_sweep_review as first_review
from bench.tests.test_sweep_review import TINY, _in_process_sweep

pytestmark = pytest.mark.unit
no_cluster = first_review.no_cluster  # the fixture: explore's trials in this process

SWEEP = ["texture-sweep", "--textures", "902", "--movements", "21,7", "--trials", "1", "--quiet"]
NO_SPACE = os.strerror(errno.ENOSPC)


def _disk_full_for(monkeypatch, names: set[str], folder=None) -> None:
    """Moving a finished temporary file into place fails as a full disk does (ENOSPC, naming no file) for the
    files called ``names`` (any, if empty) inside ``folder`` (anywhere, if None); the others are written."""
    commit = atomic.commit

    def full(tmp, final):
        if (not names or final.name in names) and (folder is None or final.parent == folder):
            raise OSError(errno.ENOSPC, NO_SPACE)
        return commit(tmp, final)

    monkeypatch.setattr(atomic, "commit", full)


@pytest.fixture
def system_tmp(tmp_path, monkeypatch):
    """The system's temporary folder, for this test only."""
    where = tmp_path / "system-tmp"
    where.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(where))
    return where


def _one_error_line(err: str) -> str:
    assert "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.startswith("error: ")]
    assert len(lines) == 1, err
    return lines[0]


def _saved(line: str):
    match = re.search(r"saved to (\S+) instead", line)
    assert match, line
    return read_trials(match.group(1))  # (the schema both commands write: checked as read)


def test_atomic_write_names_the_file_a_full_disk_stopped(tmp_path, monkeypatch):
    _disk_full_for(monkeypatch, set())
    with pytest.raises(OSError) as e, atomic.atomic_write(tmp_path / "x.json") as tmp:
        tmp.write_text("{}")
    assert e.value.errno == errno.ENOSPC and e.value.filename == str(tmp_path / "x.json")
    assert list(tmp_path.iterdir()) == []


def test_a_sweep_whose_results_meet_a_full_disk_names_the_file_and_saves_its_trials(tmp_path, monkeypatch, capsys,
                                                                                    system_tmp):
    monkeypatch.setattr(T, "sweep", _in_process_sweep)
    out = tmp_path / "o"
    _disk_full_for(monkeypatch, set(), out)
    assert cli.main([*SWEEP, "--out", str(out)]) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert f"{out}/trials.csv could not be written ({NO_SPACE})" in line and "written: nothing" in line
    saved = _saved(line)
    assert [r["movement_id"] for r in saved["rows"]] == [21, 7] and saved["library"]["path"]
    assert not out.exists()  # the folder the command made held nothing: removed as a refused run's is


def test_a_sweep_whose_plot_meets_a_full_disk_says_the_trials_are_in_place(tmp_path, monkeypatch, capsys,
                                                                          system_tmp):
    monkeypatch.setattr(T, "sweep", _in_process_sweep)
    out = tmp_path / "o"
    _disk_full_for(monkeypatch, {"properties.png"}, out)
    assert cli.main([*SWEEP, "--out", str(out)]) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert f"{out}/properties.png could not be written ({NO_SPACE})" in line
    assert "written: trials.csv, trials.json, wear.csv" in line and f"the trials are in {out}/trials.json" in line
    assert [r["movement_id"] for r in read_trials(out / "trials.json")["rows"]] == [21, 7]
    assert list(system_tmp.iterdir()) == []


@pytest.mark.parametrize("cached", [True, False])
def test_an_experiment_whose_results_meet_a_full_disk_names_the_file_and_saves_its_trials(
        tmp_path, monkeypatch, capsys, no_cluster, system_tmp, cached):
    exp, out = tmp_path / "tiny.toml", tmp_path / "res"
    exp.write_text(TINY.format(max_moves=10))
    _disk_full_for(monkeypatch, set(), out)
    cache = ["--cache", str(tmp_path / "cache")] if cached else ["--no-cache"]
    assert cli.main(["explore", str(exp), *cache, "--quiet", "--out", str(out)]) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert f"{out}/trials.csv could not be written ({NO_SPACE})" in line and "written: nothing" in line
    rows = _saved(line)["rows"]
    assert {r["stage"] for r in rows} == {"pilot", "training", "validation"}


def test_a_stage_cache_that_cannot_be_written_is_a_note_and_the_experiment_goes_on(tmp_path, monkeypatch, capsys,
                                                                                   no_cluster):
    exp, out, cache = tmp_path / "tiny.toml", tmp_path / "res", tmp_path / "cache"
    exp.write_text(TINY.format(max_moves=10))
    _disk_full_for(monkeypatch, set(), cache)
    assert cli.main(["explore", str(exp), "--cache", str(cache), "--quiet", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err and (out / "report.md").exists() and list(cache.iterdir()) == []
    for stage in ("pilot", "training", "validation"):
        assert re.search(rf"note: the {stage} stage's trials could not be cached at {cache}/{stage}-\w+\.json "
                         rf"\({NO_SPACE}\)", err), err



def test_a_sweep_whose_trials_fit_nowhere_says_they_are_lost(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(T, "sweep", _in_process_sweep)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "no-such-folder"))  # the temporary folder unusable too
    out = tmp_path / "o"
    _disk_full_for(monkeypatch, set(), out)
    assert cli.main([*SWEEP, "--out", str(out)]) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert line.endswith("written: nothing; the trials could not be saved in the temporary folder either (No such "
                         "file or directory): lost"), line
