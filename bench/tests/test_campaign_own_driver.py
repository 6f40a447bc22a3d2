"""A team's own host driver in the fault campaign (``campaign --driver MODULE:CALLABLE`` or ``PATH.py:CALLABLE``):
a real campaign through a driver wrapping the bench's passes and names it; one that loses every other frame without
counting it fails every case; a driver that cannot be imported, is not callable or cannot take the port is refused
in one line naming it before anything runs (the --junit report says the campaign could not run); one that raises,
or returns an object lacking what a case calls, makes its case a JUnit error naming the driver."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from bench.campaigns import faults as campaign
from bench.campaigns.drivers import BENCH_DRIVER, DriverRefused, driver_file, load_driver, uncounted_gaps
from bench.tests.test_cli_review import invoke

DRIVERS = Path(__file__).resolve().parents[2] / "fixtures" / "drivers"
WRAPPED = f"{DRIVERS / 'wrapped_bridge_driver.py'}:open_driver"
EVERY_OTHER = f"{DRIVERS / 'every_other_frame.py'}:EveryOtherFrame"


def _suite(path) -> ET.Element:
    return ET.parse(path).getroot()


@pytest.mark.firmware
def test_a_campaign_through_your_driver_passes_and_names_it(tmp_path, capsys):
    report = tmp_path / "c.xml"
    status, out, err = invoke(["campaign", "--driver", WRAPPED, "--faults", "none,serial_loss", "--scenes", "taps",
                               "--workers", "1", "--quiet", "--junit", report], capsys)
    assert status == 0, out + err
    assert f"driver: {WRAPPED}" in err  # the header
    suite = _suite(report)
    props = {p.get("name"): p.get("value") for p in suite.iter("property")}
    assert props["driver"] == WRAPPED and (suite.get("failures"), suite.get("errors")) == ("0", "0")
    assert all(f"driver {WRAPPED}\n" in c.find("system-out").text for c in suite.iter("testcase"))


@pytest.mark.firmware
def test_a_driver_that_loses_every_other_frame_without_a_word_fails_every_case(tmp_path, capsys):
    report = tmp_path / "c.xml"
    status, out, err = invoke(["campaign", "--driver", EVERY_OTHER, "--faults", "none,serial_loss", "--scenes",
                               "rest", "--workers", "1", "--quiet", "--junit", report], capsys)
    assert status == 1, out + err
    failures = [c.find("failure") for c in _suite(report).iter("testcase")]
    assert len(failures) == 2 and all(f is not None and "frames lost without a word" in f.get("message")
                                      for f in failures)
    assert out.splitlines()[-2] == "0 passed, 2 failed"


def test_frames_missing_from_the_sequence_must_be_counted_as_dropped():
    from types import SimpleNamespace

    frames = [SimpleNamespace(seq=s) for s in (65534, 65535, 1, 2)]  # 0 missing, across the counter's wrap
    assert uncounted_gaps(frames, 1) is None and uncounted_gaps(frames[:2], 0) is None
    assert "missing 1 by their sequence numbers, but counted 0 dropped" in uncounted_gaps(frames, 0)
    # a frame handed over twice, or one from before, is said as such (not "missing 65535"), whatever was counted
    for seqs, said in (((7, 8, 8, 9), "frame 8 right after frame 8 (its frames 2 and 3)"),
                       ((7, 9, 8), "frame 8 right after frame 9 (its frames 2 and 3)")):
        again = [SimpleNamespace(seq=s) for s in seqs]
        assert uncounted_gaps(again, 100) == f"the driver handed over {said}: a frame repeated or out of order"


#: (the driver file's text, the callable's name, what its refusal says)
REFUSED = [
    (None, "open_driver", "no file "),
    ("def open_driver(port:\n", "open_driver", "cannot import "),
    ("raise RuntimeError('no licence')\n", "open_driver", "cannot import "),
    ("def other(port):\n    pass\n", "open_driver", "has no open_driver"),
    ("open_driver = 3\n", "open_driver", "open_driver is a int, not callable"),
    ("def open_driver():\n    pass\n", "open_driver", "cannot be called with the serial port's path alone"),
    ("def open_driver(port, baud):\n    pass\n", "open_driver", "cannot be called with the serial port's path"),
]


@pytest.mark.parametrize("text, name, said", REFUSED, ids=[f"{r[2][:20]}-{k}" for k, r in enumerate(REFUSED)])
def test_a_driver_the_campaign_cannot_use_is_refused_in_one_line_before_anything_runs(tmp_path, capsys, text,
                                                                                       name, said):
    path = tmp_path / "team_driver.py"
    if text is not None:
        path.write_text(text)
    spec = f"{path}:{name}"
    with pytest.raises(DriverRefused) as e:
        load_driver(spec)
    assert str(e.value).startswith(f"--driver {spec}: ") and said in str(e.value) and "\n" not in str(e.value)
    report = tmp_path / "c.xml"
    status, out, err = invoke(["campaign", "--driver", spec, "--faults", "none", "--scenes", "rest", "--quiet",
                               "--junit", report], capsys)
    errors = [line for line in err.splitlines() if line.startswith("error:")]
    assert status == 2 and out == "" and errors == [f"error: {e.value}"] and "Traceback" not in err, err
    error = _suite(report).find("testcase/error")
    assert error.get("type") == "unfinished" and f"the campaign could not run: --driver {spec}" in error.get("message")


@pytest.mark.parametrize("spec", ["nocolon", "x.py:", ":open", "my driver:open", "mod:open()"])
def test_a_driver_spelled_wrong_is_refused_by_the_command_line(capsys, tmp_path, spec):
    status, out, err = invoke(["campaign", "--driver", spec, "--junit", tmp_path / "c.xml"], capsys)
    assert status == 2 and len(err.strip().splitlines()) == 1 and "MODULE:CALLABLE" in err, err
    assert not (tmp_path / "c.xml").exists()


#: (a driver file's text, what its case's error says): raising when opened, in a method, or lacking a method
RAISING = [
    ("def open_driver(port):\n    raise OSError('the port is busy')\n",
     "raised OSError opening the port: the port is busy"),
    ("from bench.hosts.driver import BridgeDriver\n\nclass D(BridgeDriver):\n    def frames(self, **kw):\n"
     "        raise ValueError('bad frame')\n\ndef open_driver(port):\n    return D(port)\n",
     "raised ValueError: bad frame"),
    ("class D:\n    def __init__(self, port):\n        pass\n\n    def start(self):\n        pass\n\n"
     "def open_driver(port):\n    return D(port)\n",
     "returned a D without request_status, wait_for, frames, close, parser"),
]


@pytest.mark.firmware
@pytest.mark.parametrize("text, said", RAISING, ids=["opening", "frames", "lacking"])
def test_a_driver_that_raises_makes_its_case_an_error_naming_it(tmp_path, text, said):
    path = tmp_path / "team_driver.py"
    path.write_text(text)
    spec = f"{path}:open_driver"
    r = campaign.run_case(campaign.FAULTS["none"], "rest", 0, driver=spec)
    assert not r["passed"] and r["error"] and r["problem"].startswith(f"driver {spec} {said}"), r["problem"]
    campaign.write_junit([r], tmp_path / "c.xml")
    suite = _suite(tmp_path / "c.xml")
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors")) == ("1", "0", "1")
    error = suite.find("testcase/error")
    assert error.get("type") == "driver-error" and error.get("message") == r["problem"]
    assert suite.find("testcase/failure") is None
    lines = campaign.summary([r]).splitlines()
    assert lines[1].split()[3] == "ERROR" and lines[-1].startswith("0 passed, 0 failed, 1 error(s)")


@pytest.mark.firmware
def test_a_driver_a_worker_cannot_import_makes_its_case_an_error_naming_it():
    """A ``MODULE:CALLABLE`` driver the campaign's client imported but a worker (of a remote scheduler) cannot: no
    verdict on the firmware — the case is an error naming the driver and why, as one that raises."""
    spec = "team_driver_not_installed_here:open_driver"
    r = campaign.run_case(campaign.FAULTS["none"], "rest", 0, driver=spec)
    assert not r["passed"] and r["error"], r
    assert r["problem"].startswith(f"--driver {spec}: cannot import") and "where this case ran" in r["problem"], r


#: a driver file at the same relative path in the workers' directory: it must not be the one that runs
WORKERS_OWN = "def open_driver(port):\n    raise OSError(\"the worker's own ci/driver.py\")\n"


@pytest.mark.firmware
def test_a_relative_driver_path_is_the_clients_file_on_workers_in_another_directory(tmp_path, monkeypatch):
    """``--driver ci/driver.py:...`` is resolved where the campaign starts and its text goes out with the cases: a
    LocalCluster worker whose working directory holds another ci/driver.py, then none, runs the client's file (as
    a worker of a remote scheduler, on a machine without the file, does)."""
    import os

    from bench.campaigns.engine import ClusterSpec, close, connect

    client_dir, worker_dir = tmp_path / "client", tmp_path / "worker"
    for folder in (client_dir, worker_dir):
        (folder / "ci").mkdir(parents=True)
    (client_dir / "ci" / "driver.py").write_text((DRIVERS / "wrapped_bridge_driver.py").read_text())
    (worker_dir / "ci" / "driver.py").write_text(WORKERS_OWN)
    monkeypatch.chdir(client_dir)
    spec = "ci/driver.py:open_driver"
    client = connect(ClusterSpec(workers=1))  # (its worker process starts here, in the client's directory)
    try:
        client.run(os.chdir, str(worker_dir))
        assert set(client.run(os.getcwd).values()) == {str(worker_dir)}
        for worker_has in ("another file", "no file"):
            r, = campaign.run_campaign(["none"], ["rest"], [0], client=client, driver=spec)
            assert r["passed"] and r["driver"] == spec, (worker_has, r["problem"])
            (worker_dir / "ci" / "driver.py").unlink(missing_ok=True)
    finally:
        close(client)


def test_a_driver_file_runs_from_the_text_the_client_read_under_its_own_name(tmp_path, monkeypatch):
    """What runs is the text read where the campaign started (the file since removed, here), under the file's
    absolute path: a traceback names the team's file and shows its line."""
    import traceback

    (tmp_path / "ci").mkdir()
    path = tmp_path / "ci" / "team_driver.py"
    path.write_text("def open_driver(port):\n    raise OSError('from the text the client read')\n")
    monkeypatch.chdir(tmp_path)
    file = driver_file("ci/team_driver.py:open_driver")
    assert file.path == str(path.resolve())
    path.unlink()
    monkeypatch.chdir("/")
    make = load_driver("ci/team_driver.py:open_driver", file)
    with pytest.raises(OSError, match="from the text the client read") as e:
        make("/dev/pts/N")
    last = traceback.extract_tb(e.value.__traceback__)[-1]
    assert (last.filename, last.lineno, last.line) == (str(path), 2, "raise OSError('from the text the client read')")


#: a driver that never hands over a frame: its frames() reads the port until the port is closed under it
HANGING = """\
from bench.hosts.driver import BridgeDriver


class Hanging(BridgeDriver):
    def frames(self, max_frames=None, timeout_s=5.0):
        while not self.disconnected:
            self.poll()
        return iter(())
"""


@pytest.mark.firmware
def test_a_driver_that_hangs_makes_its_case_an_error_within_the_limit(tmp_path):
    path = tmp_path / "hanging.py"
    path.write_text(HANGING)
    spec = f"{path}:Hanging"
    r = campaign.run_case(campaign.FAULTS["none"], "rest", 0, driver=spec, host_limit_s=3.0)
    assert r["error"] and r["problem"].startswith(f"driver {spec} had not returned within 3 s"), r["problem"]
    assert r["seconds"] < 30


#: a driver that spins in pure Python once asked for frames, carrying on whatever Exception its loop meets: it
#: never blocks, so closing its port cannot end it
SPINNING = """\
from bench.hosts.driver import BridgeDriver


class Spinning(BridgeDriver):
    def frames(self, max_frames=None, timeout_s=5.0):
        while True:
            try:
                for _ in range(10**6):
                    pass
            except Exception:
                pass
"""


@pytest.mark.firmware
def test_a_spinning_driver_is_stopped_when_its_case_times_out_and_the_next_case_runs_at_full_speed(tmp_path):
    """The case's limit stops the driver's thread itself (an exception raised into it), not only the case: no
    "host driver" thread is left, the process burns no CPU while it sleeps (a spinning thread would take a whole
    core), and the next case, through the bench's driver, passes."""
    import threading
    import time

    path = tmp_path / "spinning.py"
    path.write_text(SPINNING)
    spec = f"{path}:Spinning"
    r = campaign.run_case(campaign.FAULTS["none"], "rest", 0, driver=spec, host_limit_s=2.0)
    assert r["error"] and r["problem"] == (f"driver {spec} had not returned within 2 s (a case's calls to the driver "
                                           f"are bounded: start, frames, request_status and wait_for must return); "
                                           f"its thread was stopped"), r["problem"]
    assert not [t for t in threading.enumerate() if t.name == "host driver"]
    cpu, wall = time.process_time(), time.perf_counter()
    time.sleep(1.0)
    assert time.process_time() - cpu < 0.5 * (time.perf_counter() - wall)  # nothing spins on in this process
    assert campaign.run_case(campaign.FAULTS["none"], "rest", 0)["passed"]



def test_a_driver_returning_as_its_limit_passes_is_not_stopped_after_and_no_other_thread_gets_the_stop(monkeypatch):
    """_within's limit passes with the driver's calls still under way; they return before the case stops the
    thread (the case's own _raise_in, run as usual, is only made to wait: for the thread to end, at most 2 s, and
    then for a thread started in its place).  DriverStopped is raised into no thread but the driver's, whose
    thread ends without an uncaught exception; the error says the calls returned late or the thread was stopped.  It
    used to be raised by the ended thread's id, which the thread started next had taken over: that thread got it."""
    import threading
    import time

    returning, unhandled, hit = threading.Event(), [], []
    monkeypatch.setattr(threading, "excepthook", lambda args: unhandled.append(args.exc_type))

    def bystander():
        try:
            for _ in range(500):
                time.sleep(0.001)
        except campaign.DriverStopped:
            hit.append("the next thread")

    raise_in = campaign._raise_in
    started = []

    def raise_in_later(thread, exc_type):
        returning.set()  # (the session returns now)
        deadline = time.monotonic() + 2.0
        while thread.is_alive() and time.monotonic() < deadline:
            time.sleep(0.001)
        started.append(threading.Thread(target=bystander, name="the next thread"))
        started[0].start()
        return raise_in(thread, exc_type)

    def session():
        returning.wait(30)
        return "frames"

    monkeypatch.setattr(campaign, "_raise_in", raise_in_later)
    with pytest.raises(campaign.DriverFailed, match="had not returned within 0.2 s") as failed:
        campaign._within(session, 0.2, "late:driver")
    started[0].join()
    assert hit == [], "DriverStopped was raised into a thread started after the driver's had ended"
    assert unhandled == []
    assert str(failed.value).endswith(("its calls returned just after that", "its thread was stopped"))

def test_the_bench_driver_is_the_default_and_named_so():
    assert load_driver(BENCH_DRIVER).__name__ == "BridgeDriver"
    results = [{"fault": "none", "scene": "rest", "seed": 0, "expected": "-", "passed": True, "problem": None,
                "seconds": 0.1}]  # results from before the driver was recorded: the bench's
    assert "driver bench.hosts.driver:BridgeDriver\n" in campaign.case_output(results[0])


@pytest.mark.firmware
def test_a_driver_that_raises_is_closed_by_the_case(tmp_path):
    """A driver whose ``frames`` raises (its case an error) still has ``close()`` called by the case, so its port's
    file descriptor is given back then, not whenever the garbage collector comes by (a CI campaign of hundreds of
    cases would otherwise hold hundreds of ptys)."""
    closed = tmp_path / "closed"
    path = tmp_path / "team_driver.py"
    path.write_text("from pathlib import Path\n\nfrom bench.hosts.driver import BridgeDriver\n\n"
                    "class D(BridgeDriver):\n    def frames(self, **kw):\n        raise ValueError('bad frame')\n\n"
                    f"    def close(self):\n        Path({str(closed)!r}).write_text('closed')\n"
                    "        super().close()\n\ndef open_driver(port):\n    return D(port)\n")
    r = campaign.run_case(campaign.FAULTS["none"], "rest", 0, driver=f"{path}:open_driver")
    assert r["error"] and "raised ValueError: bad frame" in r["problem"], r["problem"]
    assert closed.read_text() == "closed"


def test_a_driver_file_that_fails_leaves_another_cases_module_of_the_same_file_in_place(tmp_path):
    """Two cases of one worker (threads) run the same driver file: one whose run of the file fails takes out only its
    own module, not the one the other case is using (a dataclass there looks its module up by name)."""
    import sys

    from bench.campaigns import drivers

    file = drivers.DriverFile(str(tmp_path / "team_driver.py"), "X = 1\n")
    first = drivers._run_file(file)  # the other case's, in use
    name = first.__name__
    assert sys.modules[name] is first
    failing = drivers.DriverFile(file.path, "raise OSError('no port')\n")  # the same file, read as it changed
    with pytest.raises(OSError):
        drivers._run_file(failing)
    assert sys.modules.get(name) is first
    del sys.modules[name]


def test_two_cases_running_one_driver_file_at_once_keep_the_survivors_module(tmp_path, monkeypatch):
    """Two threads of a worker run the same driver file at once and the first one's run fails (its port, say) after
    the second one's has begun: the second case's module stays registered under the name they share."""
    import builtins
    import sys
    import threading

    from bench.campaigns import drivers

    first_began, second_began, first_failed = threading.Event(), threading.Event(), threading.Event()

    def step():  # what the file's text calls: the first case fails once the second has begun
        if threading.current_thread().name == "first":
            first_began.set()
            assert second_began.wait(30)
            raise OSError("the port is busy")
        second_began.set()
        assert first_failed.wait(30)

    monkeypatch.setattr(builtins, "_driver_test_step", step, raising=False)
    file = drivers.DriverFile(str(tmp_path / "team_driver.py"), "import builtins\nbuiltins._driver_test_step()\n")
    got = {}

    def run(who):
        try:
            got[who] = drivers._run_file(file)
        except OSError as e:
            got[who] = e
        finally:
            if who == "first":
                first_failed.set()

    threads = [threading.Thread(target=run, args=(who,), name=who) for who in ("first", "second")]
    threads[0].start()
    assert first_began.wait(30)  # (its module registered: the second's registers over it)
    threads[1].start()
    for t in threads:
        t.join(60)
    assert isinstance(got["first"], OSError) and not isinstance(got["second"], Exception)
    assert sys.modules.get(got["second"].__name__) is got["second"]
    del sys.modules[got["second"].__name__]
