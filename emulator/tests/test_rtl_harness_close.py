"""The streaming RTL harness behind ``spi="rtl"``: closing it never leaves the process behind (even one that hangs),
and an idle stretch of virtual time costs the harness little work however long it is (the RTL's timer is used
only as differences, so the harness skips idle timer edges), with MISO still matching the reference model."""

import subprocess
import sys

import numpy as np
import pytest

from emulator.rtl import harness as H
from emulator.sensor import NoiseSources, Sensor
from emulator.spi import protocol as proto
from emulator.spi.model import SELECT_CODE, Bus, SensorPort

HANGS = "import signal, time; signal.signal(signal.SIGTERM, signal.SIG_IGN); time.sleep(120)"


def _bus_with(proc) -> H.RtlBus:
    """An RtlBus around ``proc`` instead of a harness (close() only needs the process)."""
    bus = object.__new__(H.RtlBus)
    bus.proc = proc
    return bus


def test_close_kills_a_harness_that_does_not_exit(monkeypatch):
    """A harness that ignores the end of its input (and SIGTERM) is killed and reaped: no orphan, no exception."""
    monkeypatch.setattr(H, "CLOSE_TIMEOUT_S", 0.5)
    proc = subprocess.Popen([sys.executable, "-c", HANGS], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        _bus_with(proc).close()
        assert proc.returncode is not None, "the harness process is still running"
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_close_of_a_harness_that_already_exited_is_quiet():
    proc = subprocess.Popen([sys.executable, "-c", "pass"], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    proc.wait()
    bus = _bus_with(proc)
    bus.close()
    bus.close()
    assert proc.returncode == 0


def _sensor() -> Sensor:
    return Sensor(channels_read=["PDC"], seed=2, noise=NoiseSources.none())


def _command_then_read(t_command: float, t_read: float):
    """(start times s, select codes, MOSI words) of a PDC sampling command and a read of its result."""
    return (np.array([t_command, t_read]), np.full(2, SELECT_CODE[1]),
            np.array([int(proto.sample_command(1)) << 8, 0], np.uint16))


@pytest.mark.rtl
def test_an_idle_gap_in_virtual_time_costs_the_harness_little_work():
    """A command, then 2 s of idle bus, then a read: the harness evaluates the RTL a bounded number of times (the
    idle timer edges are skipped: clocking them all would be 4 million evaluations), and a 1000 s gap, and one
    across the 32-bit timer's wrap (4295 s) between a command and its read, give the reference model's words."""
    rtl = H.RtlBus({1: _sensor()})
    try:
        rtl.exchange_words(*_command_then_read(1e-3, 1.06e-3), proto.HOST_DEFAULT_CLOCK_HZ)
        per_word_pair = rtl.evals
        rtl.exchange_words(*_command_then_read(2.001, 2.00106), proto.HOST_DEFAULT_CLOCK_HZ)
        gap_cost = rtl.evals - per_word_pair
        assert gap_cost < per_word_pair + 2000, f"2 s of idle bus cost {gap_cost} evaluations"
        schedule = [_command_then_read(2.01, 1002.01), _command_then_read(1003.0, 6000.0)]
        software = Bus({1: SensorPort(_sensor())})
        software.exchange_words(*_command_then_read(1e-3, 1.06e-3), proto.HOST_DEFAULT_CLOCK_HZ)
        software.exchange_words(*_command_then_read(2.001, 2.00106), proto.HOST_DEFAULT_CLOCK_HZ)
        for start, cs, mosi in schedule:
            got = rtl.exchange_words(start, cs, mosi, proto.HOST_DEFAULT_CLOCK_HZ)
            want = software.exchange_words(start, cs, mosi, proto.HOST_DEFAULT_CLOCK_HZ)
            assert np.array_equal(got, want), f"gap of {start[1] - start[0]:.0f} s: RTL {got} model {want}"
            assert proto.decode_response(got[1:])[1].all(), "the read after the gap is not a good data word"
    finally:
        rtl.close()
    assert rtl.proc.returncode == 0, "the harness did not exit when its input ended"


def _children() -> set[int]:
    """This process's child processes, running or not yet reaped (zombies)."""
    from pathlib import Path

    return {int(pid) for f in Path("/proc/self/task").glob("*/children") for pid in f.read_text().split()}


@pytest.mark.parametrize("stand_in, error", [
    ("exit 3", (H.HarnessError, r"the RTL harness .*/harness did not take the bus's header: it exited with status 3")),
    ("printf 'not ready'; exec sleep 30",
     (H.HarnessError, r"the RTL harness .*/harness did not take the bus's header: it answered b'not read' and was "
                      r"stopped")),
    ("exec sleep 30", (H.HarnessError, r"the RTL harness .*/harness did not take the bus's header: it said nothing "
                                       r"within 1 s and was stopped")),
    ("exec sleep 30", (KeyboardInterrupt, "")),
], ids=["exits at start", "answers something else", "says nothing", "Ctrl-C while it starts"])
def test_a_harness_that_does_not_take_the_header_leaves_nothing_behind(tmp_path, monkeypatch, stand_in, error):
    """An RtlBus whose harness exits as it starts (a broken or foreign binary), or answers its header with anything
    but STREAM_READY, or says nothing within START_TIMEOUT_S, is not made: a HarnessError names the binary and what it
    did; one that the user gives up on with Ctrl-C as it starts, neither.  Its process is reaped (no zombie, none left running), its pipes are closed, and
    nothing warns of a resource left open."""
    import gc
    import os
    import signal
    import threading
    import warnings

    monkeypatch.setattr(H, "CLOSE_TIMEOUT_S", 0.2)
    monkeypatch.setattr(H, "START_TIMEOUT_S", 1.0 if error[0] is H.HarnessError else 30.0)
    harness = H.Harness(build_dir=tmp_path)
    harness.binary.write_text(f"#!/bin/sh\n{stand_in}\n")
    harness.binary.chmod(0o755)
    (tmp_path / "sources.sha256").write_text(harness._sources_digest())  # (taken as built: not rebuilt)
    children, fds = _children(), len(os.listdir("/proc/self/fd"))
    ctrl_c = threading.Timer(0.5, signal.pthread_kill, (threading.get_ident(), signal.SIGINT))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(error[0], match=error[1]):
            if error[0] is KeyboardInterrupt:
                ctrl_c.start()
            H.RtlBus({1: _sensor()}, harness=harness)
        ctrl_c.cancel()  # (when it was never started: nothing to send)
        if ctrl_c.ident is not None:
            ctrl_c.join()
        gc.collect()
    assert _children() == children, "the harness's process was left behind"
    assert len(os.listdir("/proc/self/fd")) == fds, "the harness's pipes were left open"
    assert not [w for w in caught if issubclass(w.category, ResourceWarning)], [str(w.message) for w in caught]


@pytest.mark.rtl
@pytest.mark.parametrize("cut", ["ctrl-c", "raise"], ids=["Ctrl-C while a sensor computes", "a sensor raising"])
def test_a_call_cut_short_before_its_transfers_are_sent_leaves_the_bus_refusing_calls(cut):
    """A real Ctrl-C (SIGINT) while the sensor computes the codes of a call's conversions, or the sensor raising
    there: the bus had already moved its record of the sensors on (the conversion taken, the ADC-busy window, resets
    cleared) for transfers the harness never got.  Every later call is refused, saying why and what to do, rather
    than played against an RTL out of step with that record; close() still ends the harness."""
    import signal

    sensor = _sensor()
    rtl = H.RtlBus({1: sensor})
    try:
        assert rtl.exchange_words(*_command_then_read(1e-3, 1.2e-3), proto.HOST_DEFAULT_CLOCK_HZ)[1] != 0

        def cut_short(*args, **kw):
            if cut == "raise":
                raise RuntimeError("the stimulus went away")
            signal.raise_signal(signal.SIGINT)  # (Python raises KeyboardInterrupt here, as the handler returns)
            return Sensor.sample(sensor, *args, **kw)

        sensor.sample = cut_short
        with pytest.raises(KeyboardInterrupt if cut == "ctrl-c" else RuntimeError):
            rtl.exchange_words(*_command_then_read(2e-3, 2.2e-3), proto.HOST_DEFAULT_CLOCK_HZ)
        del sensor.sample
        ended = "KeyboardInterrupt\\(\\)" if cut == "ctrl-c" else r"RuntimeError\('the stimulus went away'\)"
        for _ in range(2):
            with pytest.raises(H.HarnessError, match=rf"RTL bus: a call of 2 transfers was ended by {ended} before its "
                                                     r"transfers were sent to the harness, while the bus updated its "
                                                     r"record of the sensors .*: that record and the RTL's state are "
                                                     r"out of step; close this bus and make a new one"):
                rtl.exchange_words(*_command_then_read(3e-3, 3.2e-3), proto.HOST_DEFAULT_CLOCK_HZ)
    finally:
        rtl.close()
    assert rtl.proc.returncode is not None


def test_a_call_cut_short_before_its_reply_is_read_leaves_the_bus_refusing_calls():
    """Ctrl-C while a call waits for the harness's MISO: the reply stays in the pipe, where the next call would read
    it as its own (the words of another call, silently).  The bus refuses every later call instead, saying why and
    what to do; close() still ends the harness."""
    import signal
    import threading
    import time

    rtl = H.RtlBus({1: _sensor()})
    main = threading.get_ident()

    def ctrl_c_once_reading() -> None:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            frame = sys._current_frames().get(main)
            while frame is not None and not (frame.f_code.co_name == "_read"
                                             and frame.f_code.co_filename == H.__file__):
                frame = frame.f_back
            if frame is not None:
                signal.pthread_kill(main, signal.SIGINT)
                return
            time.sleep(0.0005)

    n = 400_000  # (the harness plays them for about a second)
    start = 1e-3 + np.arange(n) * 10e-6
    interrupter = threading.Thread(target=ctrl_c_once_reading)
    try:
        interrupter.start()
        with pytest.raises(KeyboardInterrupt):
            rtl.exchange_words(start, np.full(n, SELECT_CODE[1]), np.zeros(n, np.uint16), proto.HOST_DEFAULT_CLOCK_HZ)
        interrupter.join()
        for _ in range(2):
            with pytest.raises(H.HarnessError, match=r"RTL bus: a call of 400000 transfers was ended by "
                                                     r"KeyboardInterrupt\(\) between sending its transfers to the "
                                                     r"harness and reading all of their MISO: the harness's replies "
                                                     r"and the bus's calls are out of step; close this bus and make a "
                                                     r"new one"):
                rtl.exchange_words(*_command_then_read(10.0, 10.0001), proto.HOST_DEFAULT_CLOCK_HZ)
    finally:
        interrupter.join()
        rtl.close()
    assert rtl.proc.returncode is not None
