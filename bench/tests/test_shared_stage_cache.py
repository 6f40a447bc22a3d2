"""Two explores started at once with the same new --cache folder: each stage's trials run once — the second waits
for the first (saying so, with its pid), then reads what it cached — or, if the first ends without caching them,
the second runs them itself; the cache ends holding the entry alone (no lock file, no temporary file)."""

import json
import subprocess
import sys
import time

import pytest

pytestmark = pytest.mark.unit

#: one explore's pilot stage, in a process of its own: its trials are synthetic and take 1.5 s; the first to run
#: them fails after that when FIRST_FAILS (an explore stopped before caching them); prints the rows it got
EXPLORE = """
import json, os, sys, time
from pathlib import Path
from bench.experiments import experiment as E
from bench.tests.test_experiment_variants import _synthetic_sweep

cache, ready, go, runs, first_fails = Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3]), Path(sys.argv[4]), \\
    sys.argv[5] == "1"

def sweep(tasks, **kw):
    first = not runs.exists()
    with runs.open("a") as fh:
        fh.write(f"{os.getpid()}\\n")
    time.sleep(1.5)
    if first and first_fails:
        raise SystemExit(3)
    return _synthetic_sweep(tasks)

E.sweep = sweep
tasks = [E.TrialTask(5, 0.5, 0.025, k, k, 14) for k in range(2)]
ready.touch()
while not go.exists():
    time.sleep(0.005)
rows = E.run_stage("pilot", tasks, cache, progress=False, log=lambda m: print(m, file=sys.stderr, flush=True))
print(json.dumps(rows))
"""


@pytest.mark.parametrize("first_fails", [False, True])
def test_two_explores_sharing_a_new_cache_run_each_stage_once(tmp_path, first_fails):
    cache, go, runs = tmp_path / "new" / "cache", tmp_path / "go", tmp_path / "runs"
    procs = []
    for k in range(2):
        ready = tmp_path / f"ready{k}"
        procs.append((ready, subprocess.Popen(
            [sys.executable, "-c", EXPLORE, str(cache), str(ready), str(go), str(runs), str(int(first_fails))],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)))
    deadline = time.monotonic() + 60
    while not all(ready.exists() for ready, _ in procs) and time.monotonic() < deadline:
        time.sleep(0.01)
    go.touch()  # both start the stage together
    ended = [(p.pid, p.wait(timeout=60), *p.communicate()) for _, p in procs]
    ran = [int(pid) for pid in runs.read_text().split()]
    waited = [(pid, status, out, err) for pid, status, out, err in ended if "waiting for it" in err]
    assert len(waited) == 1, ended  # the other held the entry: one waited for it, saying so
    (waiter, status, out, err) = waited[0]
    first = ran[0]
    assert first != waiter and f"note: another explore (pid {first}) sharing the cache {cache}" in err, err
    assert "is running the pilot stage's trials; waiting for it to finish" in err
    assert not [e for *_, e in ended if "note: the cached" in e]  # no entry was there to be found wanting
    rows = json.loads(out)
    assert status == 0 and [r["trial"] for r in rows] == [0, 1]
    if first_fails:  # the first ended without caching them: the waiter ran them
        assert ran == [first, waiter]
        assert [s for pid, s, *_ in ended if pid == first] == [3]
    else:  # the waiter read what the first cached: the trials ran once, both explores have the same rows
        assert ran == [first]
        assert all(s == 0 and json.loads(o) == rows for _, s, o, _ in ended)
    entries = sorted(p.name for p in cache.iterdir())
    assert len(entries) == 1 and entries[0].startswith("pilot-") and entries[0].endswith(".json"), entries
    assert json.loads((cache / entries[0]).read_text()) == rows
