"""The Cheetah-compatible library: an unmodified-style client program runs against emulated sensors."""

import ctypes as C
import subprocess

import pytest

from bench.hosts.cheetah_server import CheetahBench, build_client, build_library
from bench.tests.host_benches import cheetah_adapter

pytestmark = pytest.mark.firmware

API = ["find_devices", "find_devices_ext", "open", "open_ext", "close", "port", "unique_id", "status_string",
       "version", "sleep_ms", "target_power", "host_ifce_speed", "dev_addr", "spi_bitrate", "spi_configure",
       "spi_queue_clear", "spi_queue_oe", "spi_queue_delay_cycles", "spi_queue_delay_ns", "spi_queue_ss",
       "spi_queue_byte", "spi_queue_array", "spi_batch_length", "spi_batch_shift", "spi_async_submit",
       "spi_async_collect"]


def test_the_library_exports_the_loader_interface():
    lib = C.CDLL(str(build_library()))
    lib.ch_c_version.restype = C.c_uint32
    v = lib.ch_c_version()
    assert (v & 0xFFFF) >= 0x0306 and (v >> 16) <= (v & 0xFFFF)
    for name in API:
        assert hasattr(lib, f"c_ch_{name}"), name


def test_an_unmodified_client_detects_sensors_and_streams_frames():
    with CheetahBench(2) as cb:
        exe = build_client(cb.library)
        r = subprocess.run([str(exe), "20"], capture_output=True, text=True, env=cb.env, timeout=120)
        assert r.returncode == 0, r.stderr
    serials = [line for line in r.stdout.splitlines() if line.startswith("serial")]
    assert serials[0].endswith("BT0101EMU0000001") and serials[1].endswith("BT0101EMU0000002")
    assert serials[2].endswith("N/A")  # sensor 3 absent: reads back an idle line
    fields = r.stdout.splitlines()[-1].split()
    stats = dict(zip(fields[::2], fields[1::2]))
    assert stats["frames"] == "100" and stats["parity_errors"] == "0"
    assert abs(float(stats["pac_mean"]) - 2048) < 1 and 1.2 < float(stats["pac_std"]) < 1.6


def test_the_example_client_samples_at_4400_slots_per_second():
    """biotac_client.c pads each slot to 1/4400 s with the adapter's overheads (README): 20 batches more (100 frames
    of 44 slots) take the adapter's clock 1.000 s more, within 0.2 % (the difference of two runs cancels the
    set-up and the batches in flight at exit)."""
    elapsed = {}
    for batches in (20, 40):
        with CheetahBench(2) as cb:
            r = subprocess.run([str(build_client(cb.library)), str(batches)], capture_output=True, text=True,
                               env=cb.env, timeout=120)
            assert r.returncode == 0, r.stderr
            elapsed[batches] = cb.t
    assert elapsed[40] - elapsed[20] == pytest.approx(100 * 44 / 4400, rel=2e-3)


def test_queued_delays_and_sleep_advance_the_emulators_time_exactly(monkeypatch):
    with cheetah_adapter(monkeypatch, 1, bitrate_khz=None) as (cb, lib, h):
        t0 = cb.t
        lib.c_ch_spi_queue_clear(h)
        lib.c_ch_spi_queue_delay_ns(h, 123456)
        lib.c_ch_spi_queue_delay_ns(h, 1000)
        buf = (C.c_uint8 * 4)()
        assert lib.c_ch_spi_batch_shift(h, 4, buf) == 0
        assert cb.t - t0 == pytest.approx(124456e-9, abs=1e-12)
        lib.c_ch_sleep_ms(250)
        assert cb.t - t0 == pytest.approx(0.250124456, abs=1e-12)
        assert lib.c_ch_spi_async_collect(h, 4, buf) == -103  # CH_SPI_ASYNC_EMPTY
        assert lib.c_ch_spi_queue_clear(h) == 0 and lib.c_ch_spi_batch_shift(h, 4, buf) == -101  # empty queue
        assert lib.c_ch_close(h) == 0 and lib.c_ch_close(h) == -10  # CH_INVALID_HANDLE once closed


def test_without_the_emulator_the_client_finds_no_adapter(tmp_path):
    exe = build_client(build_library())
    env = {"BIOTAC_CHEETAH_SOCKET": str(tmp_path / "nothing.sock"), "PATH": "/usr/bin:/bin"}
    r = subprocess.run([str(exe), "1"], capture_output=True, text=True, env=env, timeout=30)
    assert r.returncode == 4 and "no Cheetah adapter found" in r.stderr


def test_a_program_that_finds_no_adapter_is_told_why(tmp_path):
    """The library said nothing when BIOTAC_CHEETAH_SOCKET was unset or named a server that had stopped: the
    program only reported that it found no adapter.  It says why, once, on stderr."""
    exe = build_client(build_library())
    gone = tmp_path / "stopped"  # a server's private folder, removed when it stopped
    for env, said in (({}, "cheetah.so (BioTac emulator): BIOTAC_CHEETAH_SOCKET is not set: start `biotac-bench "
                            "cheetah serve` and export the line it prints\n"),
                      ({"BIOTAC_CHEETAH_SOCKET": str(tmp_path / "nothing.sock")},
                       f"not using BIOTAC_CHEETAH_SOCKET={tmp_path / 'nothing.sock'}: nothing is served there (is "
                       f"`biotac-bench cheetah serve` running?)\n"),
                      ({"BIOTAC_CHEETAH_SOCKET": str(gone / "cheetah.sock")},
                       f"not using BIOTAC_CHEETAH_SOCKET={gone / 'cheetah.sock'}: nothing is served there")):
        r = subprocess.run([str(exe), "1"], capture_output=True, text=True, env={**env, "PATH": "/usr/bin:/bin"},
                           timeout=30)
        assert r.returncode == 4 and "no Cheetah adapter found" in r.stderr, r.stderr
        assert said in r.stderr and r.stderr.count("cheetah.so (BioTac emulator)") == 1, r.stderr


def test_a_batch_of_just_over_an_hour_of_delays_is_refused():
    """README: one request may advance virtual time by at most an hour. A batch whose queued delays add up to 3602 s
    (an hour and two seconds, stated here rather than read from the server) ends the connection, the clock untouched."""
    with pytest.MonkeyPatch.context() as mp, cheetah_adapter(mp, 1, bitrate_khz=None) as (cb, lib, h):
        t0 = cb.t
        lib.c_ch_spi_queue_clear(h)
        for _ in range(1801):
            assert lib.c_ch_spi_queue_delay_ns(h, 2_000_000_000) == 2_000_000_000
        assert lib.c_ch_spi_batch_shift(h, 0, (C.c_uint8 * 1)()) < 0 and cb.t == t0
        assert any("of virtual time" in e for e in cb.client_errors), cb.client_errors


def test_a_request_past_an_hour_of_virtual_time_ends_the_connection_with_the_reason():
    """The sensors are simulated through every virtual second a program sleeps or queues, so one request may
    advance at most MAX_ADVANCE_S (3600 s): a 49-day ch_sleep_ms (it held the adapter, and Ctrl-C, for an hour) or a
    batch of delays past it ends that program's connection, the reason kept for the exit message; the adapter and
    its clock are untouched."""
    import time

    from bench.hosts.cheetah_server import MAX_ADVANCE_S

    for request in ("sleep", "batch"):
        with pytest.MonkeyPatch.context() as mp, cheetah_adapter(mp, 1, bitrate_khz=None) as (cb, lib, h):
            t0, wall = cb.t, time.monotonic()
            if request == "sleep":
                lib.c_ch_sleep_ms.restype = C.c_uint32
                assert lib.c_ch_sleep_ms(C.c_uint32(0xFFFFFFFF)) == 0  # the milliseconds slept: none
            else:
                lib.c_ch_spi_queue_clear(h)
                for _ in range(int(MAX_ADVANCE_S / 2.0) + 2):  # the API's delays are ints: ≤ 2.1 s each
                    assert lib.c_ch_spi_queue_delay_ns(h, 2_000_000_000) == 2_000_000_000
                buf = (C.c_uint8 * 1)()
                assert lib.c_ch_spi_batch_shift(h, 0, buf) < 0
            assert time.monotonic() - wall < 10 and cb.t == t0
            lib.c_ch_spi_queue_clear(h)
            lib.c_ch_spi_queue_delay_ns(h, 1000)
            assert lib.c_ch_spi_batch_shift(h, 0, (C.c_uint8 * 1)()) == -7  # CH_COMMUNICATION_ERROR from now on
            assert any(f"more than {MAX_ADVANCE_S:g} s of virtual time" in e for e in cb.client_errors)


def test_stop_returns_while_a_request_is_being_clocked():
    """Ctrl-C or SIGTERM stops the adapter even while a client's request holds the bench (its thread ends with the
    process): stop() never waits on that request's lock."""
    import time

    cb = CheetahBench(1).start()
    cb._lock.acquire()  # as a batch being clocked holds it
    try:
        t0 = time.monotonic()
        cb.stop()
        assert time.monotonic() - t0 < 2
    finally:
        cb._lock.release()


@pytest.mark.parametrize("bad", ["0", "-1", "ten", "3x", ""])
def test_the_example_client_refuses_a_batch_count_that_is_not_a_whole_number_from_1(bad):
    """``biotac_client -1`` printed "frames -5" and ``biotac_client ten`` ran no batch (atoi): now refused, naming
    the argument, before it looks for the adapter."""
    exe = build_client(build_library())
    r = subprocess.run([str(exe), bad], capture_output=True, text=True, timeout=30)
    assert r.returncode == 1 and r.stderr == f"batches: a whole number from 1 to 1000000, not {bad}\n", r.stderr
