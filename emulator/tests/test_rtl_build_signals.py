"""A build step (Verilator -> make -> the compilers) runs in a process group of its own that this process passes
SIGINT and SIGTERM on to (:func:`emulator.rtl.build.run_build`): a SIGTERM sent to this process alone ends the
step's grandchildren too (they were left running), and a terminal's Ctrl-C — SIGINT to this process's group —
still reaches them, also under ``run``'s stop guard (which only notes the signal and sees the build fail)."""

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit

REPO = Path(__file__).resolve().parents[2]

#: The build step standing in for make: a Python process that starts a compiler (sleep), writes both pids, waits.
STEP = ("import os, subprocess, sys; c = subprocess.Popen(['sleep', '300']); "
        "open(sys.argv[1], 'w').write(f'{os.getpid()} {c.pid}'); c.wait()")

#: The process under test: runs the step through run_build (under run's stop guard with ``guarded``), then says
#: what it saw.
HOST = textwrap.dedent("""
    import sys
    from emulator.rtl.build import run_build
    from bench.running.signals import StopSignals
    cmd = [sys.executable, "-c", {step!r}, {pids!r}]
    if {guarded!r}:
        with StopSignals(announce=False) as stop:
            r = run_build(cmd)
        print("returncode", r.returncode, "stop", stop.signal_name, flush=True)
    else:
        run_build(cmd)
        print("finished", flush=True)
""")


def _alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie waiting for its parent to reap it counts as ended)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def _start(tmp_path, guarded: bool):
    """The host in a process group of its own (a terminal's job), once its step's two processes run: (host, their
    pids)."""
    pids = tmp_path / "pids"
    host = subprocess.Popen([sys.executable, "-c", HOST.format(step=STEP, pids=str(pids), guarded=guarded)],
                            cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 60
    while not (pids.exists() and len(pids.read_text().split()) == 2):
        assert host.poll() is None and time.monotonic() < deadline, host.communicate()
        time.sleep(0.05)
    return host, [int(p) for p in pids.read_text().split()]


def _gone(pids, timeout_s: float = 10.0) -> list[int]:
    """Those of ``pids`` still running after up to ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while any(map(_alive, pids)) and time.monotonic() < deadline:
        time.sleep(0.05)
    return [p for p in pids if _alive(p)]


def _kill_left(pids) -> None:
    for p in pids:
        try:
            os.kill(p, signal.SIGKILL)
        except ProcessLookupError:
            pass


def test_sigterm_to_the_process_alone_ends_its_builds_grandchildren_too(tmp_path):
    """``kill PID`` (as ``timeout`` or a CI runner sends it) during a build: this process ends by SIGTERM as before,
    and make and the compilers — here the step and its ``sleep`` — end with it instead of running on."""
    host, pids = _start(tmp_path, guarded=False)
    try:
        host.send_signal(signal.SIGTERM)
        host.communicate(timeout=30)
        assert host.returncode == -signal.SIGTERM
        assert _gone(pids) == []
    finally:
        _kill_left(pids)
        if host.poll() is None:
            host.kill()


@pytest.mark.parametrize("guarded", [False, True], ids=["Ctrl-C raises", "run's stop guard notes it"])
def test_a_terminals_ctrl_c_still_reaches_the_build(tmp_path, guarded):
    """SIGINT to the host's process group (a terminal's Ctrl-C) during a build reaches the step's processes,
    forwarded to their own group.  With Python's handler the host stops with KeyboardInterrupt; under ``run``'s stop
    guard it only notes the signal, and sees the build end by it (non-zero status) — how ``run --spi rtl`` tells a
    build the Ctrl-C reached."""
    host, pids = _start(tmp_path, guarded=guarded)
    try:
        os.killpg(host.pid, signal.SIGINT)
        out, err = host.communicate(timeout=30)
        assert _gone(pids) == []
        if guarded:
            words = out.split()
            assert words[0] == "returncode" and int(words[1]) != 0 and words[2:] == ["stop", "SIGINT"], (out, err)
        else:
            assert "KeyboardInterrupt" in err and "finished" not in out, (out, err)
    finally:
        _kill_left(pids)
        if host.poll() is None:
            host.kill()


def test_a_ctrl_c_arriving_while_the_step_starts_still_ends_it(monkeypatch):
    """A SIGINT that arrives as the step is being started — its process made, its group not yet noted to forward
    to — is acted on once it is: the step is stopped and waited for, and KeyboardInterrupt raised.  (Acted on at
    once, the KeyboardInterrupt left the step running in a group of its own, which no terminal's Ctrl-C reaches.)"""
    from emulator.rtl import build

    started = []
    real = subprocess.Popen

    def popen_then_ctrl_c(*args, **kwargs):
        started.append(real(*args, **kwargs))
        os.kill(os.getpid(), signal.SIGINT)  # handled by Python at its next instruction, inside this call
        time.sleep(0.2)
        return started[-1]

    monkeypatch.setattr(build.subprocess, "Popen", popen_then_ctrl_c)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        t0 = time.monotonic()
        with pytest.raises(KeyboardInterrupt):
            build.run_build(["sleep", "10"])
        assert started and started[0].poll() is not None, "the step was left running"
        assert time.monotonic() - t0 < 5.0, "the Ctrl-C was not acted on: the step ran to its end"
    finally:
        signal.signal(signal.SIGINT, previous)
        for p in started:
            if p.poll() is None:
                p.kill()
                p.wait()


def test_a_ctrl_c_held_while_a_step_fails_to_start_is_not_lost(monkeypatch):
    """A SIGINT held while the step was being started, which then failed to start (no such program), is acted on
    all the same when run_build gives up: KeyboardInterrupt, not only the start's error."""
    from emulator.rtl import build

    def ctrl_c_then_fail(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.2)
        raise FileNotFoundError(2, "No such file or directory", args[0][0])

    monkeypatch.setattr(build.subprocess, "Popen", ctrl_c_then_fail)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            build.run_build(["no-such-compiler"])
    finally:
        signal.signal(signal.SIGINT, previous)
