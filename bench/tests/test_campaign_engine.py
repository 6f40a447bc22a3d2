"""The campaign engine on Dask: results in task order and identical for 1 and 2 workers, a worker killed
mid-task loses nothing, an existing scheduler by address, clear errors."""

import logging
import os
from pathlib import Path

import numpy as np
import pytest

from bench.campaigns.engine import CampaignError, ClusterSpec, group_size, run_tasks
from bench.experiments.trials import TrialTask, run_trial_task, trial_seed

pytestmark = pytest.mark.unit


def seeded_value(task):
    """A task whose result depends only on its own seed."""
    seed, n = task
    return float(np.random.default_rng(seed).standard_normal(n).sum())


def die_once(task):
    """Kills its worker process the first time it runs (a marker file remembers), then answers."""
    marker, value = task
    if not Path(marker).exists():
        Path(marker).write_text("died")
        os._exit(1)
    return value * 2


def raise_once(task):
    """Raises the first time it runs (a marker file remembers), then answers: a task that fails, not a worker."""
    marker, value = task
    if not Path(marker).exists():
        Path(marker).write_text("raised")
        raise RuntimeError("a transient failure")
    return value * 2


def test_results_are_identical_for_one_and_two_workers_and_in_task_order():
    tasks = [(trial_seed(7, "x", k), 1000) for k in range(12)]
    one = run_tasks(seeded_value, tasks, ClusterSpec(workers=1), progress=False)
    two = run_tasks(seeded_value, tasks, ClusterSpec(workers=2), progress=False)
    assert one == two == [seeded_value(t) for t in tasks]


def test_grouped_tasks_give_the_same_results_in_task_order_and_name_a_failing_task_by_its_own_index():
    """50 short tasks travel in groups (6 a group on 1 worker, 3 on 2): the same results in the same order as one
    by one; a failing task deep in a group is reported by its own index."""
    assert group_size(50, 1) == 6 and group_size(50, 2) == 3 and group_size(2160, 2) == 16 and group_size(3, 2) == 1
    tasks = [(trial_seed(8, "g", k), 100) for k in range(50)]
    expected = [seeded_value(t) for t in tasks]
    assert run_tasks(seeded_value, tasks, ClusterSpec(workers=1), progress=False) == expected
    assert run_tasks(seeded_value, tasks, ClusterSpec(workers=2), progress=False) == expected
    tasks[39] = ("not a seed", 1)
    with pytest.raises(CampaignError, match=r"task 39 \(\('not a seed', 1\)\) failed: TypeError"):
        run_tasks(seeded_value, tasks, ClusterSpec(workers=1), progress=False, retries=0)


def test_a_rig_trial_is_the_same_on_any_worker():
    task = TrialTask(902, 0.5, 0.05, 0, trial_seed(1, "t", 902, 0, 0))
    here = run_trial_task(task)
    there = run_tasks(run_trial_task, [task, task], ClusterSpec(workers=2), progress=False)
    for row in there:
        for key in ("traction", "roughness", "fineness", "true_normal_N"):
            assert row[key] == here[key]


@pytest.mark.parametrize("n", [4, 40])  # one task a Dask task; groups of 2
def test_a_worker_killed_mid_task_loses_nothing(tmp_path, n):
    tasks = [(str(tmp_path / "died-once"), k) for k in range(n)]
    assert run_tasks(die_once, tasks, ClusterSpec(workers=2), progress=False) == [2 * k for k in range(n)]
    assert (tmp_path / "died-once").read_text() == "died"  # the kill did happen


def kill_the_scheduler(task):
    """The first task kills the scheduler (its pid in the task) and every task then takes a moment."""
    import signal
    import time

    pid, k = task
    if k == 0:
        os.kill(pid, signal.SIGKILL)
    time.sleep(0.5)
    return k


def test_a_scheduler_lost_mid_run_is_one_line_naming_it_not_a_task_and_a_traceback(capfd):
    """A research group's scheduler killed mid-sweep: distributed logged a traceback as the client closed, and the
    error blamed "task 0 (…) failed: FutureCancelledError …" — no task had failed."""
    import socket
    import subprocess
    import sys
    import time

    from distributed import Client

    from bench.paths import REPO

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env, "cwd": REPO}
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                  "--port", str(port), "--dashboard-address", ":0"], **quiet)
    worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                               "--no-nanny"], **quiet)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:  # the scheduler up, the worker joined
            try:
                with Client(address, timeout="2s") as c:
                    if c.scheduler_info()["workers"]:
                        break
            except OSError:
                pass
            time.sleep(0.2)
        capfd.readouterr()
        logged = []  # what distributed's client logs (its own handler writes to the stderr it found at import)
        catcher = logging.Handler(logging.ERROR)
        catcher.emit = logged.append
        logging.getLogger("distributed.client").addHandler(catcher)
        try:
            with pytest.raises(CampaignError) as e:
                run_tasks(kill_the_scheduler, [(scheduler.pid, k) for k in range(6)], ClusterSpec(scheduler=address),
                          progress=False)
        finally:
            logging.getLogger("distributed.client").removeHandler(catcher)
        assert str(e.value).startswith(f"lost the connection to the Dask scheduler at {address} after 0 of 6 tasks "
                                       "had finished; start the scheduler and its workers again")
        assert not logged and "Traceback" not in capfd.readouterr().err
    finally:
        for p in (worker, scheduler):
            p.kill()
            p.wait()


def test_an_existing_scheduler_by_address_and_by_environment(monkeypatch):
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        tasks = [(k, 10) for k in range(3)]
        assert run_tasks(seeded_value, tasks, ClusterSpec(scheduler=cluster.scheduler_address), progress=False) \
            == [seeded_value(t) for t in tasks]
        monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", cluster.scheduler_address)
        assert ClusterSpec.from_env().scheduler == cluster.scheduler_address


def test_clear_errors_for_no_scheduler_and_a_failing_task():
    with pytest.raises(CampaignError, match="no Dask scheduler answers at tcp://127.0.0.1:9"):
        run_tasks(seeded_value, [(1, 1)], ClusterSpec(scheduler="tcp://127.0.0.1:9"), progress=False)
    with pytest.raises(CampaignError, match="task 1"):
        run_tasks(seeded_value, [(1, 1), ("not a seed", 1)], ClusterSpec(workers=1), progress=False, retries=0)


def test_a_local_cluster_does_not_fight_over_the_dashboard_port():
    """Two campaigns on one machine (or a notebook holding 8787): the scheduler's HTTP server takes a free port
    quietly instead of warning that 8787 is in use."""
    import socket
    import warnings

    from bench.campaigns.engine import close, connect

    holder = socket.socket()
    try:
        holder.bind(("127.0.0.1", 8787))
        holder.listen()
    except OSError:
        pass  # already held by something else: the situation this test is about
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            close(connect(ClusterSpec(workers=1)))
    finally:
        holder.close()
    assert not [w for w in caught if "8787" in str(w.message)]


@pytest.mark.parametrize("address", ["garbage", "tcp://host", "tcp://host:0", "host:99999", "http://host:8786", ""])
def test_a_scheduler_address_that_is_none_is_named_with_its_flag_or_variable(address, monkeypatch):
    """Refused before any connection, naming --scheduler or DASK_SCHEDULER_ADDRESS (distributed said "missing port
    number in address 'garbage'", naming neither); addresses as schedulers print them pass."""
    from bench.campaigns.engine import check_address

    with pytest.raises(ValueError, match="--scheduler .*not a scheduler address; give tcp://HOST:PORT"):
        check_address(address, "--scheduler")
    if address:
        monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", address)
        with pytest.raises(ValueError, match="DASK_SCHEDULER_ADDRESS .*not a scheduler address"):
            ClusterSpec.from_env()
    for good in ("tcp://10.0.0.5:8786", "10.0.0.5:8786", "tcp://[::1]:8786", "tls://sched.example.org:8786"):
        assert check_address(good, "--scheduler") == good


def test_a_task_that_raises_once_is_retried_and_zero_workers_is_refused(tmp_path, monkeypatch):
    """run_tasks' retries cover a task that raises (not only a dead worker); a LocalCluster of 0 workers is an error,
    not "every core"; an explicit --scheduler wins over DASK_SCHEDULER_ADDRESS."""
    marker = str(tmp_path / "raised")
    assert run_tasks(raise_once, [(marker, 21)], ClusterSpec(workers=1), progress=False, retries=1) == [42]
    assert Path(marker).read_text() == "raised"
    with pytest.raises(CampaignError, match="workers"):
        run_tasks(seeded_value, [(1, 1)], ClusterSpec(workers=0), progress=False)
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", "tcp://10.0.0.9:8786")
    assert ClusterSpec.from_env("tcp://10.0.0.5:8786").scheduler == "tcp://10.0.0.5:8786"
    assert ClusterSpec.from_env().scheduler == "tcp://10.0.0.9:8786"


@pytest.mark.parametrize("address", ["tls://127.0.0.1:9", "ucx://127.0.0.1:9"])
def test_a_scheduler_address_this_client_cannot_speak_to_is_one_error_naming_it(address):
    """tls:// (accepted as an address) without the cluster's certificates in Dask's configuration, and ucx:// without
    ucx-py, ended in distributed's TypeError traceback instead of an error naming the scheduler.  (In a process of
    its own, as a user meets it: the failed client's leftovers had kept the next in-process cluster's IO loop from
    starting within distributed's 10 s, in the full suite.)"""
    import subprocess
    import sys

    from bench.paths import REPO

    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    r = subprocess.run([sys.executable, "-m", "bench.cli", "claims", "--seeds", "1", "--only", "scales", "--scheduler",
                        address], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert r.stderr.strip().splitlines()[-1].startswith(f"error: cannot connect to the Dask scheduler at {address}: ")
    assert "tls://" in r.stderr.strip().splitlines()[-1]


def hold_a_project_module_from(path):
    """On a worker: a module of this project (by name) loaded from ``path``, as an import would leave it."""
    import sys
    import types

    module = types.ModuleType("bench._probe_module")
    module.__file__ = path
    sys.modules[module.__name__] = module


def test_workers_holding_project_modules_changed_since_they_started_are_refused(tmp_path):
    """A long-lived worker of an existing cluster runs the code it imported: after an edit (or a git pull) its trials
    came from the old code and were cached under the new code's digest, silently.  Fresh workers pass."""
    import time

    from distributed import Client, LocalCluster

    from bench.campaigns.engine import close, connect

    probe = tmp_path / "probe.py"
    probe.write_text("")
    os.utime(probe, (time.time() - 60,) * 2)  # written well before the worker starts (its start time is to ~1 s)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        close(connect(ClusterSpec(scheduler=cluster.scheduler_address)))
        with Client(cluster) as client:
            client.run(hold_a_project_module_from, str(probe))
        close(connect(ClusterSpec(scheduler=cluster.scheduler_address)))  # loaded, unchanged since
        os.utime(probe, (time.time() + 5,) * 2)  # edited after the worker started
        with pytest.raises(CampaignError, match=r"1 worker\(s\) of the Dask scheduler at .* hold modules of this "
                                                r"project whose files changed .*probe\.py.*restart the workers"):
            connect(ClusterSpec(scheduler=cluster.scheduler_address))


def test_a_scheduler_without_workers_is_said_so_rather_than_a_silent_wait(capsys):
    """The tasks wait for a worker to join (a cluster may grow); that wait had looked like a hang, the bar at 0."""
    from distributed import LocalCluster

    from bench.campaigns.engine import close, connect

    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        close(connect(ClusterSpec(scheduler=cluster.scheduler_address)))
        err = capsys.readouterr().err
        assert f"note: the Dask scheduler at {cluster.scheduler_address} has no workers yet" in err
        cluster.scale(1)
        cluster.wait_for_workers(1)
        close(connect(ClusterSpec(scheduler=cluster.scheduler_address)))
        assert "no workers" not in capsys.readouterr().err


def test_a_worker_that_loaded_a_project_module_after_its_edit_is_not_refused(tmp_path):
    """A file edited after the worker started but before the worker first loaded it (a fresh worker loads the check's
    own module, and what a campaign needs, only when asked) holds the new code: such a worker had been refused as
    stale (the edit compared with the worker's start, not with when the worker can have loaded the file)."""
    import time

    from distributed import Client, LocalCluster

    from bench.campaigns.engine import close, connect

    probe = tmp_path / "probe.py"
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        time.sleep(0.5)  # the worker started well before the edit
        probe.write_text("")  # the edit
        time.sleep(0.1)
        with Client(cluster) as client:
            client.run(hold_a_project_module_from, str(probe))  # loaded after the edit (and the check's module too)
        close(connect(ClusterSpec(scheduler=cluster.scheduler_address)))
        os.utime(probe, (time.time() + 5,) * 2)  # edited again after that: stale now
        with pytest.raises(CampaignError, match=r"probe\.py.*restart the workers"):
            connect(ClusterSpec(scheduler=cluster.scheduler_address))
