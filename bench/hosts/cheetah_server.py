"""The emulated Cheetah adapter behind the Cheetah-compatible library (emulator/cheetah/cheetah_emu.c).

``CheetahBench`` builds ``cheetah.so`` (cached), serves a Unix socket in a private folder, and clocks every queue
a client shifts through the emulated sensors' SPI bus in virtual time.  A program built against Total Phase's
public header and loader runs unmodified with the built ``cheetah.so`` beside it and ``BIOTAC_CHEETAH_SOCKET``
pointing at the bench (``bench.env``; ``biotac-bench cheetah serve`` prints the line to export).

How it behaves like the device
    *One client per adapter.*  The first program that opens it owns it until it closes (or dies); meanwhile
    ``ch_find_devices`` reports the port ORed with ``CH_PORT_NOT_FREE`` and ``ch_open`` fails with
    ``CH_UNABLE_TO_OPEN`` — as a second open of a real adapter does.

    *Private socket.*  The socket lives in a fresh folder of mode 0700: under ``$XDG_RUNTIME_DIR`` when that is
    a private folder of this user, else a ``mkdtemp`` folder; the library refuses sockets in folders that are
    not private or served by another user, and there is no default path.

    *Timing.*  Bytes are clocked at the configured bit rate; queued delays and ``ch_sleep_ms`` advance time
    exactly.  The adapter's own overheads (model choices, taken from the delay formula of SynTouch's published
    Cheetah host code, which budgets them): every queued slave-select command occupies one byte slot,
    :data:`SELECT_CYCLES` = 8 SCK periods, before the lines change; every run of bytes under one select costs
    :data:`TRANSFER_OVERHEAD_S` = 750 ns beyond its bits (set-up before the first clock and hold after the
    last).  With the vendor's per-sample queue (6 select commands, 4 runs of 2 bytes, 3 delays) a sample costs
    its delays + 112 SCK periods + 3 µs — what the formula assumes, so it yields the 4400 Hz it asks for.

    *The host and the adapter run in parallel.*  The adapter's time (the bus) and the host's time advance
    separately: a batch starts when it is submitted (or shifted) and the bus is free; ``ch_sleep_ms`` advances
    the host's time only; collecting a batch (or a synchronous shift) makes the host wait for its end.
    :attr:`t` is the host's time.

    *SPI settings.*  The sensors are mode 0 (sample MOSI on the rising edge, shift MISO on the falling edge,
    first bit at chip-select fall), MSB first, active-low selects.  The adapter clocks as configured and the
    bus shows what that does: LSB first reverses every byte each way; phase 1 with idle-low clock (mode 1)
    changes MOSI on the rising edge the sensor samples on, so the sensor reads each bit one late (MOSI shifted
    by one bit); mode 3 (idle-high, sample on the trailing rising edge) samples MISO after the sensor's first
    falling-edge shift (MISO shifted by one bit); mode 2 samples MISO on the edge the sensor shifts it, and
    gets the old bit (the sensor's output changes ~45 ns after the edge), so it happens to read correctly, as
    on a real bus; an active-high select line (``ss_polarity`` bit set) is asserted when the host thinks it
    idle, so the sensors see the complement of every select code (``code ^ ss_polarity``).

    *Clean teardown.*  Whatever clients send, the bench keeps serving the others; a malformed request ends
    that client's connection and is recorded in :attr:`client_errors`; :meth:`stop` closes every connection,
    joins every thread and removes the folder, and never raises.
"""

from __future__ import annotations

import os
import select
import shutil
import socket
import stat
import struct
import tempfile
import threading
from collections import deque
from pathlib import Path

import numpy as np

from bench.hosts.scene_sensors import bench_sensors
from bench.hosts.native import build_folder, compile_c
from bench.paths import REPO
from bench.scenes.limits import SPI_SIDES, SPI_SIDES_SAID
from emulator.spi.model import Bus, SensorPort, Transfer

LIBRARY_SOURCE = REPO / "emulator" / "cheetah" / "cheetah_emu.c"
CLIENT_SOURCE = REPO / "firmware_tests" / "cheetah_client" / "biotac_client.c"
VENDOR_RATE_CLIENT_SOURCE = REPO / "firmware_tests" / "cheetah_client" / "vendor_rate_client.c"
OP_SS, OP_BYTES, OP_DELAY_NS, OP_OE = 1, 2, 3, 4
REQ_SHIFT, REQ_SLEEP, REQ_HELLO, REQ_QUERY, REQ_SUBMIT, REQ_COLLECT = 1, 2, 3, 4, 5, 6
#: The largest request a client may send (bytes): 1 MiB, 1.9 s of SPI at 4.4 MHz (a BioTac frame is ~100 bytes).
MAX_REQUEST_BYTES = 1 << 20
#: The most virtual time one request (a sleep, or a batch with its delays) may advance (s): the emulated sensors
#: are simulated through all of it, at ~1000× real time, so a 49-day ch_sleep_ms would hold the adapter for an hour.
MAX_ADVANCE_S = 3600.0
UNIQUE_ID = 1365000042

#: Every queued slave-select command occupies one byte slot of the adapter's shift engine (SCK periods).
SELECT_CYCLES = 8
#: Every run of bytes shifted under one select costs this much beyond its bits (s): set-up and hold.
TRANSFER_OVERHEAD_S = 750e-9
#: A batch's slave-select polarity bits: 1 = that line is active high (the sensors' selects are active low).
MODE_CPOL, MODE_CPHA, MODE_LSB = 1, 2, 4
#: How long (wall s) :meth:`CheetahBench.stop` waits for each client's thread to end (a request still being clocked)
#: before it ends the RTL harness under it (:meth:`emulator.rtl.harness.RtlBus.stop_process`).
CLIENT_STOP_S = 5.0


class ProtocolError(Exception):
    """A client sent something the library never sends: its connection is closed."""


def build_library(out_dir: Path | None = None) -> Path:
    """Compile cheetah.so into its own folder (cached by the library's and clients' sources); returns its path."""
    folder = build_folder(out_dir or REPO / "out" / "cheetah",
                          [LIBRARY_SOURCE, CLIENT_SOURCE, VENDOR_RATE_CLIENT_SOURCE])
    return compile_c([LIBRARY_SOURCE], folder / "cheetah.so", flags=("-D_DEFAULT_SOURCE", "-shared", "-fPIC"),
                     what="cheetah.so")


def private_folder() -> str:
    """A fresh folder only this user can enter (0700): under $XDG_RUNTIME_DIR if that is private, else mkdtemp."""
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    if runtime:
        try:
            st = os.stat(runtime)
            if stat.S_ISDIR(st.st_mode) and st.st_uid == os.getuid() and not st.st_mode & 0o077 \
                    and len(runtime) + len("/biotac-cheetah-") + 8 + len("/cheetah.sock") < 108:  # sun_path room
                return tempfile.mkdtemp(prefix="biotac-cheetah-", dir=runtime)
        except OSError:
            pass
    return tempfile.mkdtemp(prefix="biotac-cheetah-")


def _reverse_bits(b: int) -> int:
    return int(f"{b:08b}"[::-1], 2)


_REVERSED = bytes(_reverse_bits(b) for b in range(256))


class _Plan:
    """One queue, planned: transfers relative to the batch's start, its duration, the select state it leaves."""

    def __init__(self, steps, clock, mode, duration, final):
        self.steps, self.clock, self.mode, self.duration, self.final = steps, clock, mode, duration, final
        self.words = None
        if mode == 0 and steps and all(st[3] == 16 for st in steps):
            self.words = (np.array([st[0] for st in steps]), np.array([st[1] for st in steps], dtype=np.int64),
                          np.array([st[2] for st in steps], dtype=np.uint16), np.array([st[4] for st in steps]))


class _Client:
    def __init__(self, conn: socket.socket):
        self.conn = conn
        self.owner = False
        self.gone = False  # the program closed its end (exited): what it left unread here is not served
        self.results: deque[tuple[bytes, float]] = deque()  # submitted batches: (MISO, end time)
        self.thread: threading.Thread | None = None


class CheetahBench:
    """Emulated sensors behind the Cheetah-compatible library: ``with CheetahBench(3) as cb: ...``.

    ``trace=True`` keeps every transfer clocked on the bus in :attr:`trace` as (start s, select code the sensors
    see, bits, MOSI the sensors received).

    ``spi``: the sensors' SPI side — "software" (the Python model, the default) or "rtl" (the Verilog twin in the
    C++ Verilator harness, :class:`emulator.rtl.harness.RtlBus`, stopped by :meth:`stop`), which the adapter clocks
    the same transfers through.  Over the RTL a batch in SPI mode 3 is refused (a client error, its connection
    ended): the bench gives the host the sensor's first MISO bit, driven before the first clock edge, from the
    sensor's port state, which the RTL harness does not expose; modes 0–2 and LSB first are served.
    """

    def __init__(self, n_sensors: int = 1, stimuli=(), seed: int = 0, sensors=None, trace: bool = False,
                 variant: str = "biotac", spi: str = "software", request_wait_s: float | None = None):
        if not isinstance(trace, (bool, np.bool_)):
            raise ValueError(f"trace = {trace!r}: must be True or False")
        if request_wait_s is not None and not (isinstance(request_wait_s, (int, float)) and not isinstance(
                request_wait_s, bool) and 0 < request_wait_s <= 3600):
            raise ValueError(f"request_wait_s = {request_wait_s!r}: wall seconds, more than 0 and at most 3600")
        #: how long (wall s) :meth:`stop` waits for a request still being clocked (None: :data:`CLIENT_STOP_S`)
        self.request_wait_s = request_wait_s
        trace = bool(trace)
        if spi not in SPI_SIDES:
            raise ValueError(f"spi = {spi!r}: {SPI_SIDES_SAID}")
        sensors = bench_sensors(n_sensors, sensors, stimuli, seed, variant)  # variant: "biotac" or "biotac-sp"
        self.library = build_library()
        self.lib_dir = self.library.parent
        self.spi = spi
        if spi == "rtl":  # built (or refused) before the socket's folder exists
            from emulator.rtl.harness import RtlBus

            self.bus = RtlBus(sensors)
        else:
            self.bus = Bus({n: SensorPort(s, n) for n, s in sensors.items()})
        try:
            self._tmp = private_folder()
        except BaseException:  # (no folder to make: the RTL's harness process is not left running)
            self.bus.close()
            raise
        self.socket_path = os.path.join(self._tmp, "cheetah.sock")
        self.t_host = 0.0  # the host program's time (s)
        self.t_bus = 0.0  # when the adapter's bus is free
        self.batches = 0
        self.trace: list | None = [] if trace else None
        self.client_errors: list[str] = []
        # the adapter's state on the bus, carried from batch to batch
        self._host_ss = 0  # the select code the host asked for last
        self._bus_open = False  # a chip-select window is open on the bus (with code _bus_code)
        self._bus_code = 0
        self._mosi_last = 0  # the last bit the adapter drove on MOSI (it holds the line)
        self._plans: dict = {}  # (queue, starting select state) -> _Plan, most recently used last
        self._lock = threading.Lock()
        self._owner: _Client | None = None
        self._clients: list[_Client] = []
        self._server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            self._server.bind(self.socket_path)
            os.chmod(self.socket_path, 0o600)
        except BaseException:  # nothing left behind: the RTL's harness process, the socket's folder
            self._server.close()
            self.bus.close()
            shutil.rmtree(self._tmp, ignore_errors=True)
            raise
        self._server.listen(8)
        self._server.settimeout(0.2)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="cheetah-server", daemon=True)
        self._stopped = False
        #: what :meth:`stop` had to do beyond a clean stop, in one line (None: nothing): a client's request still
        #: being clocked over the RTL after that wait (:meth:`stop`), its harness process ended under it
        self.stop_problem: str | None = None

    @property
    def t(self) -> float:
        """The host's time (s): what queued delays, shifts, collects and ``ch_sleep_ms`` have advanced."""
        return self.t_host

    @property
    def env(self) -> dict:
        """Environment for a client process: where the library finds this bench."""
        return {**os.environ, "BIOTAC_CHEETAH_SOCKET": self.socket_path}

    @property
    def in_use(self) -> bool:
        return self._owner is not None

    def _release_if_closed(self) -> None:
        """Free the adapter if its owner has closed its end of the connection, whatever it left unread here (call
        with the lock held, before each request): a real Cheetah is free once the program that opened it exits,
        its pending asynchronous batches dropped, while this server would otherwise clock every batch still
        queued before it saw the end, and refuse the next program meanwhile."""
        owner = self._owner
        if owner is None:
            return
        poller = select.poll()
        hangup = select.POLLHUP | getattr(select, "POLLRDHUP", 0)
        poller.register(owner.conn, hangup)
        if any(events & hangup for _, events in poller.poll(0)):
            owner.gone, owner.owner, self._owner = True, False, None

    # --- serving ------------------------------------------------------------------------
    def _serve(self):
        while not self._stop.is_set():
            try:
                conn, _ = self._server.accept()
            except socket.timeout:
                continue
            except OSError:
                return
            client = _Client(conn)
            client.thread = threading.Thread(target=self._client, args=(client,), name="cheetah-client", daemon=True)
            with self._lock:
                self._clients.append(client)
            client.thread.start()

    def _client(self, c: _Client):
        conn = c.conn
        try:
            while not self._stop.is_set() and not c.gone:
                head = self._recv(conn, 5)
                if head is None:
                    return
                kind, length = head[0], struct.unpack("<I", head[1:])[0]
                if length > MAX_REQUEST_BYTES:
                    raise ProtocolError(f"request of {length} bytes")
                payload = self._recv(conn, length) if length else b""
                if payload is None:
                    return
                reply = self._handle(c, kind, payload)
                if reply is not None:
                    conn.sendall(struct.pack("<I", len(reply)) + reply)
                if kind == REQ_HELLO and not c.owner:
                    return  # refused: another program has the adapter
        except (ProtocolError, ValueError, struct.error, IndexError) as e:
            self.client_errors.append(f"{type(e).__name__}: {e}")
        except OSError:
            pass  # the client went away mid-request
        except Exception as e:  # noqa: BLE001 - whatever a client caused ends its connection, not the bench
            self.client_errors.append(f"{type(e).__name__}: {e}")
        finally:
            with self._lock:
                if self._owner is c:
                    self._owner = None
                if c in self._clients:
                    self._clients.remove(c)
            try:
                conn.close()
            except OSError:
                pass

    def _handle(self, c: _Client, kind: int, payload: bytes) -> bytes | None:
        with self._lock:
            self._release_if_closed()  # first: whoever asks, an exited program's adapter is free at once
            if c.gone:  # its program has exited and another may hold the adapter now: nothing more is done for it
                return None
            if kind == REQ_QUERY:
                return bytes([self._owner is not None]) + struct.pack("<I", UNIQUE_ID)
            if kind == REQ_HELLO:
                if self._owner is None:
                    self._owner, c.owner = c, True
                    return b"\x00"
                return b"\x01"
            if not c.owner:
                raise ProtocolError(f"request {kind} before opening the adapter")
            if kind == REQ_SLEEP:
                if len(payload) != 4:
                    raise ProtocolError("sleep needs 4 bytes")
                ms = struct.unpack("<I", payload)[0]
                if ms * 1e-3 > MAX_ADVANCE_S:
                    raise ProtocolError(f"ch_sleep_ms({ms}): more than {MAX_ADVANCE_S:g} s of virtual time in one "
                                        f"request (the sensors are simulated through all of it)")
                self.t_host += ms * 1e-3
                return b""
            if kind == REQ_SHIFT:
                miso, end = self.execute(payload, max(self.t_host, self.t_bus))
                self.t_bus = self.t_host = end
                return miso
            if kind == REQ_SUBMIT:  # starts now (when the bus is free); the host does not wait
                miso, end = self.execute(payload, max(self.t_host, self.t_bus))
                self.t_bus = end
                c.results.append((miso, end))
                return None
            if kind == REQ_COLLECT:
                if not c.results:
                    raise ProtocolError("collect with nothing submitted")
                miso, end = c.results.popleft()
                self.t_host = max(self.t_host, end)
                return miso
            raise ProtocolError(f"unknown request type {kind}")

    @staticmethod
    def _recv(conn, n):
        buf = bytearray()
        while len(buf) < n:
            chunk = conn.recv(n - len(buf))
            if not chunk:
                return None
            buf += chunk
        return bytes(buf)

    # --- the queue -> SPI transfers ------------------------------------------------------------
    def execute(self, payload: bytes, start: float) -> tuple[bytes, float]:
        """Clock one batch from ``start`` (s); returns (the MISO bytes the host receives, when the batch ends).

        Hosts submit the same queue over and over: its plan (transfers relative to the batch's start, and the
        select state it leaves) is computed once per queue and starting state, then shifted in time."""
        key = (payload, self._host_ss, self._bus_open, self._bus_code)
        plan = self._plans.pop(key, None)
        if plan is None:
            plan = self._make_plan(payload)
        self._plans[key] = plan  # most recent last
        while len(self._plans) > 16:
            del self._plans[next(iter(self._plans))]
        self._host_ss, self._bus_open, self._bus_code = plan.final
        self.batches += 1
        return self._clock(plan, start), start + plan.duration

    def _make_plan(self, payload: bytes) -> "_Plan":
        if len(payload) < 6:
            raise ProtocolError("batch header truncated")
        rate_khz, mode, ss_pol = struct.unpack_from("<IBB", payload)
        if not 1 <= rate_khz <= 1_000_000 or mode > 7:
            raise ProtocolError(f"bit rate {rate_khz} kHz, mode {mode}")
        ss_pol &= 7
        clock = rate_khz * 1e3
        T = 1.0 / clock
        after_run = max(0.5 * T, TRANSFER_OVERHEAD_S)
        select_slot = SELECT_CYCLES * T
        steps: list[tuple] = []  # (start relative to the batch, select code, MOSI, bits, keep chip select)
        t = 0.0
        pending: list | None = None  # [start, code, bytearray]
        sel: tuple[float, int] | None = None  # a select change the bus has not seen yet
        host_ss, bus_open, bus_code = self._host_ss, self._bus_open, self._bus_code
        cur = (host_ss ^ ss_pol) & 7  # the code the sensors see
        if cur != (bus_code if bus_open else 0):
            sel = (t, cur)

        def emit_select(when: float, code: int):
            nonlocal bus_open, bus_code, t
            steps.append((when, code, 0, 0, code != 0))
            bus_open, bus_code = code != 0, code
            t = max(t, when + 0.5 * T)  # the bus holds a select change for half an SCK period (Transfer.end_s)

        def flush(keep: bool):
            nonlocal pending, t, bus_open, bus_code
            p0, code, data = pending
            keep = keep and code != 0
            steps.append((p0, code, int.from_bytes(bytes(data), "big"), 8 * len(data), keep))
            bus_open, bus_code = keep, code
            t = p0 + 8 * len(data) * T + after_run
            pending = None

        i, n = 6, len(payload)
        unpack = struct.unpack_from
        while i < n:
            if i + 5 > n:
                raise ProtocolError("queue record truncated")
            kind, value = unpack("<BI", payload, i)
            i += 5
            if kind == OP_SS:
                if value > 7:
                    raise ProtocolError(f"select code {value}")
                new = (value ^ ss_pol) & 7
                if pending is not None:
                    flush(keep=new != 0)
                t += select_slot  # the select command's byte slot; the lines change at its end
                host_ss, cur = value, new
                sel = (t, cur) if cur != (bus_code if bus_open else 0) else None
            elif kind == OP_BYTES:
                if value == 0 or i + value > n:
                    raise ProtocolError("byte record truncated")
                data = payload[i:i + value]
                i += value
                if pending is None:
                    sel = None  # the transfer itself changes the select at its start
                    pending = [t, cur, bytearray()]
                pending[2] += data
            elif kind == OP_DELAY_NS:
                if pending is not None:
                    flush(keep=cur != 0)
                if sel is not None:
                    emit_select(*sel)
                    sel = None
                t += value * 1e-9
            elif kind == OP_OE:
                pass  # output enable: the lines stay driven (the sensors see no difference)
            else:
                raise ProtocolError(f"queue record kind {kind}")
        if pending is not None:
            flush(keep=cur != 0)
        if sel is not None:
            emit_select(*sel)
        if t > MAX_ADVANCE_S:
            raise ProtocolError(f"a batch lasting {t:.6g} s: more than {MAX_ADVANCE_S:g} s of virtual time in one "
                                f"request (the sensors are simulated through all of it)")
        return _Plan(steps, clock, mode, t, (host_ss, bus_open, bus_code))

    def _clock(self, plan: "_Plan", start: float) -> bytes:
        if not plan.steps:
            return b""
        mode, clock = plan.mode, plan.clock
        if self.spi == "rtl" and mode & (MODE_CPOL | MODE_CPHA) == MODE_CPOL | MODE_CPHA:
            raise ProtocolError("SPI mode 3 over the RTL: not served (the sensor's first MISO bit, driven before the "
                                "first clock edge, is read from its port's state, which the RTL harness does not "
                                "expose); use mode 0, the sensors' own, or the software SPI side")
        if plan.words is not None:  # word traffic in mode 0: the vectorized path
            rel, cs, mosi, keep = plan.words
            starts = rel + start
            if self.trace is not None:
                self.trace.extend(zip(starts.tolist(), cs.tolist(), [16] * len(cs), mosi.tolist()))
            miso = self.bus.exchange_words(starts, cs, mosi, np.full(len(cs), clock), keep)
            self._mosi_last = int(mosi[-1]) & 1
            return miso.astype(">u2").tobytes()
        out = bytearray()
        for rel, code, mosi, nbits, keep in plan.steps:
            t0 = start + rel
            if not nbits:
                if self.trace is not None:
                    self.trace.append((t0, code, 0, 0))
                self.bus.transfer(Transfer(t0, code, 0, 0, clock, keep))
                continue
            n = nbits // 8
            if mode & MODE_LSB:  # the adapter shifts each byte LSB first: the sensors assemble it reversed
                mosi = int.from_bytes(mosi.to_bytes(n, "big").translate(_REVERSED), "big")
            host_last = mosi & 1
            if mode & (MODE_CPOL | MODE_CPHA) == MODE_CPHA:  # mode 1: the sensor samples each bit one late
                mosi = (self._mosi_last << (nbits - 1)) | (mosi >> 1)
            self._mosi_last = host_last
            mode3 = mode & (MODE_CPOL | MODE_CPHA) == MODE_CPOL | MODE_CPHA
            wire = Transfer(t0, code, mosi, nbits, clock, True if mode3 else keep)
            if self.trace is not None:
                self.trace.append((wire.start_s, wire.cs, wire.nbits, wire.mosi))
            bits = self.bus.transfer(wire)
            if mode3:  # the first falling edge (the leading one) shifts MISO before the first sample
                selected = self.bus.selected_by(code)
                nxt = 0
                for k in selected:
                    nxt |= self.bus.ports[k].miso_bit(self.bus.ports[k].position)
                if not selected:
                    nxt = int(self.bus.pull_up)
                bits = ((bits << 1) | nxt) & ((1 << nbits) - 1)
                if not keep:
                    self.bus.transfer(Transfer(wire.end_s, 0, 0, 0, clock))
            data = bits.to_bytes(n, "big")
            if mode & MODE_LSB:
                data = data.translate(_REVERSED)
            out += data
        return bytes(out)

    # --- lifetime -------------------------------------------------------------------------
    def start(self) -> "CheetahBench":
        self._thread.start()
        return self

    def stop(self) -> None:
        """Close every connection, join every thread (:attr:`request_wait_s`, else :data:`CLIENT_STOP_S`, each at most), remove the socket's folder;
        never raises and never waits on the lock a busy request holds.  A client still busy clocking a request after
        that: over the RTL its harness process is ended under it (SIGTERM, then SIGKILL: no Verilator process
        outlives the bench), the request fails, and :attr:`stop_problem` says so; over the software model its
        thread, a daemon, is left to end with the process."""
        if self._stopped:
            return
        self._stopped = True
        self._stop.set()
        try:
            self._server.close()
        except OSError:
            pass
        if self._thread.is_alive():
            self._thread.join(timeout=5)
        clients = list(self._clients)  # not under the lock: a request being clocked holds it
        for c in clients:
            try:
                c.conn.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        others = [c.thread for c in clients if c.thread is not None and c.thread is not threading.current_thread()]
        wait_s = CLIENT_STOP_S if self.request_wait_s is None else self.request_wait_s
        for thread in others:
            thread.join(timeout=wait_s)
        busy = [thread for thread in others if thread.is_alive()]
        if busy and self.spi == "rtl":  # the harness process is ended under the request: it fails, its thread ends
            pid, how = self.bus.proc.pid, self.bus.stop_process()
            for thread in busy:
                thread.join(timeout=CLIENT_STOP_S)
            ended = f"was {how} under it" if how else "had exited already"
            self.stop_problem = (f"{len(busy)} client request(s) still being clocked {wait_s:g} s after "
                                 f"stop(): the RTL harness process (pid {pid}) {ended}")
        if not any(c.thread is not None and c.thread.is_alive() for c in clients):  # (none still clocking it)
            self.bus.close()  # the RTL's harness process, if any
        shutil.rmtree(self._tmp, ignore_errors=True)

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()


def build_client(library: Path) -> Path:
    """Compile the example client beside ``library`` (a :func:`build_library` result): it loads cheetah.so
    from its own folder, as programs using the vendor's loader do."""
    return compile_c([CLIENT_SOURCE], Path(library).parent / "biotac_client", libs=("-ldl", "-lm"),
                     what="the Cheetah example client")


def build_vendor_rate_client(library: Path) -> Path:
    """Compile the client that paces its samples with SynTouch's published delay formula (beside ``library``)."""
    return compile_c([VENDOR_RATE_CLIENT_SOURCE], Path(library).parent / "vendor_rate_client", libs=("-ldl",),
                     what="the vendor-formula Cheetah client")
