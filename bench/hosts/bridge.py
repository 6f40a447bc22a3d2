"""The bridge firmware running against emulated sensors, behind a serial port anyone can open.

    with FirmwareBench(n_sensors=1) as fb:
        driver = BridgeDriver(fb.port)      # or: open fb.port with any serial program
        driver.start()
        for frame in driver.frames(100): ...

A background thread runs the firmware in virtual time in 10 ms steps, moving bytes between the pty and the
firmware's UART.  Faults are scheduled in virtual time (:meth:`at`) or applied at once (:meth:`now`); the
line itself can corrupt or drop bytes (``corrupt_rate``, ``drop_rate``).

``firmware=``: the firmware to run — None (the reference bridge firmware), your C sources (a list of paths, built
with :func:`bench.hosts.cosim.build_firmware`, headers beside them part of the build's key) or a library you built;
it must export ``bt_bridge_size``, ``bt_init``, ``bt_step`` and ``bt_set_pattern`` (``bt_bridge.h``).  A firmware
whose ``bt_step`` never returns is reported by :meth:`stop` (a :class:`~bench.errors.FirmwareError`) after
:data:`STOP_TIMEOUT_S` of wall time (time the process spends compiling the emulator's numba kernels, as a fresh
clone's first steps do, not counted).  A bench whose firmware thread ended with an error (the firmware crashed or
called exit, a HAL call it made was refused, a scheduled action raised) says so at the first call after —
:meth:`at`, :meth:`now`, :attr:`virtual_time`, or else :meth:`stop` — naming the virtual time it ended at; every
later call but :meth:`stop` says it again (:meth:`overrun_frames` still reads what the host was sent).

The host's side of the link is a finite receive buffer (:class:`bench.hosts.serial_link.PtyLink`, 4096 bytes by
default, ``rx_buffer=``).  Paced to the wall clock (``realtime=True``, what ``biotac-bench bridge`` does), it
behaves like a UART without flow control: bytes arrive at the baud rate, and a host that does not read in time
loses what does not fit (an overrun) while the firmware streams on; ``overrun_frames()`` lists the frames that
lost bytes.  Unpaced (``realtime=False``, the default for tests), virtual time has no relation to the host's
clock, so the firmware waits for a host that is reading (back-pressure: nothing is lost however slow the host);
a host that has not read for :data:`HOST_GONE_S` (``host_gone_s=``: raise it for a host that may stall longer,
e.g. on a loaded CI machine) is taken as gone, and bytes overrun as in real time.

Sample times: the wire carries no time, but the bench knows when each slot was sampled.  :meth:`sample_times` gives,
for a data frame a host read, the virtual time (s from power-on) of each slot's sample — the instant its sampling
command ended on the bus and the sensor's conversion started; ``BridgeDriver(bench.port,
sample_times=bench.sample_times)`` puts them in every frame's ``t_s``.

Virtual time, and so every stimulus and scheduled fault, counts from power-on (t = 0, when the bench starts).
Unpaced, it stands still at the end of the firmware's start-up until the host sends its first byte (usually
START): however long the host takes to open the port and set up, it finds the sensors as at power-on, so a tap
scripted at 0.5 s comes ≈ 0.5 s into the stream, and the same host commands give the same frames on every run
(and over the software and the RTL SPI).  Paced to the wall clock, time runs from power-on as on a real bench.
"""

from __future__ import annotations

import math
import numbers
import queue
import random
import threading
import time

import numpy as np

from bench.errors import BenchError, FirmwareError
from bench.hosts.compile_clock import join_outside_compiles
from bench.hosts.cosim import CoSim, VirtualBoard, firmware_library, run_action
from bench.hosts.driver import DataFrame, FrameParser
from bench.hosts.scene_sensors import bench_sensors
from bench.hosts.serial_link import RX_BUFFER_BYTES, PtyLink

#: Unpaced, a host whose receive buffer has stayed full this long (wall s) is taken as gone (bytes overrun).
HOST_GONE_S = 0.2
#: Unpaced, before the host's first byte: how often (wall s) the bench looks for it (virtual time stands still).
HOST_POLL_S = 0.002
#: How long (wall s) stop() waits for the firmware to end its step before it reports a hung firmware; time spent
#: compiling the emulator's numba kernels (a fresh clone's first steps) does not count
#: (:func:`bench.hosts.compile_clock.join_outside_compiles`).
STOP_TIMEOUT_S = 10.0
#: The sample times of this many of the latest data frames are kept (:meth:`FirmwareBench.sample_times`): 40 s of
#: 44-slot frames, and fewer than the 65 536 sequence numbers, so a frame's number never finds another's times.
SAMPLE_TIMES_FRAMES = 4096


def _check_action(what: str, action) -> None:
    if not callable(action):
        raise ValueError(f"{what}: action = {action!r}: give a callable taking the board, e.g. "
                         f"lambda board: board.unplug(2)")


class FirmwareBench:
    def __init__(self, n_sensors: int = 1, stimuli=(), seed: int = 0, sensors=None, realtime: bool = False,
                 speed: float = 1.0, pull_up: bool = False, corrupt_rate: float = 0.0, drop_rate: float = 0.0,
                 step_s: float = 0.01, baudrate: int = 3_000_000, spi: str = "software",
                 rx_buffer: int = RX_BUFFER_BYTES, keep_arrivals: bool = False, pattern=None,
                 variant: str = "biotac", host_gone_s: float = HOST_GONE_S, firmware=None):
        if not (isinstance(speed, (int, float)) and math.isfinite(speed) and speed > 0):
            raise ValueError(f"speed = {speed!r}: must be a number > 0 (virtual seconds per wall second)")
        for name, flag in (("realtime", realtime), ("pull_up", pull_up), ("keep_arrivals", keep_arrivals)):
            if not isinstance(flag, (bool, np.bool_)):  # "no" is truthy: it would have turned the flag on
                raise ValueError(f"{name} = {flag!r}: must be True or False")
        realtime, pull_up, keep_arrivals = bool(realtime), bool(pull_up), bool(keep_arrivals)  # (numpy's too)
        if not (isinstance(baudrate, int) and baudrate > 0):
            raise ValueError(f"baudrate = {baudrate!r}: must be a whole number > 0")
        if not (isinstance(host_gone_s, (int, float)) and not isinstance(host_gone_s, bool)
                and math.isfinite(host_gone_s) and host_gone_s > 0):
            raise ValueError(f"host_gone_s = {host_gone_s!r}: must be a number > 0 (wall seconds)")
        # a zero, negative or NaN step never advanced the firmware (the host read nothing, without a word), and a
        # rate outside 0..1 corrupted every byte or none: refused before anything is built
        if not (isinstance(step_s, (int, float)) and not isinstance(step_s, bool) and math.isfinite(step_s)
                and step_s > 0):
            raise ValueError(f"step_s = {step_s!r}: must be a number > 0 (the firmware's virtual-time step, s)")
        for name, rate in (("corrupt_rate", corrupt_rate), ("drop_rate", drop_rate)):
            if not (isinstance(rate, (int, float)) and not isinstance(rate, bool) and 0 <= rate <= 1):
                raise ValueError(f"{name} = {rate!r}: must be a probability per byte, 0 to 1")
        if corrupt_rate + drop_rate > 1:
            raise ValueError(f"corrupt_rate + drop_rate = {corrupt_rate + drop_rate:g}: together at most 1 (each byte "
                             f"is dropped, corrupted or sent as it is)")
        sensors = bench_sensors(n_sensors, sensors, stimuli, seed, variant)
        library = firmware_library(firmware)  # built (or refused) before a pty or an RTL harness exists
        self.link = PtyLink(baudrate, rx_buffer=rx_buffer, keep_arrivals=keep_arrivals)
        self.baudrate = baudrate
        self._line_free_at = 0.0  # wall time when the paced UART has sent everything so far
        self.host_gone_s = host_gone_s
        self._host_gone = False  # unpaced: the buffer stayed full for host_gone_s (no more waiting until it drains)
        self.port = self.link.path
        self._sent = FrameParser()  # the firmware's own bytes, before the line's faults: its data frames' times
        self._frame_times: dict[int, np.ndarray] = {}  # sequence number -> each slot's sample time (s)
        self._rng = random.Random(seed)
        self.corrupt_rate, self.drop_rate = corrupt_rate, drop_rate
        # (set before the firmware's bt_init runs: what it sends the host at start-up goes through _line)
        self.realtime, self.speed, self.step_s = realtime, speed, step_s
        self._stop = threading.Event()
        self.board = None
        try:
            self.board = VirtualBoard(sensors, uart_out=self._line, pull_up=pull_up, spi=spi)
            self.board.command_ends = []
            self.sim = CoSim(self.board, library)
            if pattern is not None:
                self.sim.set_pattern(pattern)
        except BaseException:  # a refused pattern, a library that does not load: nothing left open behind it
            self.link.close()
            if self.board is not None:
                self.board.bus.close()
            raise
        self._requests: queue.Queue = queue.Queue()  # (virtual time or None, action): applied by the bench thread
        self._thread = threading.Thread(target=self._loop, name="firmware", daemon=True)
        self.error: BaseException | None = None
        self._error_at = 0.0  # the virtual time (s) when the firmware's thread ended with error
        self._error_told = False  # a call raised error already (stop() then does not again)
        self.bytes_corrupted = self.bytes_dropped = 0

    def _line(self, data: bytes) -> None:
        self._time_frames(data)
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
                self._sleep(self._line_free_at - now)
            self.link.deliver(data)
            return
        # unpaced: wait for a host that reads, not for one that is gone; what the host's reading made room for is
        # all kept, also when the pty's fill count, lagging the kernel, finds less room once delivering
        if self.link.room() < len(data):
            if not self._host_gone:
                self._host_gone = not self.link.wait_for_room(len(data), self.host_gone_s, self._stop)
        else:
            self._host_gone = False
        self.link.deliver(data, keep_all=not self._host_gone)

    def _time_frames(self, data: bytes) -> None:
        """Give each data frame among the firmware's bytes ``data`` the sample times of its slots: the ends of the
        last command words clocked before it, one per slot (none if fewer were clocked: a firmware that samples
        otherwise)."""
        commands = self.board.command_ends
        for item in self._sent.feed(data, now=self.board.t):
            if not isinstance(item, DataFrame):
                continue
            slots = len(item.channels)
            if len(commands) >= slots:
                self._frame_times.pop(item.seq, None)  # (re-inserted newest)
                self._frame_times[item.seq] = np.array(commands[len(commands) - slots:])
                while len(self._frame_times) > SAMPLE_TIMES_FRAMES:
                    del self._frame_times[next(iter(self._frame_times))]
            commands.clear()

    def sample_times(self, frame: DataFrame) -> np.ndarray | None:
        """The virtual time (s from power-on) of each slot's sample of ``frame`` (a data frame a host read from this
        bench: ``t_s[slot]``, 1/4400 s apart in the reference firmware): when its sampling command ended and the
        sensors' conversion started.  None for a frame the bench did not send with that sequence number and slot
        count, or one more than :data:`SAMPLE_TIMES_FRAMES` frames old."""
        times = self._frame_times.get(frame.seq)
        return times.copy() if times is not None and len(times) == len(frame.channels) else None

    def _sleep(self, seconds: float) -> None:
        """Sleep, moving buffered bytes on to the pty as the host reads them."""
        end = time.perf_counter() + seconds
        while True:
            self.link.pump()
            left = end - time.perf_counter()
            if left <= 0:
                return
            time.sleep(min(left, 0.001))

    def _loop(self) -> None:
        """Run the firmware in steps of ``step_s`` virtual s, passing the host's bytes in between; unpaced,
        virtual time waits for the host's first byte (see the module's docstring)."""
        wall0, virt0 = time.perf_counter(), self.board.t
        host_spoke = self.realtime
        try:
            while not self._stop.is_set():
                self._take_requests()
                data = self.link.read_available()
                if data:
                    self.board.send_to_firmware(data)
                    host_spoke = True
                if not host_spoke:
                    self.link.pump()
                    self._stop.wait(HOST_POLL_S)
                    continue
                self.sim.run(self.step_s)
                self.link.pump()
                if self.realtime:
                    ahead = (self.board.t - virt0) / self.speed - (time.perf_counter() - wall0)
                    if ahead > 0:
                        self._sleep(ahead)
        except BaseException as e:  # reported by the next call (_check_alive), or by stop()
            self._error_at = self.board.t
            self.error = e

    def _take_requests(self) -> None:
        while True:
            try:
                when, action = self._requests.get_nowait()
            except queue.Empty:
                return
            if when is None:
                run_action(action, self.board)
            else:
                self.board.at(when, action)

    def at(self, t_s: float, action) -> None:
        """Apply ``action(board)`` when virtual time reaches ``t_s`` (never blocks the caller).  A ``t_s`` that is
        not a finite number ≥ 0 (NaN was never reached: the fault silently never happened) or an ``action`` that is
        not callable is refused here, in the caller's thread."""
        if not (isinstance(t_s, numbers.Real) and not isinstance(t_s, bool) and math.isfinite(t_s) and t_s >= 0):
            raise ValueError(f"at: t_s = {t_s!r}: must be a finite virtual time ≥ 0 s (e.g. bench.virtual_time + 0.5)")
        _check_action("at", action)
        self._check_alive("at")
        self._check_running("at")
        self._requests.put((float(t_s), action))

    def now(self, action) -> None:
        """Apply ``action(board)`` before the firmware's next step (never blocks the caller)."""
        _check_action("now", action)
        self._check_alive("now")
        self._check_running("now")
        self._requests.put((None, action))

    def _ended_with(self) -> str:
        """How the firmware's thread ended: the bench's own error (a test's action, the firmware) in its words, else
        its repr."""
        return str(self.error) if isinstance(self.error, BenchError) else repr(self.error)

    def _check_alive(self, what: str) -> None:
        """Raise, for the call ``what``, the error the firmware's thread ended with, if it did: the call would act on
        a bench that no longer runs."""
        if self.error is None:
            return
        self._error_told = True
        raise RuntimeError(f"{what}: the firmware bench on {self.port} stopped at virtual time {self._error_at:.6f} "
                           f"s with an error: {self._ended_with()}") from self.error

    def _check_running(self, what: str) -> None:
        """Refuse scheduling on a stopped bench: the action would silently never run."""
        if self._stop.is_set():
            raise RuntimeError(f"{what}: the bench on {self.port} is stopped (stop() was called): an action given now "
                               f"would never run; schedule faults before stopping it")

    @property
    def virtual_time(self) -> float:
        """The firmware's virtual time (s) since power-on."""
        self._check_alive("virtual_time")
        return self.board.t

    def overrun_frames(self) -> list[int]:
        """Sequence numbers of the data frames that lost bytes to receive-buffer overruns (needs
        ``keep_arrivals=True``): exactly the frames a host reading this port can never get."""
        if self.link.arrivals is None:
            raise ValueError("overrun_frames() needs FirmwareBench(..., keep_arrivals=True)")
        data, lost, pos, k = bytes(self.link.arrivals), [], 0, 0
        ranges = self.link.overruns
        while pos + 7 <= len(data):
            if data[pos:pos + 2] != b"\xaa\x55":  # only with line faults: find the next frame
                nxt = data.find(b"\xaa\x55", pos + 1)
                if nxt < 0:
                    break
                pos = nxt
                continue
            length = data[pos + 3] | data[pos + 4] << 8
            end = pos + 7 + length
            while k < len(ranges) and sum(ranges[k]) <= pos:
                k += 1
            if data[pos + 2] == 0x10 and k < len(ranges) and ranges[k][0] < end and length >= 2:
                lost.append(data[pos + 5] | data[pos + 6] << 8)
            pos = end
        return lost

    def start(self) -> "FirmwareBench":
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the firmware and close the port (a host still reading it sees the port go away); idempotent."""
        if self.link.closed:
            return
        self._stop.set()
        join_outside_compiles(self._thread, STOP_TIMEOUT_S)
        self.link.close()
        if self._thread.is_alive():  # inside the firmware's bt_step: a loop that never returns to the bench
            hung = (f"the firmware did not return from bt_step within {STOP_TIMEOUT_S:g} s of wall time after stop() "
                    f"(virtual time {self.board.t:.6f} s): it hangs in a loop (one waiting for a byte or a time that "
                    f"only comes between steps, or one that calls no HAL function; its last HAL call: "
                    f"{self.board.last_hal_call or 'none'}; firmware {self.sim.library})")
            why_not = self.sim.stop_step(within_s=STOP_TIMEOUT_S)  # the step guard: the firmware's loop is left
            if why_not is None:
                join_outside_compiles(self._thread, STOP_TIMEOUT_S)
            if self._thread.is_alive():  # (inside a HAL call of the bench's, or outside the firmware's own code)
                self.board.abandoned.set()
                raise FirmwareError(f"{hung}; the watchdog could not stop it ({why_not or 'its thread did not end'}): "
                                    f"its port is closed, its SPI bus left open and its thread parked at its next HAL "
                                    f"call")
            self.board.bus.close()
            raise FirmwareError(f"{hung}; the watchdog stopped it (its thread ended; its port and SPI bus are closed)")
        self.board.bus.close()
        if self.error is not None and not self._error_told:
            raise RuntimeError(f"the firmware bench stopped with an error: {self._ended_with()}") from self.error

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()
