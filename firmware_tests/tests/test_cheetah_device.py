"""The emulated Cheetah adapter behaves like the device (issue 12, item 5): one client at a time, an error code
(never SIGPIPE) when the server dies, a private socket, clean teardown whatever clients did, a command that
serves it, adapter overheads that make SynTouch's own delay formula sample at 4400 Hz, wrong SPI settings that
garble the bus, asynchronous batches that start when submitted."""

import ctypes as C
import os
import signal
import socket
import stat
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from bench.hosts import cheetah_server as cs
from bench.hosts.cheetah_server import CheetahBench, build_client, build_library, build_vendor_rate_client
from bench.paths import REPO
from bench.tests.host_benches import open_adapter, read_serial
from emulator.spi import protocol as proto
from emulator.spi.model import PROP_SERIAL

pytestmark = pytest.mark.firmware
CH_COMMUNICATION_ERROR, CH_UNABLE_TO_OPEN, CH_SPI_ASYNC_PENDING = -7, -8, -104


@pytest.fixture
def lib(monkeypatch):
    """cheetah.so loaded in this process; closes whatever handle a test leaves open."""
    lib = C.CDLL(str(build_library()))
    yield lib, monkeypatch
    lib.c_ch_close(1)


def sample_words(lib, h, commands=(0x80, 0x83, 0x86)) -> list[int]:
    """Each command to sensor 1, 50 µs, then its response word."""
    out = []
    for cmd in commands:
        buf = (C.c_uint8 * 4)()
        lib.c_ch_spi_queue_clear(h)
        lib.c_ch_spi_queue_ss(h, 1)
        lib.c_ch_spi_queue_array(h, 2, (C.c_uint8 * 2)(cmd, 0))
        lib.c_ch_spi_queue_ss(h, 0)
        lib.c_ch_spi_queue_delay_ns(h, 60000)
        lib.c_ch_spi_queue_ss(h, 1)
        lib.c_ch_spi_queue_byte(h, 2, 0)
        lib.c_ch_spi_queue_ss(h, 0)
        lib.c_ch_spi_queue_delay_ns(h, 20000)
        assert lib.c_ch_spi_batch_shift(h, 4, buf) == 4
        out.append(buf[2] << 8 | buf[3])
    return out


def odd(b):
    return bin(b).count("1") % 2 == 1


# --- one client per adapter ------------------------------------------------------------------------------------


def test_a_second_program_cannot_open_an_adapter_in_use_and_can_once_it_is_closed(lib):
    lib, mp = lib
    with CheetahBench(1) as cb:
        h = open_adapter(lib, mp, cb)
        assert lib.c_ch_open(0) == CH_UNABLE_TO_OPEN  # a second open in the same program
        exe = build_client(cb.library)
        r = subprocess.run([str(exe), "1"], capture_output=True, text=True, env=cb.env, timeout=60)
        assert r.returncode == 4 and "cannot open the adapter (-8)" in r.stderr  # another program: refused
        ports = (C.c_uint16 * 1)()
        assert lib.c_ch_find_devices(1, ports) == 1 and ports[0] == 0x8000  # CH_PORT_NOT_FREE | port 0
        assert read_serial(lib, h).startswith(b"BT0101EMU0000001")  # the owner is not disturbed
        assert lib.c_ch_close(h) == 0
        r = subprocess.run([str(exe), "2"], capture_output=True, text=True, env=cb.env, timeout=60)
        assert r.returncode == 0, r.stderr
        assert cb.client_errors == []


# --- a dead server: an error code, never a signal ------------------------------------------------------------


def serve(*args):
    p = subprocess.Popen([sys.executable, "-m", "bench.cli", "cheetah", "serve", *map(str, args)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO)
    line = p.stdout.readline()
    assert line.startswith("export BIOTAC_CHEETAH_SOCKET="), (line, p.stderr.read() if p.poll() is not None else "")
    path = line.split("=", 1)[1].strip().strip("'")
    return p, path


def test_a_server_killed_mid_stream_gives_the_client_an_error_code_not_sigpipe():
    p, path = serve("--sensors", "3")
    try:
        exe = build_client(build_library())
        client = subprocess.Popen([str(exe), "100000"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                  env={**os.environ, "BIOTAC_CHEETAH_SOCKET": path})
        time.sleep(2.0)  # streaming asynchronous batches by now
        assert client.poll() is None
        p.kill()  # SIGKILL: no goodbye
        out, err = client.communicate(timeout=60)
    finally:
        p.kill()
        p.wait()
    assert client.returncode == 5, (client.returncode, err)  # its own error exit; -13 would be SIGPIPE
    assert "batch failed: -7 (communication error" in err


def test_every_call_after_the_server_went_away_returns_communication_error(lib):
    lib, mp = lib
    cb = CheetahBench(1).start()
    h = open_adapter(lib, mp, cb)
    cb.stop()
    buf = (C.c_uint8 * 4)()
    lib.c_ch_spi_queue_clear(h)
    lib.c_ch_spi_queue_byte(h, 2, 0x80)
    assert lib.c_ch_spi_async_submit(h) in (0, CH_COMMUNICATION_ERROR)  # the write may still be buffered
    assert lib.c_ch_spi_batch_shift(h, 4, buf) in (CH_COMMUNICATION_ERROR, CH_SPI_ASYNC_PENDING)
    lib.c_ch_spi_async_collect(h, 4, buf)
    assert lib.c_ch_spi_batch_shift(h, 4, buf) == CH_COMMUNICATION_ERROR
    assert lib.c_ch_close(h) == 0


# --- the socket: private, never shared ------------------------------------------------------------------------


def test_the_socket_lives_in_a_private_folder_and_the_library_has_no_shared_default(tmp_path, monkeypatch):
    runtime = tmp_path / "run"
    runtime.mkdir(mode=0o700)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(runtime))
    with CheetahBench(1) as cb:
        folder = Path(cb.socket_path).parent
        assert folder.parent == runtime and stat.S_IMODE(folder.stat().st_mode) == 0o700
        assert stat.S_IMODE(Path(cb.socket_path).stat().st_mode) == 0o600
    assert not folder.exists()
    runtime.chmod(0o755)  # not private: not used
    with CheetahBench(1) as cb:
        assert not Path(cb.socket_path).is_relative_to(runtime)
        assert stat.S_IMODE(Path(cb.socket_path).parent.stat().st_mode) == 0o700
    src = (REPO / "emulator" / "cheetah" / "cheetah_emu.c").read_text()
    assert "/tmp/" not in src  # no fixed fallback path


def test_the_library_refuses_a_socket_in_a_folder_others_can_enter(tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir(mode=0o755)
    shared.chmod(0o755)
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    server.bind(str(shared / "cheetah.sock"))
    server.listen(1)
    try:
        exe = build_client(build_library())
        env = {"BIOTAC_CHEETAH_SOCKET": str(shared / "cheetah.sock"), "PATH": "/usr/bin:/bin"}
        r = subprocess.run([str(exe), "1"], capture_output=True, text=True, env=env, timeout=30)
    finally:
        server.close()
    assert r.returncode == 4 and "no Cheetah adapter found" in r.stderr
    assert "must be yours and private" in r.stderr


# --- clean teardown whatever clients did ----------------------------------------------------------------------


def test_teardown_is_clean_after_garbage_half_requests_and_open_clients(lib):
    lib, mp = lib
    cb = CheetahBench(2).start()
    rng = np.random.default_rng(5)
    socks = []
    for k in range(12):  # garbage of every kind
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.connect(cb.socket_path)
        if k % 4 == 0:
            s.sendall(rng.integers(0, 256, 200, dtype=np.uint8).tobytes())
        elif k % 4 == 1:
            s.sendall(bytes([cs.REQ_SHIFT]) + struct.pack("<I", 0xFFFFFFF0))  # absurd length
        elif k % 4 == 2:
            s.sendall(bytes([cs.REQ_HELLO, 0, 0, 0, 0]) + bytes([cs.REQ_SHIFT]) + struct.pack("<I", 9) + b"\x01\x02")
        else:
            batch = struct.pack("<IBB", 4400, 0, 0) + b"\x09\x00\x00\x00\x00"  # an unknown queue record
            s.sendall(bytes([cs.REQ_SHIFT]) + struct.pack("<I", len(batch)) + batch)
        socks.append(s)
    time.sleep(0.3)
    h = open_adapter(lib, mp, cb) if not cb.in_use else None  # a half request may still hold the adapter
    threads_before = threading.active_count()
    cb.stop()  # never raises
    assert cb.client_errors  # the garbage was noticed
    assert not Path(cb.socket_path).parent.exists()
    time.sleep(0.2)
    assert threading.active_count() <= threads_before
    assert not any(t.name.startswith("cheetah") for t in threading.enumerate())
    for s in socks:
        s.close()
    if h:
        lib.c_ch_close(h)


# --- biotac-bench cheetah serve ----------------------------------------------------------------------------------


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_cheetah_serve_prints_the_line_to_export_serves_and_stops_cleanly(sig, tmp_path):
    scene = tmp_path / "quiet.toml"
    scene.write_text('[scene]\nname = "quiet"\nduration_s = 10\nseed = 4\n[noise]\njohnson = false\n'
                     'amplifier = false\nmains_hum = false\nadc = false\nspi_coupling = false\n')
    p, path = serve(scene, "--sensors", "2")
    try:
        assert stat.S_IMODE(Path(path).parent.stat().st_mode) == 0o700
        exe = build_client(build_library())
        r = subprocess.run([str(exe), "5"], capture_output=True, text=True, timeout=120,
                           env={**os.environ, "BIOTAC_CHEETAH_SOCKET": path})
        assert r.returncode == 0, r.stderr
        stats = dict(zip(r.stdout.split()[-10::2], r.stdout.split()[-9::2]))
        assert float(stats["pac_std"]) < 0.3  # the scene's noise switches reached the sensors
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as bad:  # one request past the 1 MiB limit
            bad.connect(path)
            bad.sendall(bytes([cs.REQ_SHIFT]) + struct.pack("<I", cs.MAX_REQUEST_BYTES + 1))
            bad.settimeout(10)
            assert bad.recv(1) == b""  # the server ended that connection
        p.send_signal(sig)
        out, err = p.communicate(timeout=30)
    finally:
        p.kill()
    assert p.returncode == 0 and "stopped:" in err and "Traceback" not in err
    # README: malformed requests end that connection, listed and printed when `cheetah serve` stops
    assert "1 client connection(s) ended for malformed requests" in err
    assert f"request of {cs.MAX_REQUEST_BYTES + 1} bytes" in err
    assert not Path(path).parent.exists()


def test_a_request_of_1_mib_is_read_and_one_byte_more_refused():
    """README: one request is at most 1 MiB: a 1 MiB shift (0xEE bytes here) from an opened adapter is read whole and
    judged on its content (a bit rate of 0xEEEEEEEE kHz), one of 1 MiB + 1 bytes is refused for its length alone."""
    assert cs.MAX_REQUEST_BYTES == 1 << 20
    with CheetahBench(1) as cb:
        for length in (cs.MAX_REQUEST_BYTES, cs.MAX_REQUEST_BYTES + 1):
            with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
                s.connect(cb.socket_path)
                s.settimeout(10)
                s.sendall(bytes([cs.REQ_HELLO]) + struct.pack("<I", 0))
                assert s.recv(64)  # the adapter is this connection's
                s.sendall(bytes([cs.REQ_SHIFT]) + struct.pack("<I", length))
                if length == cs.MAX_REQUEST_BYTES:
                    s.sendall(bytes([0xEE]) * length)
                assert s.recv(1) == b""
        deadline = time.monotonic() + 10
        while len(cb.client_errors) < 2 and time.monotonic() < deadline:
            time.sleep(0.05)
        errors = list(cb.client_errors)
    assert len(errors) == 2 and f"bit rate {0xEEEEEEEE} kHz" in errors[0], errors
    assert f"request of {cs.MAX_REQUEST_BYTES + 1} bytes" in errors[1]


# --- timing: the vendor's own formula yields its rate ----------------------------------------------------------


def vendor_rate(monkeypatch=None, batches=6) -> tuple[float, str]:
    with CheetahBench(3, trace=True) as cb:
        exe = build_vendor_rate_client(cb.library)
        r = subprocess.run([str(exe), str(batches)], capture_output=True, text=True, env=cb.env, timeout=300)
        assert r.returncode == 0, r.stderr
        starts = np.array([t for t, code, nbits, mosi in cb.trace if code == 7 and nbits == 16])
    assert len(starts) == batches * 5 * 44
    return 1.0 / np.diff(starts).mean(), r.stdout


def test_synTouchs_delay_formula_samples_at_4400_hz():
    """The vendor's padding (227 273 − 112 SCK periods − 63 µs = 138 818 ns at 4.4 MHz) plus what the adapter
    spends
    (its bits, 8 SCK periods per select command, 750 ns per run of bytes) is 1/4400 s."""
    rate, out = vendor_rate()
    assert "additional_ns 138818 frames_per_batch 5" in out
    assert rate == pytest.approx(4400, rel=0.01)
    assert rate == pytest.approx(4400, abs=0.5)  # in fact exact
    assert "parity_errors 0" in out


def test_without_the_adapter_overheads_the_formula_would_run_fast(monkeypatch):
    """The issue's figure: an adapter that charged nothing for selects and transfers gave 4677 Hz."""
    monkeypatch.setattr(cs, "SELECT_CYCLES", 0)
    monkeypatch.setattr(cs, "TRANSFER_OVERHEAD_S", 0.0)
    rate, _ = vendor_rate(batches=2)
    assert rate == pytest.approx(4677, rel=0.002)


# --- wrong SPI settings garble the bus --------------------------------------------------------------------------


@pytest.mark.parametrize("polarity,phase,bitorder,ss_pol,garbled", [
    (0, 0, 0, 0, False),  # mode 0, MSB first, active low: the sensors' own settings
    (1, 0, 0, 0, False),  # mode 2: every sample races the sensor's shift, and the old bit wins (as on a real bus)
    (0, 1, 0, 0, True),  # mode 1: the sensor reads MOSI one bit late
    (1, 1, 0, 0, True),  # mode 3: the host reads MISO one bit early
    (0, 0, 1, 0, True),  # LSB first
    (0, 0, 0, 1, True),  # SS0 active high
    (0, 0, 0, 4, True),  # SS2 active high: sensor 1's select code 6 drives SS1 and SS2
])
def test_spi_settings_the_sensors_do_not_use_garble_the_traffic(lib, polarity, phase, bitorder, ss_pol, garbled):
    lib, mp = lib
    with CheetahBench(1) as cb:
        h = open_adapter(lib, mp, cb)
        assert lib.c_ch_spi_configure(h, polarity, phase, bitorder, ss_pol) == 0
        serial = read_serial(lib, h)
        words = sample_words(lib, h)
        lib.c_ch_close(h)
    good = serial.startswith(b"BT0101EMU0000001") and all(
        (w >> 8) != 0xA5 and odd(w >> 8) and odd(w & 0xFF) for w in words)
    assert good == (not garbled), (serial, [hex(w) for w in words])
    if not garbled:
        assert abs(((words[0] >> 9) * 32 + ((words[0] & 0xFF) >> 3)) - 2048) < 20  # PAC at rest


def test_an_invalid_configuration_is_refused(lib):
    lib, mp = lib
    with CheetahBench(1) as cb:
        h = open_adapter(lib, mp, cb)
        assert lib.c_ch_spi_configure(h, 2, 0, 0, 0) == -11  # CH_CONFIG_ERROR


# --- asynchronous batches start at submit ------------------------------------------------------------------------


def test_a_delay_in_cycles_lasts_that_many_periods_of_the_bit_clock(lib):
    """ch_spi_queue_delay_cycles(n) idles the bus n clock periods: at 1000 kHz, 1000 cycles last 1 ms, as
    delay_ns(1 000 000) does; at 4000 kHz a quarter of that."""
    lib, mp = lib
    with CheetahBench(1) as cb:
        h = open_adapter(lib, mp, cb)
        buf = (C.c_uint8 * 1)()
        for khz, expected_s in ((1000, 1e-3), (4000, 0.25e-3)):
            assert lib.c_ch_spi_bitrate(h, khz) == khz
            lib.c_ch_spi_queue_clear(h)
            assert lib.c_ch_spi_queue_delay_cycles(h, 1000) == 1000
            t0 = cb.t
            lib.c_ch_spi_batch_shift(h, 0, buf)
            assert cb.t - t0 == pytest.approx(expected_s, abs=2e-6), khz


def test_an_async_batch_starts_when_submitted_not_when_collected(lib):
    lib, mp = lib
    with CheetahBench(1, trace=True) as cb:
        h = open_adapter(lib, mp, cb)
        t0 = cb.t
        lib.c_ch_spi_queue_clear(h)
        lib.c_ch_spi_queue_ss(h, 1)
        lib.c_ch_spi_queue_array(h, 2, (C.c_uint8 * 2)(0x80, 0))
        lib.c_ch_spi_queue_ss(h, 0)
        lib.c_ch_spi_queue_delay_ns(h, 1_000_000)  # the batch lasts ~1 ms
        assert lib.c_ch_spi_async_submit(h) == 0
        lib.c_ch_sleep_ms(100)  # the host does something else meanwhile
        buf = (C.c_uint8 * 4)()
        assert lib.c_ch_spi_batch_shift(h, 4, buf) == CH_SPI_ASYNC_PENDING  # as on the device: collect first
        assert lib.c_ch_spi_async_collect(h, 4, buf) == 2
        started = [t for t, code, nbits, mosi in cb.trace if nbits == 16][0]
        assert started - t0 < 1e-5  # it ran during the sleep, not after it
        assert cb.t == pytest.approx(t0 + 0.1, abs=1e-9)  # the batch ended long before the host collected it
        # a batch longer than the sleep: collecting waits for its end
        lib.c_ch_spi_queue_clear(h)
        lib.c_ch_spi_queue_delay_ns(h, 300_000_000)
        lib.c_ch_spi_async_submit(h)
        lib.c_ch_sleep_ms(100)
        lib.c_ch_spi_async_collect(h, 0, buf)
        assert cb.t == pytest.approx(t0 + 0.1 + 0.3, abs=1e-5)


@pytest.mark.parametrize("split", ["across batches", "a short delay in one batch"])
def test_a_select_asserted_before_the_bytes_is_held_for_half_a_clock_period(lib, split):
    """A program that asserts the select in a batch of its own (or with a delay shorter than half an SCK period
    before its bytes) then sends a sampling command and reads its answer: the bus holds a select change for half a
    period, so the bytes start after it — the answer is PDC's data word, never a dropped client
    (-7, "starts before the previous one ended", found by a helper's hunt)."""
    lib, mp = lib
    with CheetahBench(1) as cb:
        h = open_adapter(lib, mp, cb)

        def shift(n, *ops):
            buf = (C.c_uint8 * max(n, 1))()
            lib.c_ch_spi_queue_clear(h)
            for op, *args in ops:
                getattr(lib, f"c_ch_spi_queue_{op}")(h, *args)
            return lib.c_ch_spi_batch_shift(h, n, buf), bytes(buf)[:n]

        if split == "across batches":
            assert shift(0, ("ss", 1))[0] == 0
            assert shift(2, ("byte", 1, 0x83), ("byte", 1, 0), ("ss", 0), ("delay_ns", 60000))[0] == 2
        else:
            assert shift(2, ("ss", 1), ("delay_ns", 50), ("byte", 1, 0x83), ("byte", 1, 0), ("ss", 0),
                         ("delay_ns", 60000))[0] == 2
        got, word = shift(2, ("ss", 1), ("byte", 2, 0), ("ss", 0))
        assert got == 2 and cb.client_errors == []
        value, ok = proto.decode_response(word[0] << 8 | word[1])
        assert ok and not proto.is_error_word(word[0] << 8 | word[1]) and 100 < value < 4000  # PDC at rest
        lib.c_ch_close(h)


# --- conformance with the Cheetah API (the vendor's cheetah.h and user manual) ----------------------------------


def test_a_cycle_delay_past_a_u32_of_nanoseconds_lasts_every_cycle_it_returns(lib):
    """ch_spi_queue_delay_cycles returns the cycles queued (cheetah.h): 500 000 cycles at 100 kHz are 5 s, which
    the library once held as u32 nanoseconds and wrapped to 0.705 s while returning 500 000."""
    lib, mp = lib
    with CheetahBench(1) as cb:
        h = open_adapter(lib, mp, cb, bitrate_khz=None)
        khz = lib.c_ch_spi_bitrate(h, 100)  # the slowest the adapter runs at
        lib.c_ch_spi_queue_clear(h)
        assert lib.c_ch_spi_queue_delay_cycles(h, 500_000) == 500_000
        t0 = cb.t
        assert lib.c_ch_spi_batch_shift(h, 0, (C.c_uint8 * 1)()) == 0
        assert cb.t - t0 == pytest.approx(500_000 / (khz * 1e3), abs=1e-6)


def test_the_bit_rate_returned_is_the_one_the_bus_runs_at(lib):
    """A request past the manual's top rate (40 MHz, 50 MHz overclocked) is answered with the rate the adapter
    set, and delays in cycles then last periods of that rate, not of the one asked for; so for 1 kHz. Our choices
    (README): 1000 kHz after open (asking 0 reports the rate), clamped to 100–40 000 kHz."""
    lib, mp = lib
    with CheetahBench(1) as cb:
        h = open_adapter(lib, mp, cb, bitrate_khz=None)
        assert lib.c_ch_spi_bitrate(h, 0) == 1000
        for asked, clamped in ((100_000, 40_000), (1, 100)):
            khz = lib.c_ch_spi_bitrate(h, asked)
            assert khz == clamped and lib.c_ch_spi_bitrate(h, 0) == clamped
            lib.c_ch_spi_queue_clear(h)
            lib.c_ch_spi_queue_delay_cycles(h, 4000)
            t0 = cb.t
            lib.c_ch_spi_batch_shift(h, 0, (C.c_uint8 * 1)())
            assert cb.t - t0 == pytest.approx(4000 / (khz * 1e3), rel=1e-6), asked


def rev(b: int) -> int:
    return int(f"{b:08b}"[::-1], 2)


def test_lsb_first_shifts_every_byte_bit_0_first_both_ways(lib):
    """CH_SPI_BITORDER_LSB (cheetah.h) is a setting the adapter takes: a host that reverses each byte's bits
    itself talks to the MSB-first sensors exactly, and reads their answer reversed."""
    lib, mp = lib
    with CheetahBench(1) as cb:
        h = open_adapter(lib, mp, cb)
        assert lib.c_ch_spi_configure(h, 0, 0, 1, 0) == 0
        buf = (C.c_uint8 * 20)()
        lib.c_ch_spi_queue_clear(h)
        lib.c_ch_spi_queue_ss(h, 1)
        lib.c_ch_spi_queue_array(h, 2, (C.c_uint8 * 2)(rev(0x61), rev(PROP_SERIAL)))  # read the serial number
        lib.c_ch_spi_queue_ss(h, 0)
        lib.c_ch_spi_queue_delay_ns(h, 60000)
        lib.c_ch_spi_queue_ss(h, 1)
        lib.c_ch_spi_queue_byte(h, 18, 0)
        lib.c_ch_spi_queue_ss(h, 0)
        assert lib.c_ch_spi_batch_shift(h, 20, buf) == 20
    assert bytes(rev(b) for b in buf[2:]).startswith(b"BT0101EMU0000001")


def test_target_power_query_returns_the_state_and_leaves_it(lib):
    """CH_TARGET_POWER_QUERY (0x80, cheetah.h) asks for the target power state; ON (1) and OFF (0) set it."""
    lib, mp = lib
    with CheetahBench(1) as cb:
        h = open_adapter(lib, mp, cb)
        for flag in (1, 0):
            assert lib.c_ch_target_power(h, flag) == flag
            assert lib.c_ch_target_power(h, 0x80) == flag
            assert lib.c_ch_target_power(h, 0x80) == flag


def test_a_shift_writes_no_more_of_data_in_than_num_bytes(lib):
    """A buffer shorter than the batch gets num_bytes bytes and nothing past them (the vendor's bindings cut
    data_in to num_bytes the same way); the return counts what was written."""
    lib, mp = lib
    with CheetahBench(1) as cb:
        h = open_adapter(lib, mp, cb)
        buf = (C.c_uint8 * 8)(*[0xEE] * 8)
        lib.c_ch_spi_queue_clear(h)
        lib.c_ch_spi_queue_byte(h, 6, 0)  # nothing selected: the idle line
        assert lib.c_ch_spi_batch_length(h) == 6
        assert lib.c_ch_spi_batch_shift(h, 2, buf) == 2
        assert bytes(buf[2:]) == b"\xee" * 6 and bytes(buf[:2]) != b"\xee\xee"
        assert lib.c_ch_spi_batch_shift(h, 0, None) == 0


def test_async_submissions_past_the_limit_are_refused_and_none_is_lost(lib):
    """Past the adapter's limit of outstanding batches (64: our choice, README) ch_spi_async_submit answers
    CH_SPI_ASYNC_MAX_REACHED (-105) and sends nothing: every accepted batch is collected, then CH_SPI_ASYNC_EMPTY
    (-103)."""
    lib, mp = lib
    with CheetahBench(1) as cb:
        h = open_adapter(lib, mp, cb)
        lib.c_ch_spi_queue_clear(h)
        lib.c_ch_spi_queue_byte(h, 2, 0)
        codes = [lib.c_ch_spi_async_submit(h) for _ in range(200)]
        accepted = codes.index(-105)
        assert accepted == 64 and set(codes[:accepted]) == {0} and set(codes[accepted:]) == {-105}
        buf = (C.c_uint8 * 2)()
        assert [lib.c_ch_spi_async_collect(h, 2, buf) for _ in range(accepted)] == [2] * accepted
        assert lib.c_ch_spi_async_collect(h, 2, buf) == -103
        assert lib.c_ch_spi_async_submit(h) == 0 and lib.c_ch_spi_async_collect(h, 2, buf) == 2
        assert cb.client_errors == []


FIND_DEVICES = ("import ctypes as C, sys\n"
                "lib = C.CDLL(sys.argv[1])\n"
                "ports, ids = (C.c_uint16 * 2)(), (C.c_uint32 * 2)()\n"
                "print(lib.c_ch_find_devices_ext(2, ports, 2, ids), ports[0], ids[0], lib.c_ch_find_devices(0, None))\n")


def test_another_program_finds_the_adapter_marked_in_use_while_it_is_open(lib):
    """cheetah.h: ports in use are ORed with CH_PORT_NOT_FREE (0x8000), and the count is of the devices found,
    whatever the array's size — seen from a second program, which asks the adapter."""
    lib, mp = lib
    with CheetahBench(1) as cb:
        def find():
            r = subprocess.run([sys.executable, "-c", FIND_DEVICES, str(cb.library)], capture_output=True,
                               text=True, env=cb.env, timeout=60)
            assert r.returncode == 0, r.stderr
            return r.stdout.split()

        assert find() == ["1", "0", str(cs.UNIQUE_ID), "1"]
        h = open_adapter(lib, mp, cb)
        assert find() == ["1", str(0x8000), str(cs.UNIQUE_ID), "1"]
        assert lib.c_ch_close(h) == 0
        assert find() == ["1", "0", str(cs.UNIQUE_ID), "1"]


SLEEP_AFTER_SERVER = ("import ctypes as C, signal, sys\n"
                      "signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # as in a C program\n"
                      "lib = C.CDLL(sys.argv[1])\n"
                      "lib.c_ch_sleep_ms.restype = C.c_uint32\n"
                      "assert lib.c_ch_open(0) == 1\n"
                      "print('open', flush=True)\n"
                      "sys.stdin.readline()\n"
                      "print(lib.c_ch_sleep_ms(5), lib.c_ch_sleep_ms(5), lib.c_ch_spi_queue_byte(1, 1, 0),\n"
                      "      lib.c_ch_spi_batch_shift(1, 0, None))\n")


def test_sleep_once_the_server_is_gone_slept_nothing_and_raises_no_sigpipe():
    """ch_sleep_ms returns the milliseconds slept (cheetah.h): with the adapter gone it slept none and says 0,
    and the program, SIGPIPE at its default, lives on to get CH_COMMUNICATION_ERROR from the next shift."""
    cb = CheetahBench(1).start()
    try:
        p = subprocess.Popen([sys.executable, "-c", SLEEP_AFTER_SERVER, str(cb.library)], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=cb.env)
        assert p.stdout.readline() == "open\n"
    finally:
        cb.stop()
    out, err = p.communicate("\n", timeout=60)
    assert p.returncode == 0, (p.returncode, err)  # -13 would be SIGPIPE
    assert out.split() == ["0", "0", "1", str(CH_COMMUNICATION_ERROR)]


def test_a_select_change_between_bytes_ends_one_sensors_exchange_and_starts_the_next(lib):
    """ch_spi_queue_ss sets every line at once (cheetah.h): moving from sensor 1's select to sensor 2's between
    bytes of one batch deselects sensor 1 and sends the following bytes to sensor 2 — each reads its own serial."""
    lib, mp = lib
    with CheetahBench(2) as cb:
        h = open_adapter(lib, mp, cb)
        lib.c_ch_spi_queue_clear(h)
        for sel in (1, 2):
            lib.c_ch_spi_queue_ss(h, sel)
            lib.c_ch_spi_queue_array(h, 2, (C.c_uint8 * 2)(0x61, PROP_SERIAL))
        lib.c_ch_spi_queue_ss(h, 0)
        lib.c_ch_spi_queue_delay_ns(h, 60000)
        for sel in (1, 2):
            lib.c_ch_spi_queue_ss(h, sel)
            lib.c_ch_spi_queue_byte(h, 18, 0)
        lib.c_ch_spi_queue_ss(h, 0)
        buf = (C.c_uint8 * 40)()
        assert lib.c_ch_spi_batch_shift(h, 40, buf) == 40
        assert cb.client_errors == []
    assert bytes(buf[4:22]).startswith(b"BT0101EMU0000001") and bytes(buf[22:]).startswith(b"BT0101EMU0000002")


SUBMIT_AND_EXIT = ("import ctypes as C, sys\n"
                   "lib = C.CDLL(sys.argv[1])\n"
                   "h = lib.c_ch_open(0)\n"
                   "assert h == 1, h\n"
                   "print('opened', flush=True)\n"
                   "sys.stdin.readline()\n"
                   "lib.c_ch_spi_queue_clear(h)\n"
                   "for _ in range(150):  # 10 min of virtual time before each sample\n"
                   "    lib.c_ch_spi_queue_delay_ns(h, 4_000_000_000)\n"
                   "lib.c_ch_spi_queue_ss(h, 1)\n"
                   "lib.c_ch_spi_queue_array(h, 2, (C.c_uint8 * 2)(0x80, 0))\n"
                   "lib.c_ch_spi_queue_ss(h, 0)\n"
                   "assert [lib.c_ch_spi_async_submit(h) for _ in range(64)] == [0] * 64\n"
                   "print('submitted', flush=True)\n")  # and exits: no collect, no close


def test_a_program_that_exits_with_batches_pending_frees_the_adapter_at_once(lib):
    """A real Cheetah is free as soon as the program that opened it exits, its pending asynchronous batches
    dropped.  A program opens the adapter, submits 64 batches of 10 min of virtual time each while the server is
    busy (its lock held, as while clocking a batch) and exits: none of them is clocked afterwards, and the next
    program opens the adapter at once.  (Before, the server clocked every batch left — ten hours of virtual time,
    seconds of wall time — and refused the next program, −8, meanwhile.)  Deterministic: the batches are all
    waiting when the server looks at the first of them."""
    lib, mp = lib
    with CheetahBench(1) as cb:
        prog = subprocess.Popen([sys.executable, "-c", SUBMIT_AND_EXIT, str(cb.library)], stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=cb.env)
        try:
            assert prog.stdout.readline() == "opened\n", prog.stderr.read()
            with cb._lock:  # the program's batches wait in the socket until it has exited
                out, err = prog.communicate("go\n", timeout=60)
        finally:
            if prog.poll() is None:
                prog.kill()
        assert prog.returncode == 0 and out == "submitted\n", err
        deadline = time.monotonic() + 10
        while cb._clients and time.monotonic() < deadline:  # the server ends the exited program's connection
            time.sleep(0.01)
        # at its first batch after the exit: the adapter is free and none of its 64 batches was clocked
        assert not cb._clients and not cb.in_use and cb.batches == 0 and cb.client_errors == []
        h = open_adapter(lib, mp, cb)  # asserts the handle: not CH_UNABLE_TO_OPEN
        assert len(sample_words(lib, h)) == 3 and cb.batches == 3  # the next program is served as usual
        assert cb.client_errors == []
