"""Fault campaigns and claim sweeps on the campaign engine (Dask): the cases and (seed, group) pairs run as tasks on
the cluster — an external scheduler's task stream shows them — with the same verdicts and Spread rows for 1 and 2
workers as the serial code gives; claim groups that start a cluster of their own run on the client; the firmware
builds at once in two threads without colliding; a reply lost on a lossy line is asked for again; a bad --scheduler
is one line and exit 2; Ctrl-C and SIGTERM end a campaign with 130 and 143."""

import math
import os
import re
import signal
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from bench.campaigns import faults as campaign
from bench.campaigns.engine import ClusterSpec, run_tasks
from bench.cli import main as cli
from bench.paths import REPO
from bench.verification import claims
from bench.verification.claims import core

pytestmark = pytest.mark.unit

#: two faults whose verdicts do not depend on the machine's load: on a lossy line the case asks again for a lost
#: reply, and a receive-buffer overrun (a host stalled for bridge.HOST_GONE_S on a very busy machine) only adds to
#: the errors they expect — on a clean line ("none") it would fail the case
FAULTS, SCENE, SEEDS = ["serial_loss", "serial_corruption"], "rest", [0, 1]
CLAIM_ARGS = ["claims", "--seeds", "2", "--only", "noise", "--only", "scales", "--json"]  # the two cheapest groups


@pytest.fixture(scope="module")
def cluster():
    """An external 2-worker Dask cluster and a client that watches its task stream."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as c, \
            Client(c) as client:
        yield c, client


def _on_cluster(cluster, run):
    """``run()``, and the keys and workers of the tasks the cluster ran meanwhile."""
    from distributed import get_task_stream

    with get_task_stream(cluster[1]) as stream:
        out = run()
    return out, [(t["key"], t["worker"]) for t in stream.data]


def _problem(case):
    """A JUnit test case's failure message, None if it passed."""
    failure = case.find("failure")
    return None if failure is None else failure.get("message")


def test_a_fault_campaign_runs_its_cases_on_the_cluster_with_the_same_verdicts_for_1_and_2_workers(cluster, tmp_path,
                                                                                                  capsys):
    serial = [campaign.run_case(campaign.FAULTS[f], SCENE, s) for f in FAULTS for s in SEEDS]
    argv = ["campaign", "--faults", ",".join(FAULTS), "--scenes", SCENE, "--seeds", "2", "--quiet"]
    assert cli.main(argv + ["--workers", "1", "--junit", str(tmp_path / "one.xml")]) == 0
    assert "on LocalCluster, 1 worker(s)" in capsys.readouterr().err
    status, ran = _on_cluster(cluster, lambda: cli.main(argv + ["--scheduler", cluster[0].scheduler_address,
                                                                "--junit", str(tmp_path / "two.xml")]))
    assert status == 0
    assert len(ran) == 4 and all(key.startswith("_run_group-") for key, _ in ran)  # one Dask task a case
    assert {worker for _, worker in ran} == set(cluster[0].scheduler_info["workers"])  # both workers ran cases
    reports = [ET.parse(tmp_path / name).getroot() for name in ("one.xml", "two.xml")]
    verdicts = [[(c.get("classname"), c.get("name"), _problem(c)) for c in report.iter("testcase")]
                for report in reports]
    assert verdicts[0] == verdicts[1] == [(f"campaign.{r['fault']}", f"{r['scene']}[seed={r['seed']}]", r["problem"])
                                          for r in serial]
    assert all(r["passed"] for r in serial)
    for report in reports:  # each case's own wall time, adding up to the suite's
        times = [float(c.get("time")) for c in report.iter("testcase")]
        assert all(t > 0 for t in times) and float(report.get("time")) == pytest.approx(sum(times), abs=0.01)


def test_a_case_that_crashes_on_a_worker_is_a_failed_case_not_a_failed_campaign(cluster):
    """run_case turns a case's own crash (here: a scene the worker does not know) into that case's failure."""
    tasks = [campaign.CaseTask(FAULTS[0], SCENE, 0), campaign.CaseTask(FAULTS[0], "nowhere", 0)]
    ok, crashed = run_tasks(campaign.run_case_task, tasks, client=cluster[1], progress=False)
    assert ok["passed"] and not crashed["passed"] and crashed["problem"] == "KeyError: 'nowhere'"


def _spread_rows(seeds, groups):
    """What the serial code gave: run_claims per seed, each claim's values gathered in seed order."""
    rows: dict[str, dict] = {}
    for seed in seeds:
        for c in claims.run_claims(claims.Bench(seed=seed), groups):
            r = rows.setdefault(c.name, {"name": c.name, "kind": c.kind, "low": c.low, "high": c.high,
                                         "seeds": [], "measured": [], "passed": [], "ok": []})
            r["seeds"].append(seed)
            r["measured"].append(float(c.measured))
            r["passed"].append(c.passed)
            r["ok"].append(c.ok)
    return list(rows.values())


def _finite_or_null(x):
    return x if math.isfinite(x) else None


def _as_compared(json_rows):
    keys = ("name", "kind", "low", "high", "seeds", "measured", "passed", "ok")
    return [{k: r[k] for k in keys} for r in json_rows]


def test_a_claim_sweep_runs_seed_group_pairs_on_the_cluster_with_the_serial_codes_rows(cluster, capsys):
    import json

    reference = _spread_rows([2012, 2013], ["noise", "scales"])
    assert cli.main(CLAIM_ARGS + ["--workers", "1"]) == 0
    one = json.loads(capsys.readouterr().out)
    status, ran = _on_cluster(cluster, lambda: cli.main(CLAIM_ARGS + ["--scheduler", cluster[0].scheduler_address]))
    two = json.loads(capsys.readouterr().out)
    assert status == 0
    assert len(ran) == 4 and all(key.startswith("_run_group-") for key, _ in ran)  # 2 seeds × 2 groups
    assert {worker for _, worker in ran} == set(cluster[0].scheduler_info["workers"])
    as_json = [{**r, "low": _finite_or_null(r["low"]), "high": _finite_or_null(r["high"])} for r in reference]
    assert _as_compared(one) == _as_compared(two) == as_json  # JSON has null for an unbounded side


def test_a_group_that_starts_a_cluster_of_its_own_runs_on_the_client_in_its_place(cluster, monkeypatch):
    """A group marked as starting a cluster is no task (here "scales", standing in for exploration); its rows keep
    their place; a group registered at run time (unknown to the workers) runs on the client too."""
    @claims.claim_group("test-on-client")
    def seeded(bench):
        return [claims.Claim("the seed", "any", float(bench.seed), 0, 1e9, "seed", "test", kind="consistency",
                             note="test")]

    try:
        monkeypatch.setattr(core, "STARTS_A_CLUSTER", frozenset({"scales"}))
        said = []
        rows, ran = _on_cluster(cluster, lambda: claims.run_claims_over_seeds(
            lambda s: claims.Bench(seed=s), [2012, 2013], ["scales", "noise", "test-on-client"], said.append,
            spec=ClusterSpec(scheduler=cluster[0].scheduler_address)))
    finally:
        del claims.CLAIM_GROUPS["test-on-client"]
    assert len(ran) == 2  # noise for each seed
    assert said == ["seed 2012: scales", "seed 2012: test-on-client", "seed 2013: scales", "seed 2013: test-on-client"]
    expected = _spread_rows([2012, 2013], ["scales", "noise"])
    assert [{k: getattr(r, k) for k in expected[0]} for r in rows[:-1]] == expected
    assert rows[-1].name == "the seed" and rows[-1].measured == [2012.0, 2013.0]


def test_every_claim_group_that_can_reach_a_cluster_is_marked_to_run_on_the_client():
    """A group module that calls run_experiment, connect, run_tasks or sweep starts a Dask cluster (a worker
    cannot): its groups must be in STARTS_A_CLUSTER."""
    reaching = re.compile(r"\b(run_experiment|connect|run_tasks|sweep)\(")
    for name, fn in claims.CLAIM_GROUPS.items():
        source = Path(sys.modules[fn.__module__].__file__).read_text()
        assert bool(reaching.search(source)) == (name in core.STARTS_A_CLUSTER), name
        assert core.runs_on_workers(name) == (name not in core.STARTS_A_CLUSTER)


def test_two_builds_of_the_firmware_at_once_both_succeed(tmp_path):
    """Two threads of one worker building the same library: each writes its own temporary file."""
    from bench.hosts.cosim import build_firmware

    barrier, built, failed = threading.Barrier(2), [], []

    def build():
        barrier.wait()
        try:
            built.append(build_firmware(out_dir=tmp_path))
        except Exception as e:  # noqa: BLE001  (the test reports it)
            failed.append(repr(e))

    threads = [threading.Thread(target=build) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert failed == [] and len(set(built)) == 1 and built[0].stat().st_size > 0
    assert not list(tmp_path.rglob("*.partial"))


@pytest.mark.parametrize("argv", [["campaign", "--faults", "none", "--scenes", "rest", "--junit", "{tmp}/c.xml",
                                   "--spi", "rtl"],
                                  ["claims", "--seeds", "1", "--only", "scales"]])
def test_no_scheduler_at_the_address_is_one_line_and_exit_2_within_seconds(argv, capsys, tmp_path):
    """... and a campaign's --junit then says the campaign could not run (an earlier campaign's passing report left
    there would be published as this one's by a CI step that publishes reports whatever the exit status), and over
    which SPI bus it was to run."""
    import xml.etree.ElementTree as ET

    (tmp_path / "c.xml").write_text('<?xml version="1.0" encoding="utf-8"?>\n<testsuite name="biotac-fault-campaign" '
                                    'tests="1" failures="0" time="1.0"><testcase classname="campaign.none" '
                                    'name="rest[seed=0]" time="1.0" /></testsuite>')
    assert cli.main([a.format(tmp=tmp_path) for a in argv] + ["--scheduler", "tcp://127.0.0.1:9"]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines()[-1].startswith("error: no Dask scheduler answers at tcp://127.0.0.1:9")
    # "within seconds": the client gives up after its own 5 s, not distributed's default 30 s connect timeout (the
    # message says which; a wall-clock bound here failed on a loaded machine)
    assert re.search(r"after 5 s\b", err.strip().splitlines()[-1]), err
    assert "Traceback" not in err
    if argv[0] == "campaign":
        suite = ET.parse(tmp_path / "c.xml").getroot()
        assert (suite.get("tests"), suite.get("errors"), suite.get("failures")) == ("1", "1", "0")
        assert suite.find("testcase/error").get("message").startswith(
            "the campaign could not run: no Dask scheduler answers at tcp://127.0.0.1:9")
        assert [(p.get("name"), p.get("value")) for p in suite.findall("properties/property")] == [("spi", "rtl")]


@pytest.mark.parametrize("argv", [["campaign", "--workers", "0"], ["claims", "--seeds", "1", "--workers", "0"]])
def test_no_workers_is_a_usage_error(argv, capsys):
    with pytest.raises(SystemExit) as stop:
        cli.main(argv)
    assert stop.value.code == 2 and "--workers: 0: must be 1 to " in capsys.readouterr().err


@pytest.mark.parametrize("command", [["campaign"], ["claims", "--seeds", "1"],
                                     ["texture-sweep", "--textures", "902"], ["explore", "fixtures/experiments/quick.toml"]])
def test_more_than_four_workers_per_core_is_a_usage_error_naming_the_limit(command, capsys):
    """README: `--workers` is 1 to 4 per core of the machine for every Dask command (a thousand ran it out of memory);
    one more than 4 per core is refused before anything runs, saying how to get a bigger cluster."""
    from bench.cli.main import build_parser

    most = 4 * (os.cpu_count() or 1)
    assert build_parser().parse_args([*command, "--workers", str(most)]).workers == most  # parsed only: nothing runs
    with pytest.raises(SystemExit) as stop:
        build_parser().parse_args([*command, "--workers", str(most + 1)])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and f"--workers: {most + 1}: must be 1 to {most}" in err and "--scheduler" in err


def test_workers_and_scheduler_without_seeds_are_refused_for_claims(capsys):
    assert cli.main(["claims", "--only", "scales", "--workers", "2"]) == 2
    assert capsys.readouterr().err.strip() == ("error: --workers and --scheduler go with --seeds or a group that "
                                               "runs a campaign of its own (exploration); one seed of the other "
                                               "groups runs in this process")


class _ExperimentReached(Exception):
    pass


@pytest.mark.parametrize("extra", [[], ["--seeds", "1"]])
def test_the_exploration_group_runs_its_experiment_on_the_claims_cluster(extra, monkeypatch):
    """``claims --scheduler`` (with or without --seeds) is where the exploration group's experiment runs; it used to
    take its cluster only from DASK_SCHEDULER_ADDRESS."""
    from bench.verification.claims import exploration

    seen = []

    def reached(spec, cluster, **kw):
        seen.append(cluster)
        raise _ExperimentReached

    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    monkeypatch.setattr(exploration, "run_experiment", reached)
    with pytest.raises(_ExperimentReached):
        cli.main(["claims", "--only", "exploration", "--scheduler", "tcp://127.0.0.1:1", *extra])
    assert [(c.scheduler, c.workers) for c in seen] == [("tcp://127.0.0.1:1", None)]


@pytest.mark.parametrize("command", [["campaign", "--faults", "none", "--scenes", "rest"],
                                     ["claims", "--only", "exploration", "--seeds", "1"]])
def test_workers_and_a_scheduler_together_are_refused_not_one_ignored(command, capsys):
    assert cli.main([*command, "--scheduler", "tcp://127.0.0.1:1", "--workers", "2"]) == 2
    err = capsys.readouterr().err
    assert "--workers 2 sizes the LocalCluster" in err and "give one or the other" in err and "Traceback" not in err


def dask_workers_of(proc, n: int, within_s: float = 60.0) -> list:
    """The LocalCluster worker processes (psutil) below ``proc`` once ``n`` of them run; fails the test if they do
    not start within ``within_s`` (s)."""
    import psutil

    def spawned(p) -> bool:
        line = " ".join(p.cmdline())
        return "spawn_main" in line and "resource_tracker" not in line

    deadline, found = time.monotonic() + within_s, []
    while len(found) < n and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.2)
        found = list(filter(spawned, psutil.Process(proc.pid).children(recursive=True)))
    assert len(found) == n, f"{len(found)} of {n} workers started"
    return found


CAMPAIGN_ON_2 = ["campaign", "--seeds", "5", "--workers", "2", "--junit", "c.xml", "--quiet"]


@pytest.mark.parametrize("argv, signum, status, said", [
    (CAMPAIGN_ON_2, signal.SIGINT, 130, "interrupted"), (CAMPAIGN_ON_2, signal.SIGTERM, 143, "terminated"),
    (["claims", "--seeds", "20", "--only", "impact", "--workers", "2"], signal.SIGTERM, 143, "terminated")])
def test_a_signal_ends_a_campaign_or_claim_sweep_with_one_line_its_status_and_no_report(tmp_path, argv, signum,
                                                                                       status, said):
    """Ctrl-C (SIGINT to the process group, as a terminal sends it) or SIGTERM (to the main process, as `timeout`
    sends it) while the tasks run on 2 workers: one line, 130 / 143, the cluster closed; a campaign's --junit then
    holds the cases that had finished, as its summary shows them, and one error saying it was stopped (an earlier campaign's passing report left there would be
    published as this one's by a CI step that publishes reports whatever the exit status)."""
    import psutil
    import xml.etree.ElementTree as ET

    earlier = ('<?xml version="1.0" encoding="utf-8"?>\n<testsuite name="biotac-fault-campaign" tests="1" '
               'failures="0" time="1.0"><testcase classname="campaign.none" name="rest[seed=0]" time="1.0" />'
               '</testsuite>')
    if "--junit" in argv:
        (tmp_path / "c.xml").write_text(earlier)

    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "bench.cli", *argv], cwd=tmp_path, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        workers = dask_workers_of(proc, 2)
        time.sleep(3.0)  # the workers are running tasks
        if signum == signal.SIGINT:
            os.killpg(proc.pid, signum)
        else:
            os.kill(proc.pid, signum)
        stdout, stderr = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == status, stderr
    assert "Traceback" not in stderr and stderr.strip().splitlines()[-1] == said, stderr
    if "--junit" in argv:
        suite = ET.parse(tmp_path / "c.xml").getroot()
        cases = suite.findall("testcase")  # the cases that had finished (if any), then the one saying it stopped
        assert (suite.get("tests"), suite.get("errors"), suite.get("failures")) == (str(len(cases)), "1", "0")
        error = cases[-1].find("error")
        # (36 default cases × 5 seeds)
        assert error is not None and "stopped before its 180 case(s) finished" in error.get("message")
        assert [c.get("name") for c in cases[:-1]] == [line.split()[1] + f"[seed={line.split()[2]}]"
                                                       for line in stdout.splitlines()[1:-1]]  # as the summary
        (tmp_path / "c.xml").unlink()
    else:
        assert stdout == ""
    assert not list(tmp_path.iterdir())  # no other file, no temporary one
    assert not psutil.wait_procs(workers, timeout=10)[1]  # no worker left


def test_a_stopped_campaign_reports_the_cases_that_had_finished(tmp_path):
    """Ctrl-C once a few cases have finished (the progress bar says so): the summary shows them, the --junit report
    holds each with its verdict and output, then one error saying the campaign was stopped and how many finished —
    a CI page shows what ran before the stop, not nothing."""
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "bench.cli", "campaign", "--faults", "none,serial_loss", "--scenes",
                             "rest", "--seeds", "40", "--workers", "1", "--junit", "c.xml"], cwd=tmp_path, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    seen: list[str] = []
    reader = threading.Thread(target=lambda: seen.extend(iter(lambda: proc.stderr.read(1), "")), daemon=True)
    reader.start()
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not any(int(n) >= 3 for n in re.findall(r"(\d+)/80", "".join(seen))):
            time.sleep(0.2)
        os.killpg(proc.pid, signal.SIGINT)
        stdout = proc.communicate(timeout=30)[0]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    reader.join(10)
    assert proc.returncode == 130, "".join(seen)
    rows = stdout.splitlines()[1:-1]
    assert len(rows) >= 3 and stdout.splitlines()[-1] == f"{len(rows)} passed, 0 failed", stdout
    suite = ET.parse(tmp_path / "c.xml").getroot()
    cases = suite.findall("testcase")
    assert [(c.get("classname"), c.get("name")) for c in cases[:-1]] == [
        (f"campaign.{r.split()[0]}", f"{r.split()[1]}[seed={r.split()[2]}]") for r in rows]
    assert all(c.find("system-out").text.endswith(" s\n") and c.find("failure") is None for c in cases[:-1])
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors")) == (str(len(rows) + 1), "0", "1")
    assert cases[-1].find("error").get("message") == (f"the campaign was stopped before its 80 case(s) finished; "
                                                      f"the {len(rows)} that had finished are reported")


@pytest.mark.parametrize("fault, passes", [("serial_loss", True), ("none", False)])
def test_a_lost_reply_is_asked_again_on_a_lossy_line_only(monkeypatch, fault, passes):
    """The line may hit START's acknowledgement or the STATUS reply (which bytes it hits depends on the host's
    timing): on a lossy line the case asks again; on a clean line one lost reply fails the case."""
    from bench.hosts.driver import BridgeDriver

    wait_for, lost = BridgeDriver.wait_for, set()

    def first_reply_lost(self, want, timeout_s=2.0):
        reply = wait_for(self, want, timeout_s)
        if want not in lost:
            lost.add(want)
            return None
        return reply

    monkeypatch.setattr(BridgeDriver, "wait_for", first_reply_lost)
    result = campaign.run_case(campaign.FAULTS[fault], SCENE, 0)
    assert result["passed"] == passes, result["problem"]
    if not passes:
        assert result["problem"] == "TimeoutError: no acknowledgement of START within 1 × 5 s"


def test_a_slow_host_does_not_move_the_faults_schedule(monkeypatch):
    """A host descheduled for 50 ms between reading the virtual time and scheduling each action (a busy machine, two
    workers on two cores) placed the glitches late, several at once: cs_glitch failed with "errors on a healthy
    link".  The actions are now scheduled in the firmware's thread when START arrives."""
    from bench.hosts.bridge import FirmwareBench

    def stalled(fn):
        def slow(*a):
            time.sleep(0.05)
            return fn(*a)
        return slow

    monkeypatch.setattr(FirmwareBench, "virtual_time", property(stalled(FirmwareBench.virtual_time.fget)))
    monkeypatch.setattr(FirmwareBench, "at", stalled(FirmwareBench.at))
    for scene in ("rest", "sphere_drops"):
        result = campaign.run_case(campaign.FAULTS["cs_glitch"], scene, 0)
        assert result["passed"], (scene, result["problem"])


def test_seed_reruns_one_seed_of_a_campaign_as_the_report_named_its_case(tmp_path, capsys):
    """``campaign --seed K``: the cases of seed K alone (a failing case of a ``--seeds N`` campaign again, by the seed
    its report names), with the verdicts of that seed; ``--seed`` beside ``--seeds`` is refused in one line."""
    serial = [campaign.run_case(campaign.FAULTS[f], SCENE, 1) for f in FAULTS]
    argv = ["campaign", "--faults", ",".join(FAULTS), "--scenes", SCENE, "--seed", "1", "--quiet", "--workers", "1",
            "--junit", str(tmp_path / "c.xml")]
    assert cli.main(argv) == 0
    assert "2 cases (2 fault(s) × 1 scene(s) × seed 1)" in capsys.readouterr().err
    report = ET.parse(tmp_path / "c.xml").getroot()
    assert [(c.get("classname"), c.get("name"), _problem(c)) for c in report.iter("testcase")] == [
        (f"campaign.{r['fault']}", f"{SCENE}[seed=1]", r["problem"]) for r in serial]
    with pytest.raises(SystemExit) as refused:
        cli.main(argv + ["--seeds", "2"])
    assert refused.value.code == 2
    assert capsys.readouterr().err == ("biotac-bench campaign: error: argument --seeds: not allowed with argument "
                                       "--seed (see biotac-bench campaign --help)\n")
