"""The second review of texture-sweep and explore: the stage cache writes like every other file (a unique
temporary name, none left by a Ctrl-C), a signal while the outputs are written lets every file finish, SIGTERM
ends a sweep as Ctrl-C does (quietly, exit 143, cluster closed), a second Ctrl-C does not slow the exit, a signal
during the cluster's start is held even when another thread takes it, and a symlinked cache inside --out is kept."""

import json
import os
import pathlib
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from bench.campaigns import engine
from bench.cli import main as cli
from bench.cli.experiments import SWEEP_FILES
from bench.experiments import experiment as E
from bench.experiments import trials as T
from bench.paths import REPO
from bench.reporting import experiment_report
from bench.reporting.outdir import LOCK_NAME, TEMP_SUFFIX, atomic_write
from bench.rigs.texture_rig import movement_grid
from bench.tests import test_sweep_review as first_review
from bench.tests.test_sweep_review import TINY, _in_process_sweep

pytestmark = pytest.mark.unit
no_cluster = first_review.no_cluster  # the fixture: explore's trials in this process

SWEEP_ARGV = ["texture-sweep", "--textures", "902", "--movements", "21,7", "--trials", "1", "--quiet"]


def _stage_tasks():
    return T.sweep_tasks([902], [movement_grid()[7]], 1, 0, movement_ids=[7])


def test_two_writers_of_one_cache_entry_never_collide(tmp_path):
    """A second writer finishes the same entry while the first one is writing it: both end, the entry is whole,
    no temporary file is left (a fixed-name ``.tmp`` was taken from under the first one: FileNotFoundError).  Two
    explores no longer write one entry at once (the entry is locked while its stage runs:
    test_shared_stage_cache.py); the cache's writes stay collision-free on their own."""
    from bench.atomic import atomic_write

    entry = tmp_path / "pilot-0123456789abcdef.json"
    with atomic_write(entry) as first:
        first.write_text('["first"]')
        with atomic_write(entry) as second:
            second.write_text('["second"]')
    assert [p.name for p in tmp_path.iterdir()] == [entry.name]
    assert json.loads(entry.read_text()) == ["first"]  # (the last renamed into place), whole


def test_a_ctrl_c_while_the_stage_cache_is_written_leaves_no_temporary_file(tmp_path, monkeypatch):
    monkeypatch.setattr(E, "sweep", _in_process_sweep)
    write_text = pathlib.Path.write_text

    def cut_short(path, text, *a, **k):
        write_text(path, text[:10], *a, **k)
        raise KeyboardInterrupt

    monkeypatch.setattr(pathlib.Path, "write_text", cut_short)
    with pytest.raises(KeyboardInterrupt):
        E.run_stage("pilot", _stage_tasks(), tmp_path)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("content", ['[{"x": 1}]', "[1, 2]", "NaN", '[{"texture": 902', "", "\udcff"])
def test_a_stage_cache_entry_that_does_not_hold_the_stage_is_said_run_again_and_replaced(tmp_path, monkeypatch,
                                                                                         content):
    """Found by a hostile pass: a foreign, truncated or garbled entry was a KeyError/TypeError traceback, or an
    error naming no file that never healed. It is said, its trials run again, and the entry holds them after."""
    monkeypatch.setattr(E, "sweep", _in_process_sweep)
    good = E.run_stage("pilot", _stage_tasks(), tmp_path)
    (entry,) = tmp_path.iterdir()
    entry.write_text(content, errors="surrogateescape")
    said = []

    def same_trials(rows):  # the wall time differs from run to run, nothing else
        return [{k: v for k, v in r.items() if k != "wall_s"} for r in rows] == \
            [{k: v for k, v in r.items() if k != "wall_s"} for r in good]

    again = E.run_stage("pilot", _stage_tasks(), tmp_path, log=said.append)
    assert same_trials(again) and len(said) == 1 and str(entry) in said[0] and "run again" in said[0]
    assert json.loads(entry.read_text()) == again
    assert E.run_stage("pilot", _stage_tasks(), tmp_path, log=said.append) == again and len(said) == 1


def test_atomic_write_removes_its_temporary_file_on_ctrl_c(tmp_path):
    final = tmp_path / "trials.csv"
    with pytest.raises(KeyboardInterrupt):
        with atomic_write(final) as tmp:
            tmp.write_text("half a ta")
            raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_flushes_the_data_before_the_rename_and_the_folder_after_it(tmp_path, monkeypatch):
    """Whole or not at all also across a power cut (bench.atomic.commit): the temporary file's data is flushed
    (fsync) before the rename gives it the final name — else the name can survive a crash pointing at an empty or
    partial file — and the folder is flushed after it, so the new name itself is on disk."""
    events = []
    fsync, replace = os.fsync, os.replace

    def flush(fd):
        events.append(("fsync", os.fstat(fd).st_ino))
        fsync(fd)

    def rename(src, dst):
        events.append(("rename", os.lstat(src).st_ino))
        replace(src, dst)

    monkeypatch.setattr(os, "fsync", flush)
    monkeypatch.setattr(os, "replace", rename)
    final = tmp_path / "trials.csv"
    with atomic_write(final) as tmp:
        tmp.write_text("a whole table\n")
    monkeypatch.undo()
    written, folder = final.stat().st_ino, tmp_path.stat().st_ino
    assert events == [("fsync", written), ("rename", written), ("fsync", folder)]


def test_atomic_write_gives_the_file_the_mode_an_ordinary_open_would(tmp_path, monkeypatch):
    """The temporary file is made by mkstemp (mode 0600); the file placed has the mode any file the user writes
    gets (0666 less the umask: 0644 under umask 022), not one private to its owner (bench.atomic.temp_path)."""
    import bench.atomic as atomic

    monkeypatch.setattr(atomic, "_UMASK", [0o022])  # the umask as the process read it once
    final = tmp_path / "trials.csv"
    with atomic_write(final) as tmp:
        tmp.write_text("a whole table\n")
    assert oct(final.stat().st_mode & 0o777) == oct(0o644)


def _signal_at_the_first_csv(monkeypatch, signum):
    write_rows_csv = experiment_report.write_rows_csv

    def signal_then_write(*a, **k):
        monkeypatch.setattr(experiment_report, "write_rows_csv", write_rows_csv)
        os.kill(os.getpid(), signum)
        return write_rows_csv(*a, **k)

    monkeypatch.setattr(experiment_report, "write_rows_csv", signal_then_write)


@pytest.mark.parametrize("signum, status, said", [(signal.SIGINT, 130, "interrupted"),
                                                  (signal.SIGTERM, 143, "terminated")])
def test_a_signal_while_the_sweep_writes_finishes_every_file_first(tmp_path, monkeypatch, capsys, signum, status,
                                                                   said):
    monkeypatch.setattr(T, "sweep", _in_process_sweep)
    _signal_at_the_first_csv(monkeypatch, signum)
    out = tmp_path / "sweep"
    assert cli.main([*SWEEP_ARGV, "--out", str(out)]) == status
    assert capsys.readouterr().err.strip().splitlines()[-1] == said
    assert sorted(p.name for p in out.iterdir()) == sorted([*SWEEP_FILES, LOCK_NAME])
    assert not [p for p in out.iterdir() if p.name.endswith(TEMP_SUFFIX)]


def _start_sweep(tmp_path, out):
    """A texture sweep on a 2-worker LocalCluster in its own process group, and its worker processes once they
    run trials."""
    import psutil

    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "bench.cli", "texture-sweep", "--textures", "43",
                             "--movements", "all", "--trials", "30", "--workers", "2", "--out", str(out), "--quiet"],
                            cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline, workers = time.monotonic() + 60, []
    while time.monotonic() < deadline and len(workers) < 2 and proc.poll() is None:
        time.sleep(0.2)
        workers = [p for p in psutil.Process(proc.pid).children(recursive=True)
                   if "spawn_main" in " ".join(p.cmdline()) and "resource_tracker" not in " ".join(p.cmdline())]
    if len(workers) < 2:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail("the workers did not start")
    time.sleep(2.0)  # the workers are running trials
    return proc, workers


def _ended_cleanly(proc, workers, out, status, said, within_s):
    import psutil

    t0 = time.monotonic()
    try:
        _, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    took = time.monotonic() - t0
    assert proc.returncode == status, stderr
    assert "Traceback" not in stderr and "leaked" not in stderr, stderr
    assert stderr.strip().splitlines()[-1] == said, stderr
    assert not out.exists()  # nothing written, nothing half-written: the folder it made is gone
    assert took < within_s, f"the exit took {took:.1f} s"
    assert not psutil.wait_procs(workers, timeout=10)[1]  # no worker left


def test_sigterm_during_the_trials_ends_a_sweep_quietly_with_143(tmp_path):
    """As `timeout 60 biotac-bench texture-sweep …` does: SIGTERM to the main process only."""
    out = tmp_path / "sweep"
    proc, workers = _start_sweep(tmp_path, out)
    os.kill(proc.pid, signal.SIGTERM)
    _ended_cleanly(proc, workers, out, 143, "terminated", within_s=8)


def test_a_second_ctrl_c_does_not_slow_the_exit(tmp_path):
    """The second Ctrl-C used to interrupt the client's closing, and the exit then waited out a timeout (10 s)."""
    out = tmp_path / "sweep"
    proc, workers = _start_sweep(tmp_path, out)
    os.killpg(proc.pid, signal.SIGINT)
    time.sleep(0.1)
    os.killpg(proc.pid, signal.SIGINT)
    _ended_cleanly(proc, workers, out, 130, "interrupted", within_s=6)


def test_a_ctrl_c_during_the_clusters_start_is_held_even_when_another_thread_takes_it():
    """A SIGINT that the kernel gives another thread (tqdm's monitor, say) is not raised inside the block, where it
    would cut LocalCluster's start short with nothing to close; it is raised as the block ends."""
    idle = threading.Event()
    other = threading.Thread(target=idle.wait, daemon=True)
    other.start()  # its signal mask is not blocked
    reached_the_end = False
    try:
        with pytest.raises(KeyboardInterrupt):
            with engine.sigint_blocked():
                signal.pthread_kill(other.ident, signal.SIGINT)
                for _ in range(50):  # the main thread runs Python handlers between bytecodes
                    time.sleep(0.01)
                reached_the_end = True
    finally:
        idle.set()
    assert reached_the_end


@pytest.mark.usefixtures("no_cluster")
def test_a_symlinked_cache_inside_out_is_kept_by_force(tmp_path, monkeypatch, capsys):
    exp = tmp_path / "tiny.toml"
    exp.write_text(TINY.format(max_moves=10))
    out, elsewhere = tmp_path / "res", tmp_path / "elsewhere"
    elsewhere.mkdir()
    out.mkdir()
    (out / "cache").symlink_to(elsewhere)
    monkeypatch.chdir(tmp_path)
    argv = ["explore", str(exp), "--quiet", "--out", "res", "--cache", "res/cache"]
    assert cli.main(argv) == 0, capsys.readouterr().err  # the cache is the only entry: not refused
    assert (out / "report.md").exists() and any(elsewhere.iterdir())
    monkeypatch.setattr(E, "sweep", lambda *a, **k: pytest.fail("a cached stage ran trials again"))
    assert cli.main([*argv, "--force"]) == 0, capsys.readouterr().err
    assert (out / "cache").is_symlink() and any(elsewhere.iterdir())


def test_the_stage_cache_key_digests_every_module_a_trial_runs_through():
    """Found by a mutation pass: the key left out bench/textures/stage.py (the motor-current law behind traction)
    and bench/textures/library.py (its unit conversions), so a warm cache replayed old trials after they changed;
    a later audit found fixtures/electrodes.csv, which every trial reads, left out too. Every module of this
    repository that a trial imports, and every data file it opens, is digested (run in a fresh interpreter, the
    files opened seen by an audit hook; the numba caches under __pycache__ are not inputs)."""
    import subprocess
    import sys

    code = ("import sys; opened = []; "
            "sys.addaudithook(lambda e, a: opened.append(a[0]) if e == 'open' and isinstance(a[0], str) else None); "
            "from bench.experiments.trials import run_trial_task, sweep_tasks; "
            "from bench.rigs.texture_rig import movement_grid; "
            "run_trial_task(sweep_tasks([902], [movement_grid()[7]], 1, 0, movement_ids=[7])[0]); "
            "print('\\n'.join(m.__file__ for m in list(sys.modules.values()) if getattr(m, '__file__', None))); "
            "print('\\n'.join(f for f in opened if '__pycache__' not in f and not f.endswith(('.py', '.pyc'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                         cwd=E.REPO, check=True).stdout.split()
    data = {pathlib.Path(f).resolve() for f in out if pathlib.Path(f).suffix not in (".py", ".pyc")}
    data = {f for f in data if f.is_relative_to(E.REPO / "fixtures")}
    assert E.FIXTURES / "textures" / "library.toml" in data  # the hook sees what a trial reads
    assert not sorted(data - set(E.digest_files())), sorted(data - set(E.digest_files()))
    used = {pathlib.Path(f).resolve() for f in out if pathlib.Path(f).resolve().is_relative_to(E.REPO / "bench")
            or pathlib.Path(f).resolve().is_relative_to(E.REPO / "emulator")}
    used = {f for f in used if f.name != "__init__.py" or f.stat().st_size > 0}
    missing = sorted(str(f.relative_to(E.REPO)) for f in used - set(E.digest_files())
                     if not f.is_relative_to(E.REPO / "bench" / "experiments") or f.name in ("trials.py", "design.py"))
    assert not missing, missing


def test_validation_trials_are_new_trials_not_the_training_ones_again(monkeypatch):
    """Found by a mutation pass: seeding validation trials with the "training" stage reused each training twin's
    start position and noise (only the wear differed), which would inflate the accuracy and no test noticed. Every
    validation trial's seed differs from every training trial's (the quick experiment's stages, trials faked
    from their seeds so that only the bookkeeping runs)."""
    from dataclasses import asdict

    seen: dict[str, list] = {}

    def fake_sweep(tasks, spec=None, client=None, progress=True):
        rows = []
        for t in tasks:
            seen.setdefault(t.stage, []).append(t)
            r = np.random.default_rng(t.seed)
            rows.append(asdict(t) | {"traction": 0.3 + 0.01 * t.texture + 0.001 * r.standard_normal(),
                                     "roughness": 5.0 + 0.02 * t.texture + 0.01 * r.standard_normal(),
                                     "fineness": 3.0 + 0.01 * t.texture + 0.01 * r.standard_normal(),
                                     "true_normal_N": t.force_N, "start_position_m": 0.0, "simulated_s": 1.0,
                                     "wall_s": 0.0})
        return rows

    monkeypatch.setattr(E, "sweep", fake_sweep)
    spec = E.load_experiment(E.REPO / "fixtures" / "experiments" / "quick.toml")
    E.run_experiment(spec, cache_dir=None, progress=False, log=lambda m: None)
    training, validation = seen["training"], seen["validation"]
    assert training and validation
    assert not {t.seed for t in training} & {t.seed for t in validation}
    twins = {(t.texture, t.movement_id, t.trial) for t in training} & {(t.texture, t.movement_id, t.trial)
                                                                       for t in validation}
    assert twins  # the same texture, movement and repetition index in both stages: still a different trial


def test_the_stage_cache_runs_again_when_the_code_changes_or_its_rows_are_not_its_tasks(tmp_path, monkeypatch):
    """A mutation hunt: leaving the code digest out of the key, or trusting a cache file of the right length whose
    rows belong to other tasks, passed every test.  Changed code (another digest) runs the stage again; a file
    with other tasks' rows is said, run again and replaced."""
    import json
    from dataclasses import asdict

    from bench.experiments.trials import sweep_tasks
    from bench.rigs.texture_rig import movement_grid

    ran = []

    def fake_sweep(tasks, spec=None, client=None, progress=True):
        ran.append(len(tasks))
        return [asdict(t) | {"traction": 0.3, "roughness": 5.0, "fineness": 3.0, "rejected_samples": 0} for t in tasks]

    monkeypatch.setattr(E, "sweep", fake_sweep)
    tasks = sweep_tasks([902], [movement_grid()[7]], 2, 0, movement_ids=[7])
    said = []
    E.run_stage("pilot", tasks, tmp_path, progress=False, log=said.append)
    E.run_stage("pilot", tasks, tmp_path, progress=False, log=said.append)
    assert ran == [2]  # the second read from the cache
    monkeypatch.setattr(E, "_code_digest", lambda: "another model")
    E.run_stage("pilot", tasks, tmp_path, progress=False, log=said.append)
    assert ran == [2, 2]
    fresh = tmp_path / "fresh"
    fresh.mkdir()
    E.run_stage("pilot", tasks, fresh, progress=False, log=said.append)
    (cached,) = fresh.iterdir()
    others = sweep_tasks([902], [movement_grid()[7]], 2, 99, movement_ids=[7])  # another seed: other trials
    cached.write_text(json.dumps([asdict(t) | {"traction": 9.0, "roughness": 9.0, "fineness": 9.0} for t in others]))
    rows = E.run_stage("pilot", tasks, fresh, progress=False, log=said.append)
    assert ran == [2, 2, 2, 2] and [r["seed"] for r in rows] == [t.seed for t in tasks]
    assert any("a row that is not its task's trial" in m for m in said), said


def test_validation_runs_the_validation_trials_it_is_asked_for(monkeypatch):
    """quick.toml with 2 validation trials against 3 training ones (its own are both 3, which hid a validation stage
    running training_trials): every validation texture × chosen movement gets exactly 2 (trials faked)."""
    import dataclasses
    from dataclasses import asdict

    seen: dict[str, list] = {}

    def fake_sweep(tasks, spec=None, client=None, progress=True):
        for t in tasks:
            seen.setdefault(t.stage, []).append(t)
        return [asdict(t) | {"traction": 0.3 + 0.01 * t.texture, "roughness": 5.0 + 0.02 * t.texture + 0.001 * t.trial,
                             "fineness": 3.0 + 0.01 * t.texture, "true_normal_N": t.force_N, "start_position_m": 0.0,
                             "simulated_s": 1.0, "wall_s": 0.0} for t in tasks]

    monkeypatch.setattr(E, "sweep", fake_sweep)
    spec = E.load_experiment(E.REPO / "fixtures" / "experiments" / "quick.toml")
    spec = dataclasses.replace(spec, validation_trials=2)
    assert spec.training_trials == 3
    E.run_experiment(spec, cache_dir=None, progress=False, log=lambda m: None)
    per_cell: dict = {}
    for t in seen["validation"]:
        per_cell.setdefault((t.texture, t.movement_id), set()).add(t.trial)
    assert per_cell and set(map(frozenset, per_cell.values())) == {frozenset({0, 1})}
