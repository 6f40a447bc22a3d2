"""Stopping the Cheetah adapter over the RTL while a program's request is still being clocked: the C++ Verilator
harness process is ended under the request (SIGTERM, then SIGKILL), never left running until Python exits; the
bench says so (``stop_problem``), and ``biotac_cheetah`` fails the test at teardown naming it."""

from __future__ import annotations

import ctypes as C
import threading
import time

import pytest

from bench.hosts import cheetah_server
from bench.hosts.cheetah_server import CheetahBench
from bench.tests.host_benches import open_adapter

pytestmark = [pytest.mark.firmware, pytest.mark.rtl]
pytest_plugins = ["pytester"]

#: samples in the long request: clocked LSB first, transfer by transfer, each a round trip to the harness (seconds
#: of wall time, far beyond the shortened wait below)
SAMPLES = 40_000
#: the wait for client threads at stop() the tests use (wall s), instead of CLIENT_STOP_S's 5 s
SHORT_STOP_S = 0.2


def long_request(lib, h) -> tuple[threading.Thread, list]:
    """Start :data:`SAMPLES` sampling commands as one batch shift on handle ``h`` in a thread; returns the thread
    and the list it puts the shift's return value in."""
    lib.c_ch_spi_configure(h, 0, 0, 1, 0)  # mode 0, LSB first: not the vectorised word path
    lib.c_ch_spi_queue_clear(h)
    command = (C.c_uint8 * 2)(0x83, 0x00)
    for _ in range(SAMPLES):
        lib.c_ch_spi_queue_ss(h, 1)
        lib.c_ch_spi_queue_array(h, 2, command)
        lib.c_ch_spi_queue_ss(h, 0)
        lib.c_ch_spi_queue_delay_ns(h, 50_000)
    miso = (C.c_uint8 * (2 * SAMPLES))()
    returned: list = []
    thread = threading.Thread(target=lambda: returned.append(lib.c_ch_spi_batch_shift(h, 2 * SAMPLES, miso)),
                              daemon=True)
    thread.start()
    return thread, returned


def wait_for_batches(cb, n: int, within_s: float = 120.0) -> None:
    """Wait until ``cb`` has started clocking its ``n``-th batch."""
    deadline = time.monotonic() + within_s
    while cb.batches < n:
        assert time.monotonic() < deadline, "the request never reached the bench"
        time.sleep(0.01)


def test_stop_ends_the_rtl_harness_under_a_request_still_being_clocked(monkeypatch):
    monkeypatch.setattr(cheetah_server, "CLIENT_STOP_S", SHORT_STOP_S)
    cb = CheetahBench(1, spi="rtl").start()
    lib = C.CDLL(str(cb.library))
    h = open_adapter(lib, monkeypatch, cb)
    thread, returned = long_request(lib, h)
    wait_for_batches(cb, 1)
    pid = cb.bus.proc.pid
    t0 = time.monotonic()
    cb.stop()
    took = time.monotonic() - t0
    assert cb.bus.proc.poll() is not None  # no harness process survives the bench
    assert took < 30, took
    assert cb.stop_problem == (f"1 client request(s) still being clocked {SHORT_STOP_S:g} s after stop(): the RTL "
                               f"harness process (pid {pid}) was terminated under it")
    thread.join(30)
    lib.c_ch_close(h)  # (the library's one adapter closed: the next test of this process opens it again)
    assert not thread.is_alive() and returned and returned[0] < 0  # the request failed (the harness went)


def test_a_clean_stop_over_the_rtl_reports_nothing(monkeypatch):
    with CheetahBench(1, spi="rtl") as cb:
        pass
    assert cb.stop_problem is None and cb.bus.proc.poll() == 0  # its input ended: it exited by itself


USER_TEST = f'''
import ctypes as C
import os

from firmware_tests.tests.test_cheetah_rtl_stop import long_request, wait_for_batches
from bench.hosts import cheetah_server


def test_program_still_busy_at_teardown(monkeypatch, biotac_cheetah, tmp_path):  # monkeypatch first: undone last
    monkeypatch.setattr(cheetah_server, "CLIENT_STOP_S", {SHORT_STOP_S})
    cb = biotac_cheetah(spi="rtl")
    lib = C.CDLL(str(cb.library))
    monkeypatch.setenv("BIOTAC_CHEETAH_SOCKET", cb.socket_path)
    h = lib.c_ch_open(0)
    assert h == 1
    long_request(lib, h)
    wait_for_batches(cb, 1)
    (tmp_path.parent / "harness.pid").write_text(str(cb.bus.proc.pid))


def test_then_no_harness_process_runs(tmp_path):  # (this session still running: its children not yet orphaned)
    import psutil

    pid = int((tmp_path.parent / "harness.pid").read_text())
    assert not psutil.pid_exists(pid) or psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
'''


def test_biotac_cheetah_ends_the_harness_and_fails_the_test_at_teardown(pytester):
    """The plugin's teardown: the bench's harness process is gone before the session's next test (not left running
    until Python exits), and the test errs at teardown with the bench's line."""
    from bench.paths import REPO

    pytester.makepyfile(test_user=USER_TEST)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", f"--rootdir={pytester.path}",
                                           "-o", f"pythonpath={REPO}")
    result.assert_outcomes(passed=2, errors=1)
    pid = int(next(pytester.path.parent.glob("**/harness.pid")).read_text())
    result.stdout.fnmatch_lines([f"biotac_cheetah: bench on *cheetah.sock: 1 client request(s) still being clocked "
                                 f"{SHORT_STOP_S:g} s after stop(): the RTL harness process (pid {pid}) was "
                                 f"terminated under it"])


def test_cheetah_serve_says_a_request_was_cut_short_when_it_stops(tmp_path, monkeypatch):
    """``biotac-bench cheetah serve`` over the RTL, stopped by Ctrl-C while a program's request is still being
    clocked past ``--request-wait``: it stops as usual (status 0: Ctrl-C is its normal end), and its last lines say the
    request was cut short and the harness ended under it (the program's call fails)."""
    import signal

    from bench.hosts.cheetah_server import build_library
    from firmware_tests.tests.test_cheetah_device import serve

    scene = tmp_path / "rtl.toml"
    scene.write_text('[scene]\nname = "rtl"\nduration_s = 10\n[host]\nspi = "rtl"\n')
    lib = C.CDLL(str(build_library()))
    p, path = serve(scene, "--request-wait", SHORT_STOP_S)
    try:
        monkeypatch.setenv("BIOTAC_CHEETAH_SOCKET", path)
        h = lib.c_ch_open(0)
        assert h == 1
        thread, returned = long_request(lib, h)
        time.sleep(1.0)  # being clocked by now: 40 000 transfers take seconds, far longer than the wait
        assert thread.is_alive()
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=120)
        thread.join(30)
        lib.c_ch_close(h)
    finally:
        p.kill()
    assert p.returncode == 0 and "Traceback" not in err, err
    assert "1 client request(s) still being clocked" in err and "was terminated under it" in err, err
    assert returned and returned[0] < 0
