"""The bridge firmware running against emulated sensors, behind a serial port anyone can open.

    with FirmwareBench(n_sensors=1) as fb:
        driver = BridgeDriver(fb.port)      # or: open fb.port with any serial program
        driver.start()
        for frame in driver.frames(100): ...

A background thread runs the firmware in virtual time in 10 ms steps, moving bytes between the pty and the
firmware's UART.  Faults are scheduled in virtual time (:meth:`at`) or applied at once (:meth:`now`); the
line itself can corrupt or drop bytes (``corrupt_rate``, ``drop_rate``).
"""

from __future__ import annotations

import queue
import random
import threading
import time

from bench.hosts.cosim import CoSim, VirtualBoard, default_sensors
from bench.hosts.serial_link import PtyLink


class FirmwareBench:
    def __init__(self, n_sensors: int = 1, stimuli=(), seed: int = 1, sensors=None, realtime: bool = False,
                 speed: float = 1.0, pull_up: bool = False, corrupt_rate: float = 0.0, drop_rate: float = 0.0,
                 step_s: float = 0.01, baudrate: int = 3_000_000, spi: str = "software"):
        self.link = PtyLink(baudrate)
        self.baudrate = baudrate
        self._line_free_at = 0.0  # wall time when the paced UART has sent everything so far
        self.port = self.link.path
        self._rng = random.Random(seed)
        self.corrupt_rate, self.drop_rate = corrupt_rate, drop_rate
        self.board = VirtualBoard(sensors or default_sensors(n_sensors, stimuli, seed), uart_out=self._line,
                                  pull_up=pull_up, spi=spi)
        self.sim = CoSim(self.board)
        self.realtime, self.speed, self.step_s = realtime, speed, step_s
        self._stop = threading.Event()
        self._requests: queue.Queue = queue.Queue()  # (virtual time or None, action): applied by the bench thread
        self._thread = threading.Thread(target=self._loop, name="firmware", daemon=True)
        self.error: BaseException | None = None
        self.bytes_corrupted = self.bytes_dropped = 0

    def _line(self, data: bytes) -> None:
        if self.corrupt_rate or self.drop_rate:
            out = bytearray()
            for b in data:
                r = self._rng.random()
                if r < self.drop_rate:
                    self.bytes_dropped += 1
                    continue
                if r < self.drop_rate + self.corrupt_rate:
                    b ^= 1 << self._rng.randrange(8)
                    self.bytes_corrupted += 1
                out.append(b)
            data = bytes(out)
        if self.realtime:  # a real UART sends 10 bits per byte at the baud rate: pace the line accordingly
            now = time.perf_counter()
            self._line_free_at = max(self._line_free_at, now) + len(data) * 10 / (self.baudrate * self.speed)
            if self._line_free_at > now:
                time.sleep(self._line_free_at - now)
        self.link.write(data)

    def _loop(self) -> None:
        wall0, virt0 = time.perf_counter(), self.board.t
        try:
            while not self._stop.is_set():
                self._take_requests()
                data = self.link.read_available()
                if data:
                    self.board.send_to_firmware(data)
                self.sim.run(self.step_s)
                if self.realtime:
                    ahead = (self.board.t - virt0) / self.speed - (time.perf_counter() - wall0)
                    if ahead > 0:
                        time.sleep(ahead)
        except BaseException as e:  # reported by stop()
            self.error = e

    def _take_requests(self) -> None:
        while True:
            try:
                when, action = self._requests.get_nowait()
            except queue.Empty:
                return
            if when is None:
                action(self.board)
            else:
                self.board.at(when, action)

    def at(self, t_s: float, action) -> None:
        """Apply ``action(board)`` when virtual time reaches ``t_s`` (never blocks the caller)."""
        self._requests.put((t_s, action))

    def now(self, action) -> None:
        """Apply ``action(board)`` before the firmware's next step (never blocks the caller)."""
        self._requests.put((None, action))

    @property
    def virtual_time(self) -> float:
        return self.board.t

    def start(self) -> "FirmwareBench":
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=10)
        self.link.close()
        self.board.bus.close()
        if self.error is not None:
            raise RuntimeError(f"the firmware bench stopped with an error: {self.error!r}") from self.error

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()
