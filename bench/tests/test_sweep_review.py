"""texture-sweep and explore as a first-day user meets them: a trial's seed comes from its identity (not from where
its movement sits in --movements), wear.csv and trials.csv name movements alike, an earlier result is never
overwritten without --force (explore's stage cache still spares every trial), Ctrl-C ends quietly, and the help,
the errors and the explore tables say what they mean."""

import csv
import os
import signal
import subprocess
import sys
import time

import pytest

from bench.cli import main as cli
from bench.experiments import experiment as E
from bench.experiments import trials as T
from bench.paths import FIXTURES, REPO
from bench.reporting.outdir import LOCK_NAME
from bench.rigs.texture_rig import movement_grid

pytestmark = pytest.mark.unit


def _seeds(tasks) -> dict:
    return {(t.texture, t.movement_id, t.trial): t.seed for t in tasks}


def test_seeds_of_the_whole_grid_are_those_of_the_shipped_results():
    """Pinned from the code before the fix: "all" movements (ids 0..35 in order) keep their seeds bit for bit, so
    fishel2012.toml's pilot and every result made from it stay the same."""
    sweep = _seeds(T.sweep_tasks([902, 43], movement_grid(), 2, 0))
    assert sweep[(902, 0, 0)] == 441406893185960610 and sweep[(902, 7, 1)] == 134409398511199765
    assert sweep[(902, 14, 0)] == 505252576785036488 and sweep[(43, 35, 1)] == 774658868030908470
    pilot = _seeds(T.sweep_tasks([10, 30], None, 6, 2012, stage="pilot", movement_ids=range(36)))
    assert pilot[(10, 21, 5)] == 7035495911034046085 and pilot[(30, 35, 0)] == 95527863852640708
    assert pilot[(10, 0, 0)] == 2089726906405314894


def test_a_trials_seed_depends_on_its_grid_movement_not_on_its_place_in_the_list():
    grid = movement_grid()

    def seeds(ids):
        return _seeds(T.sweep_tasks([902], [grid[i] for i in ids], 2, 0, movement_ids=ids))

    whole = _seeds(T.sweep_tasks([902], grid, 2, 0))
    alone, three, reversed_ = seeds([14]), seeds([7, 14, 21]), seeds([21, 14, 7])
    for k in range(2):
        assert alone[(902, 14, k)] == three[(902, 14, k)] == reversed_[(902, 14, k)] == whole[(902, 14, k)]
    assert three == reversed_ == {key: whole[key] for key in three}
    rows = T.wear_per_movement([grid[i] for i in (7, 14, 21)], movement_ids=[7, 14, 21])
    assert [r["movement_id"] for r in rows] == [7, 14, 21]
    assert rows == [r for r in T.wear_per_movement() if r["movement_id"] in (7, 14, 21)]


def test_a_texture_or_movement_listed_twice_is_refused():
    grid = movement_grid()
    with pytest.raises(ValueError, match=r"texture\(s\) \[902\] listed twice"):
        T.sweep_tasks([902, 902], [grid[7]], 1, movement_ids=[7])
    with pytest.raises(ValueError, match=r"movement id\(s\) \[7\] listed twice"):
        T.sweep_tasks([902], [grid[7], grid[7]], 1, movement_ids=[7, 7])
    with pytest.raises(E.ExperimentError, match=r"pilot.movements: grid id\(s\) \[7\] listed twice"):
        E.parse_experiment({"experiment": {"name": "x"}, "pilot": {"movements": [7, 7, 14]}})


@pytest.mark.parametrize("argv, words", [
    (["--textures", "902,T902"], ["--textures", "[902] listed twice"]),
    (["--textures", "902", "--movements", "7,14,7"], ["--movements", "[7] listed twice"]),
    (["--textures", "999"], ["--textures: no texture number 999", "closest"]),
    (["--textures", "43,no such thing"], ['--textures: no texture named "no such thing"']),
])
def test_bad_textures_and_movements_name_the_flag_not_the_library_file(argv, words, tmp_path, capsys):
    assert cli.main(["texture-sweep", *argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert all(w in err for w in words) and "library.toml" not in err and "Traceback" not in err, err
    assert not (tmp_path / "o").exists()  # refused before the out folder is made


def test_sweep_help_shows_the_shipped_pilot_and_a_pilots_worth_of_wear(capsys):
    with pytest.raises(SystemExit):
        cli.main(["texture-sweep", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    pilot = ",".join(map(str, E.load_experiment(FIXTURES / "experiments" / "fishel2012.toml").pilot_textures))
    assert f"--textures {pilot} --trials 6" in text
    assert f"in {T.PILOT_WORTH_TRIALS} trials, a pilot's worth" in text and "100 trials" not in text
    assert "--force" in text


def _in_process_sweep(tasks, spec=None, client=None, progress=True):
    """The sweep without a cluster (the same rows: each trial depends only on its task)."""
    return [T.run_trial_task(t) for t in tasks]


def _csv(path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_sweep_files_share_grid_ids_and_an_earlier_sweep_needs_force(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(T, "sweep", _in_process_sweep)
    monkeypatch.chdir(tmp_path)
    argv = ["texture-sweep", "--textures", "902", "--movements", "21,7", "--trials", "1", "--quiet"]
    assert cli.main(argv) == 0  # no --out: a fresh out/texture-sweep
    first = tmp_path / "out" / "texture-sweep"
    trials, wear = _csv(first / "trials.csv"), _csv(first / "wear.csv")
    assert [r["movement_id"] for r in trials] == [r["movement_id"] for r in wear] == ["21", "7"]
    whole = _seeds(T.sweep_tasks([902], movement_grid(), 1, 0))
    assert {(902, int(r["movement_id"]), 0): int(r["seed"]) for r in trials} == {
        k: v for k, v in whole.items() if k[1] in (7, 21) and k[2] == 0}
    assert cli.main(argv) == 0 and (tmp_path / "out" / "texture-sweep-2" / "trials.csv").exists()  # never overwritten
    capsys.readouterr()
    before = {p.name: p.read_bytes() for p in first.iterdir()}
    assert cli.main([*argv[:-1], "--movements", "14", "--out", str(first)]) == 2
    err = capsys.readouterr().err
    assert f"--out {first}: " in err and "not empty" in err and "--force" in err and "Traceback" not in err
    assert {p.name: p.read_bytes() for p in first.iterdir()} == before  # nothing lost
    assert cli.main([*argv[:-1], "--movements", "14", "--out", str(first), "--force"]) == 0
    assert [r["movement_id"] for r in _csv(first / "wear.csv")] == ["14"]
    (first / "notes.txt").write_text("mine")
    assert cli.main([*argv, "--out", str(first), "--force"]) == 2
    assert "notes.txt" in capsys.readouterr().err and (first / "notes.txt").read_text() == "mine"


def test_a_sweep_slower_than_real_time_says_its_factor_with_digits_not_0x(tmp_path, monkeypatch, capsys):
    """A sweep whose trials take longer in wall time than they simulate (a first run compiling its kernels, a
    loaded cluster) prints its real-time factor as run's report does, 0.77× — it had printed "(0× real time)". The
    factor is checked against trials.json's own wall_s and the rows' simulated seconds."""
    import json

    from bench.reporting.report import realtime_said

    def slow_sweep(tasks, spec=None, client=None, progress=True):  # the rows, in more wall time than simulated
        t0 = time.perf_counter()
        rows = _in_process_sweep(tasks)
        time.sleep(max(0.0, 1.3 * sum(r["simulated_s"] for r in rows) - (time.perf_counter() - t0)))
        return rows

    monkeypatch.setattr(T, "sweep", slow_sweep)
    out = tmp_path / "sweep"
    assert cli.main(["texture-sweep", "--textures", "902", "--movements", "5", "--trials", "1", "--quiet",
                     "--out", str(out)]) == 0
    said = json.loads((out / "trials.json").read_text())
    factor = sum(r["simulated_s"] for r in said["rows"]) / said["wall_s"]
    assert 0 < factor < 1
    assert f"({realtime_said(factor)} real time)" in capsys.readouterr().out
    assert realtime_said(0.7712) == "0.77×" and realtime_said(1234.4) == "1234×"


TINY = """
[experiment]
name = "tiny"
seed = 3
[pilot]
textures = [43, 46, 30]
trials = 2
movements = [0, 14, 21]      # 21 is a high-power movement: run, then excluded
[training]
textures = [43, 46, 30, 100]
trials = 2
[validation]
pairs = [[43, 46]]
trials = 1
[exploration]
max_moves = {max_moves}
pair_simulations = 20
identification_simulations = 20
"""


@pytest.fixture
def no_cluster(monkeypatch):
    """Explore's trials run in this process (no LocalCluster: fast; the rows are the same)."""
    import bench.campaigns.engine as engine

    monkeypatch.setattr(engine, "connect", lambda spec: None)
    monkeypatch.setattr(engine, "close", lambda client: None)
    monkeypatch.setattr(E, "sweep", _in_process_sweep)


def test_explore_protects_its_results_and_reruns_from_the_cache(tmp_path, monkeypatch, no_cluster, capsys):
    exp = tmp_path / "tiny.toml"
    exp.write_text(TINY.format(max_moves=10))
    out, cache = tmp_path / "res", tmp_path / "cache"
    base = ["explore", str(exp), "--cache", str(cache), "--quiet"]
    assert cli.main([*base, "--out", str(out), "--ablation", "smooth-skin"]) == 0
    # the tables: the real number of candidates, no float noise, why a movement has no U
    assert "| 4-way (bayesian) |" in (out / "ablations.md").read_text()
    for row in _csv(out / "accuracy.csv"):
        assert len(row["accuracy_%"].partition(".")[2]) <= 4  # e.g. 56.5, not 56.49999999999999
    status = {int(r["movement_id"]): r["status"] for r in _csv(out / "pilot_uncertainty.csv")}
    assert (status[0], status[14], status[21], status[1]) == ("run", "run", "excluded-high-power", "not-run")
    capsys.readouterr()
    # the same folder again: refused, naming the folder and the flag and how to re-run; nothing touched
    exp.write_text(TINY.format(max_moves=5))  # a changed classifier setting
    before = sorted(p.name for p in out.rglob("*"))
    assert cli.main([*base, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"--out {out}: " in err and "pass --force" in err and "cache" in err and "Traceback" not in err
    assert sorted(p.name for p in out.rglob("*")) == before
    # --force, or a new folder: the earlier results (and ablation folder) replaced, no trial runs again
    monkeypatch.setattr(E, "sweep", lambda *a, **k: pytest.fail("a cached stage ran trials again"))
    assert cli.main([*base, "--out", str(out), "--force"]) == 0
    assert not (out / "smooth-skin").exists() and not (out / "ablations.md").exists()
    assert (out / "report.md").exists() and any(cache.iterdir())
    assert cli.main([*base, "--out", str(tmp_path / "new")]) == 0
    # a cache inside the out folder is kept by --force
    inner = ["explore", str(exp), "--quiet", "--out", str(out), "--cache", str(out / "cache")]
    monkeypatch.setattr(E, "sweep", _in_process_sweep)
    assert cli.main([*inner, "--force"]) == 0
    kept = sorted(p.name for p in (out / "cache").iterdir())
    monkeypatch.setattr(E, "sweep", lambda *a, **k: pytest.fail("a cached stage ran trials again"))
    assert cli.main([*inner, "--force"]) == 0 and sorted(p.name for p in (out / "cache").iterdir()) == kept


def test_force_keeps_the_earlier_results_until_the_new_ones_are_written(tmp_path, monkeypatch, no_cluster, capsys):
    """explore and texture-sweep with --force: a run that fails before its results exist (an experiment refused
    mid-way, a sweep whose cluster dies) leaves the earlier results as they were — they used to be removed when the
    folder was opened, leaving only the lock."""
    from bench.experiments.exploration import ExplorationError

    exp, out = tmp_path / "tiny.toml", tmp_path / "res"
    exp.write_text(TINY.format(max_moves=10))
    explore = ["explore", str(exp), "--cache", str(tmp_path / "cache"), "--quiet", "--out", str(out)]
    assert cli.main(explore) == 0
    before = {p.relative_to(out): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}

    def refused(*args, **kwargs):
        raise ExplorationError("every movement is excluded")

    monkeypatch.setattr(E, "run_experiment", refused)
    assert cli.main([*explore, "--force"]) == 2
    assert "every movement is excluded" in capsys.readouterr().err
    assert {p.relative_to(out): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()} == before

    monkeypatch.setattr(T, "sweep", _in_process_sweep)
    sweep = ["texture-sweep", "--textures", "902", "--movements", "21", "--trials", "1", "--quiet", "--out",
             str(tmp_path / "sweep")]
    assert cli.main(sweep) == 0
    before = {p.name: p.read_bytes() for p in (tmp_path / "sweep").iterdir()}

    def cluster_died(*args, **kwargs):
        raise OSError("the cluster went away")

    monkeypatch.setattr(T, "sweep", cluster_died)
    assert cli.main([*sweep, "--force"]) != 0
    assert {p.name: p.read_bytes() for p in (tmp_path / "sweep").iterdir()} == before


def test_a_sweep_stopped_by_ctrl_c_ends_quietly_with_nothing_written(tmp_path):
    """SIGINT to the process group (a terminal's Ctrl-C; `timeout -s INT`) while the workers run: the main
    process says "interrupted" once and exits 130; no worker prints a traceback; the out folder holds no output;
    no worker is left running."""
    import psutil

    out = tmp_path / "sweep"
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "bench.cli", "texture-sweep", "--textures", "43",
                             "--movements", "all", "--trials", "30", "--workers", "2", "--out", str(out), "--quiet"],
                            cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)  # its own process group, as a terminal's job
    try:
        deadline, workers = time.monotonic() + 60, []
        while time.monotonic() < deadline and len(workers) < 2 and proc.poll() is None:
            time.sleep(0.2)
            workers = [p for p in psutil.Process(proc.pid).children(recursive=True)
                       if "spawn_main" in " ".join(p.cmdline()) and "resource_tracker" not in " ".join(p.cmdline())]
        assert len(workers) == 2, "the workers did not start"
        time.sleep(2.0)  # the workers are running trials
        os.killpg(proc.pid, signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr, stderr
    assert stderr.strip().splitlines()[-1] == "interrupted" and stderr.count("interrupted") == 1, stderr
    assert not out.exists()  # nothing written, nothing half-written: the folder it made is gone
    gone, alive = psutil.wait_procs(workers, timeout=10)
    assert not alive


def test_force_clears_a_several_sensor_runs_sensor_folders(tmp_path):
    """`run --force` into the folder of an earlier several-sensor run: its sensor<k>/ folders (run files and their
    lock) are replaced too — they were refused as foreign before; anything else in one is still refused."""
    from bench.reporting.outdir import OutDirError, OutFolder

    out = tmp_path / "o"
    for folder in (out, out / "sensor2"):
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "record.json").write_text("{}")
        (folder / LOCK_NAME).write_text("1\n")
    OutFolder.open(out, force=True).close()
    assert {p.name for p in out.iterdir()} == {LOCK_NAME}
    (out / "sensor3").mkdir()
    (out / "sensor3" / "mine.txt").write_text("mine")
    with pytest.raises(OutDirError, match="mine.txt"):
        OutFolder.open(out, force=True)
    assert (out / "sensor3" / "mine.txt").read_text() == "mine"
