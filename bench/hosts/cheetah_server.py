"""The emulator behind the Cheetah-compatible library (emulator/cheetah/cheetah_emu.c).

``CheetahBench`` builds ``cheetah.so`` (cached), serves a Unix socket, and clocks every queue a client
shifts through the emulated sensors' SPI bus in virtual time: slave-select changes open and close chip-select
windows (a change from one select code to another with nothing in between is the vendor library's way of
reading sensors back to back), bytes are clocked at the configured bit rate, queued delays and
``ch_sleep_ms`` advance time exactly.  A program built against Total Phase's public header and loader runs
unmodified with the built ``cheetah.so`` beside it and ``BIOTAC_CHEETAH_SOCKET`` pointing at the bench.
"""

from __future__ import annotations

import os
import shutil
import socket
import struct
import tempfile
import threading
from pathlib import Path

import numpy as np

from bench.hosts.cosim import default_sensors
from bench.hosts.native import build_folder, compile_c
from bench.paths import REPO
from emulator.spi.model import Bus, SensorPort, Transfer

LIBRARY_SOURCE = REPO / "emulator" / "cheetah" / "cheetah_emu.c"
CLIENT_SOURCE = REPO / "firmware_tests" / "cheetah_client" / "biotac_client.c"
OP_SS, OP_BYTES, OP_DELAY_NS, OP_OE = 1, 2, 3, 4
REQ_SHIFT, REQ_SLEEP, REQ_HELLO = 1, 2, 3


def build_library(out_dir: Path | None = None) -> Path:
    """Compile cheetah.so into its own folder (cached by the library's and client's sources); returns its path."""
    folder = build_folder(out_dir or REPO / "out" / "cheetah", [LIBRARY_SOURCE, CLIENT_SOURCE])
    return compile_c([LIBRARY_SOURCE], folder / "cheetah.so", flags=("-D_DEFAULT_SOURCE", "-shared", "-fPIC"),
                     what="cheetah.so")


class CheetahBench:
    """Emulated sensors behind the Cheetah-compatible library: ``with CheetahBench(3) as cb: ...``."""

    def __init__(self, n_sensors: int = 1, stimuli=(), seed: int = 1, sensors=None):
        self.library = build_library()
        self.lib_dir = self.library.parent
        self._tmp = tempfile.mkdtemp(prefix="biotac-cheetah-")
        self.socket_path = os.path.join(self._tmp, "cheetah.sock")
        self.bus = Bus({n: SensorPort(s, n) for n, s in (sensors or default_sensors(n_sensors, stimuli, seed)).items()})
        self.t = 0.0
        self.ss = 0
        self.window_open = False
        self.batches = 0
        self._server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self._server.bind(self.socket_path)
        self._server.listen(4)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="cheetah-server", daemon=True)
        self.error: BaseException | None = None

    @property
    def env(self) -> dict:
        """Environment for a client process: where the library finds this bench."""
        return {**os.environ, "BIOTAC_CHEETAH_SOCKET": self.socket_path}

    # --- serving ------------------------------------------------------------------------
    def _serve(self):
        self._server.settimeout(0.2)
        while not self._stop.is_set():
            try:
                conn, _ = self._server.accept()
            except socket.timeout:
                continue
            except OSError:
                return
            threading.Thread(target=self._client, args=(conn,), daemon=True).start()

    def _client(self, conn):
        with conn:
            try:
                while True:
                    head = self._recv(conn, 5)
                    if head is None:
                        return
                    kind, length = head[0], struct.unpack("<I", head[1:])[0]
                    payload = self._recv(conn, length) if length else b""
                    if kind == REQ_SHIFT:
                        reply = self.execute(payload)
                    elif kind == REQ_SLEEP:
                        self.t += struct.unpack("<I", payload)[0] * 1e-3
                        reply = b""
                    else:
                        reply = b""
                    conn.sendall(struct.pack("<I", len(reply)) + reply)
            except Exception as e:  # reported by stop(); the client sees a communication error
                self.error = e

    @staticmethod
    def _recv(conn, n):
        buf = b""
        while len(buf) < n:
            chunk = conn.recv(n - len(buf))
            if not chunk:
                return None
            buf += chunk
        return buf

    # --- the queue -> SPI transfers ------------------------------------------------------------
    def execute(self, payload: bytes) -> bytes:
        rate_khz = struct.unpack_from("<I", payload)[0]
        clock = rate_khz * 1e3
        transfers: list[Transfer] = []
        pending: list | None = None  # [start, cs, bytearray]
        t = self.t

        def flush(keep: bool):
            nonlocal pending, t
            if pending is not None:
                data = bytes(pending[2])
                tr = Transfer(pending[0], pending[1], int.from_bytes(data, "big"), 8 * len(data), clock, keep)
                transfers.append(tr)
                t = tr.end_s
                self.window_open = keep and pending[1] != 0
                pending = None

        i = 4
        while i < len(payload):
            kind, value = payload[i], struct.unpack_from("<I", payload, i + 1)[0]
            i += 5
            if kind == OP_SS:
                if value != self.ss:
                    if pending is not None:
                        flush(keep=value != 0)
                    elif value == 0 and self.window_open:  # release a window held open from before
                        transfers.append(Transfer(t, 0, 0, 0, clock))
                        t = transfers[-1].end_s
                        self.window_open = False
                    self.ss = value
            elif kind == OP_BYTES:
                data = payload[i:i + value]
                i += value
                if pending is None:
                    pending = [t, self.ss, bytearray()]
                pending[2] += data
            elif kind == OP_DELAY_NS:
                flush(keep=self.ss != 0)
                t += value * 1e-9
        flush(keep=self.ss != 0)
        self.t = max(t, self.t)
        self.batches += 1
        return self._clock(transfers)

    def _clock(self, transfers: list[Transfer]) -> bytes:
        if not transfers:
            return b""
        if all(tr.nbits == 16 for tr in transfers):  # word traffic: the vectorized path
            miso = self.bus.exchange_words(np.array([tr.start_s for tr in transfers]),
                                           np.array([tr.cs for tr in transfers]),
                                           np.array([tr.mosi for tr in transfers], dtype=np.uint16),
                                           np.array([tr.clock_hz for tr in transfers]),
                                           np.array([tr.keep_cs for tr in transfers]))
            return miso.astype(">u2").tobytes()
        out = bytearray()
        for tr in transfers:
            bits = self.bus.transfer(tr)
            if tr.nbits:
                out += bits.to_bytes(tr.nbits // 8, "big")
        return bytes(out)

    # --- lifetime -------------------------------------------------------------------------
    def start(self) -> "CheetahBench":
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._server.close()
        self._thread.join(timeout=5)
        shutil.rmtree(self._tmp, ignore_errors=True)
        if self.error is not None:
            raise RuntimeError(f"the Cheetah bench failed: {self.error!r}") from self.error

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()


def build_client(library: Path) -> Path:
    """Compile the example client beside ``library`` (a :func:`build_library` result): it loads cheetah.so
    from its own folder, as programs using the vendor's loader do."""
    return compile_c([CLIENT_SOURCE], Path(library).parent / "biotac_client", libs=("-ldl", "-lm"),
                     what="the Cheetah example client")
