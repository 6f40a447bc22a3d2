"""Native co-simulation of bridge firmware: the firmware's HAL bound to emulated sensors in virtual time.

The firmware (C) is compiled for this machine with the system C compiler into a shared library and called
through ctypes. Its HAL calls land here: queued SPI sequences go through the software SPI bus to emulated
sensors, delays advance virtual time, and the UART is a byte pipe — an in-memory one, or a pty that any
program can open as a serial port (:class:`bench.hosts.serial_link.PtyLink`).  Deterministic and faster than real
time; ``run(..., realtime=True)`` paces virtual time to the wall clock.
"""

from __future__ import annotations

import ctypes as C
import math
import signal
import threading
import time
from collections import deque
from pathlib import Path

import numpy as np

from bench.errors import ActionError, BuildError, FirmwareError
from bench.hosts.driver import BridgeDriver
from bench.hosts.native import build_folder, compile_c
from bench.paths import REPO
from emulator import channels as ch
from emulator.sensor import Sensor
from emulator.spi.model import Bus, SensorPort, Transfer

FIRMWARE_DIR = REPO / "firmware_tests" / "firmware"
SPI_CLOCK_HZ = 4.4e6
#: The largest chip-select code the HAL takes (``bt_word.cs``, ``spi_bytes``' cs: three bits).
MAX_SELECT_CODE = 7
#: The command words' ends :attr:`VirtualBoard.command_ends` keeps, the latest: the most slots a data frame holds (its
#: slot count is one byte), of which a frame's sample times are the last ones before it.
COMMAND_ENDS_KEPT = 255
GUARD_SOURCE = Path(__file__).resolve().parent / "c" / "step_guard.c"
#: The signal that stops a hung bt_step (:meth:`CoSim.stop_step`): a real-time signal nothing else here uses.  The
#: bench installs its handler at the first co-simulation, only over the default action (a handler something else in
#: the process installed first is refused by name, never replaced), and keeps it for the process's life.
GUARD_SIGNAL = signal.SIGRTMIN + 3
#: How long (wall s) :meth:`CoSim.stop_step` waits between two of its signals.
GUARD_RETRY_S = 0.001
_guard_lock = threading.Lock()
_guard: list = []  # the loaded step guard


def _signal_name(sig: int) -> str:
    return f"SIGRTMIN+{sig - signal.SIGRTMIN} ({sig})"


def step_guard() -> C.CDLL:
    """The step guard (``bench/hosts/c/step_guard.c``), built and loaded once, its handler of :data:`GUARD_SIGNAL`
    installed (:class:`FirmwareError` when the signal has another handler in this process)."""
    with _guard_lock:
        if not _guard:
            folder = build_folder(REPO / "out" / "firmware", [GUARD_SOURCE, FIRMWARE_DIR / "bt_hal.h"])
            lib = C.CDLL(str(compile_c([GUARD_SOURCE], folder / "libbtguard.so",
                                       flags=("-shared", "-fPIC", f"-I{FIRMWARE_DIR}"), what="the step guard")))
            lib.bt_guard_size.restype = C.c_size_t
            lib.bt_guard_init.argtypes = [C.c_void_p, C.c_void_p]
            lib.bt_guard_step.argtypes = [C.c_void_p, C.c_void_p, C.c_void_p]
            lib.bt_guard_start.argtypes = [C.c_void_p, C.c_void_p, C.c_void_p, C.c_void_p]
            lib.bt_guard_set_pattern.argtypes = [C.c_void_p, C.c_void_p, C.c_void_p, C.c_char_p, C.c_size_t,
                                                 C.POINTER(C.c_uint8)]
            lib.bt_guard_take_exits.argtypes = [C.c_void_p]
            lib.bt_guard_wrap.argtypes = [C.c_void_p, C.c_void_p]
            for name in ("bt_guard_stop", "bt_guard_stopped", "bt_guard_poke", "bt_guard_outside"):
                getattr(lib, name).argtypes = [C.c_void_p]
            lib.bt_guard_crash.argtypes = [C.c_void_p, C.POINTER(C.c_size_t), C.POINTER(C.c_size_t),
                                           C.POINTER(C.c_int)]
            lib.bt_guard_exit_call.argtypes = [C.c_void_p]
            lib.bt_guard_exit_call.restype = C.c_char_p
            lib.bt_guard_outside.restype = C.c_size_t
            _guard.append(lib)
        lib = _guard[0]
        sig = int(GUARD_SIGNAL)
        installed = lib.bt_guard_install(sig)
        if installed == 1:
            raise FirmwareError(f"signal {_signal_name(sig)} already has a handler in this process (installed by "
                                f"signal.signal or by a library): the firmware watchdog needs a signal of its own; "
                                f"set bench.hosts.cosim.GUARD_SIGNAL to a free real-time signal before making a "
                                f"co-simulation")
        if installed != 0 or lib.bt_guard_catch_crashes() != 0:
            raise BuildError(f"the step guard cannot handle signal {_signal_name(sig)} or the fault signals")
        return lib


def code_at(address: int) -> str:
    """The library (and function, where it exports one) holding machine code at ``address``: where a hung
    firmware's thread is."""
    info = _DlInfo()
    if not address or not _LIBC.dladdr(C.c_void_p(address), C.byref(info)) or not info.dli_fname:
        return f"code at {address:#x} in no loaded library"
    where = Path(info.dli_fname.decode(errors="replace")).name
    return f"{where} ({info.dli_sname.decode(errors='replace')})" if info.dli_sname else where


class _DlInfo(C.Structure):
    _fields_ = [("dli_fname", C.c_char_p), ("dli_fbase", C.c_void_p), ("dli_sname", C.c_char_p),
                ("dli_saddr", C.c_void_p)]


_LIBC = C.CDLL(None)
_LIBC.dladdr.argtypes = [C.c_void_p, C.POINTER(_DlInfo)]


def build_firmware(sources=None, out_dir: Path | None = None) -> Path:
    """Compile firmware sources (C11) into a shared library; cached by the contents of the sources, of the headers
    beside them and of the reference firmware's headers (``bt_hal.h``), so editing a header of your own rebuilds.
    A source that is not a file is a :class:`BuildError` naming it."""
    sources = [Path(s) for s in (sources or sorted(FIRMWARE_DIR.glob("*.c")))]
    for s in sources:
        if not s.is_file():
            raise BuildError(f"the firmware: source {str(s)!r} is not a file (give C source files, e.g. "
                             f"sorted(Path('my_firmware').glob('*.c')))")
    folders = sorted({s.resolve().parent for s in sources} | {FIRMWARE_DIR.resolve()})
    headers = [h for folder in folders for h in sorted(folder.glob("*.h"))]
    folder = build_folder(out_dir or REPO / "out" / "firmware", sources + headers)
    return compile_c(sources, folder / "libbtbridge.so", flags=("-shared", "-fPIC", f"-I{FIRMWARE_DIR}"),
                     what="the firmware")


#: What a firmware library must export for the bench to run it (bt_bridge.h).
FIRMWARE_SYMBOLS = ("bt_bridge_size", "bt_init", "bt_step", "bt_set_pattern")


def firmware_library(firmware=None) -> Path:
    """The shared library to run for ``firmware``: None, the reference firmware (built); a list of C sources, built
    with :func:`build_firmware`; or the path of a library you built (``.so``).  Anything else is a
    :class:`BuildError` saying what is allowed."""
    if firmware is None:
        return build_firmware()
    if isinstance(firmware, (str, Path)):
        path = Path(firmware)
        if path.suffix == ".c":
            return build_firmware([path])
        if not path.is_file():
            raise BuildError(f"firmware = {str(firmware)!r}: no such library (give a built .so, a list of C sources, "
                             f"or None for the reference firmware)")
        return path
    if isinstance(firmware, (list, tuple)) and firmware and all(isinstance(s, (str, Path)) for s in firmware):
        return build_firmware(list(firmware))
    raise BuildError(f"firmware = {firmware!r}: give None (the reference firmware), a list of C source files, or "
                     f"the path of a built .so")


def load_firmware(library: Path) -> C.CDLL:
    """Load a firmware library, checking it exports :data:`FIRMWARE_SYMBOLS` (FirmwareError naming those missing)."""
    try:
        lib = C.CDLL(str(library))
    except OSError as e:
        raise FirmwareError(f"the firmware library {str(library)!r} cannot be loaded: {e}") from e
    missing = [name for name in FIRMWARE_SYMBOLS if not hasattr(lib, name)]
    if missing:
        raise FirmwareError(f"the firmware library {str(library)!r} does not export {', '.join(missing)}; the bench "
                            f"calls {', '.join(FIRMWARE_SYMBOLS)} (firmware_tests/firmware/bt_bridge.h)")
    return lib


class BtWord(C.Structure):
    _fields_ = [("offset_ns", C.c_uint32), ("cs", C.c_uint8), ("keep_cs", C.c_uint8), ("mosi", C.c_uint16)]


SEQ_FN = C.CFUNCTYPE(None, C.c_void_p, C.POINTER(BtWord), C.POINTER(C.c_uint16), C.c_size_t)
BYTES_FN = C.CFUNCTYPE(None, C.c_void_p, C.c_uint8, C.c_uint8, C.POINTER(C.c_uint8), C.POINTER(C.c_uint8), C.c_size_t)
DELAY_FN = C.CFUNCTYPE(None, C.c_void_p, C.c_uint32)
MICROS_FN = C.CFUNCTYPE(C.c_uint64, C.c_void_p)
WRITE_FN = C.CFUNCTYPE(None, C.c_void_p, C.POINTER(C.c_uint8), C.c_size_t)
READ_FN = C.CFUNCTYPE(C.c_size_t, C.c_void_p, C.POINTER(C.c_uint8), C.c_size_t)


class BtHal(C.Structure):
    _fields_ = [("ctx", C.c_void_p), ("spi_sequence", SEQ_FN), ("spi_bytes", BYTES_FN), ("delay_us", DELAY_FN),
                ("micros", MICROS_FN), ("uart_write", WRITE_FN), ("uart_read", READ_FN)]


def action_name(action) -> str:
    """An action as a reader finds it: its name and, for a Python function or lambda, where it is defined
    (``<lambda> at test_mine.py:19``)."""
    name = getattr(action, "__qualname__", None) or repr(action)
    code = getattr(action, "__code__", None)
    return name if code is None else f"{name} at {code.co_filename}:{code.co_firstlineno}"


def run_action(action, board, due_s: float | None = None) -> None:
    """Apply ``action(board)``; an exception it raises becomes :class:`~bench.errors.ActionError` naming the action,
    when it was due (``due_s``, virtual s; None: asked with ``now``) and the board's virtual time."""
    try:
        action(board)
    except Exception as e:  # noqa: BLE001 - whatever a test's action raises, reported as that action's
        when = "asked to run now" if due_s is None else f"due at virtual time {due_s:.6f} s"
        raise ActionError(f"the action {action_name(action)}, {when}, raised {type(e).__name__}: {e} (virtual "
                          f"time {board.t:.6f} s); the bench stopped there") from e


class VirtualBoard:
    """The board around the firmware: SPI bus with emulated sensors, virtual time, a UART.

    ``sensors`` maps sensor number (1–5) to an emulated :class:`Sensor`; ``uart_out`` receives every byte
    the firmware sends; bytes for the firmware are queued with :meth:`send_to_firmware`.  ``events`` are
    (virtual time s, callable(board)) applied as time passes: unplugging a sensor, corrupting the line...
    """

    def __init__(self, sensors: dict[int, Sensor], uart_out=None, pull_up: bool = False, spi: str = "software"):
        self.sensors = dict(sensors)
        if spi == "rtl":  # the Verilog twin in a persistent C++ Verilator harness
            from emulator.rtl.harness import RtlBus

            self.bus = RtlBus(self.sensors)
        elif spi == "software":
            self.bus = Bus({n: SensorPort(s, n) for n, s in self.sensors.items()}, pull_up=pull_up)
        else:
            raise ValueError(f"spi = {spi!r}: use 'software' or 'rtl'")
        self.spi = spi
        self.t = 0.0
        self.uart_out = uart_out or (lambda data: None)
        self.uart_in: deque[int] = deque()
        self.events: list[tuple[float, object]] = []
        self.resets: list[tuple[float, int]] = []  # (virtual time s, sensor): brown-outs inside an SPI sequence
        self.error: BaseException | None = None
        self.error_in = ""  # the HAL function where error came, and when
        #: A HAL call ended midway — by Ctrl-C, or by an exception that is neither the bench refusing the call (a
        #: ValueError, raised before anything changed) nor a test's action raising (ActionError) — says which, when
        #: and by what: the board's record (virtual time, events and resets applied, the sensors' SPI state) may be
        #: half-updated, so the firmware is left as that call returns (``stop_firmware``) and never runs again.
        self.cut_short: str | None = None
        #: Set by the co-simulation running the firmware: ends its bt_init or bt_step as the HAL call returns, for good
        #: (the step guard's stop), so the firmware never goes on with what a call cut short gave it.
        self.stop_firmware = lambda: None
        #: Set when the bench gave up on a hung firmware: its next HAL call parks its thread for good, so a loop
        #: that keeps calling the HAL stops spending a core for the rest of the process.
        self.abandoned = threading.Event()
        self.last_hal_call: str | None = None  # the HAL function the firmware called last (where a hang is)
        #: When a list: every command word (a word whose MOSI is not 0: a sampling command, or any other command)
        #: the firmware's SPI sequences clock gets its end appended — the virtual time (s) chip select rises on it
        #: and a sampling command's conversion starts (:meth:`bench.hosts.bridge.FirmwareBench.sample_times`); the
        #: latest :data:`COMMAND_ENDS_KEPT` are kept.
        self.command_ends: list[float] | None = None

    # --- faults and events ---------------------------------------------------------------
    def at(self, t_s: float, action) -> None:
        self.events.append((t_s, action))
        self.events.sort(key=lambda e: e[0])

    def unplug(self, n: int) -> None:
        """Unplug sensor n (on either SPI bus: over the RTL its sensor leaves the RTL's sensors present at the next
        transfer)."""
        self.bus.ports.pop(n, None)

    def plug(self, n: int) -> None:
        """Plug sensor n back in: it starts from power-on state (its physics carries on).  Over the RTL it rejoins
        the RTL's sensors present, reset, at the next transfer."""
        if self.spi == "rtl":
            from emulator.rtl.harness import RtlSensorPort

            port = RtlSensorPort(self.sensors[n], n, self.bus)
        else:
            port = SensorPort(self.sensors[n], n)
        self.bus.ports[n] = port

    def reset_at(self, n: int, t_s: float) -> None:
        """Reset sensor n (a brown-out: power-on state, :meth:`SensorPort.reset`) at virtual time ``t_s`` (s):
        inside a frame's SPI sequence at the first word boundary at or after ``t_s`` that is not inside a window the
        firmware holds open on one sensor — between a sampling command and its read, say, where it loses the
        pending result; elsewhere at the firmware's first HAL call from ``t_s`` on.  (Events of :meth:`at` act
        between the firmware's HAL calls.)  On either SPI bus: over the RTL the port's reset reaches the RTL sensor
        just before the next word (:class:`emulator.rtl.harness.RtlSensorPort`)."""
        if not math.isfinite(t_s) or t_s < 0:
            raise ValueError(f"reset_at: t_s = {t_s!r} s: must be a finite instant ≥ 0")
        self.resets.append((float(t_s), int(n)))
        self.resets.sort()

    def _reset(self) -> None:
        """Apply the earliest pending reset."""
        _, sensor = self.resets.pop(0)
        if sensor in self.bus.ports:
            self.bus.ports[sensor].reset()

    def glitch(self, n: int) -> None:
        """Toggle sensor n's chip select with no clock edges (a glitch on the line), now (on either SPI bus)."""
        from emulator.spi.model import SELECT_CODE

        tr = Transfer(self.t, SELECT_CODE[n], 0, 0, SPI_CLOCK_HZ)
        self.bus.transfer(tr)
        self.t = tr.end_s

    def _events_due(self) -> None:
        while self.resets and self.resets[0][0] <= self.t:
            self._reset()
        while self.events and self.events[0][0] <= self.t:
            due, action = self.events.pop(0)
            run_action(action, self, due)

    def send_to_firmware(self, data: bytes) -> None:
        self.uart_in.extend(data)

    # --- the HAL ------------------------------------------------------------------------
    def _guard(fn):  # noqa: N805 - decorator inside the class body
        name = fn.__name__

        def wrapped(self, *a):
            if self.abandoned.is_set():
                threading.Event().wait()  # never set: the firmware's thread sleeps until the process ends
            self.last_hal_call = name
            try:
                return fn(self, *a)
            except BaseException as e:  # an exception must not unwind through C: keep it, stop the run
                if self.error is None or not isinstance(e, Exception):  # (Ctrl-C is never hidden by a refusal)
                    self.error, self.error_in = e, f"{name} at virtual time {self.t:.6f} s"
                if not isinstance(e, (ValueError, ActionError)) and self.cut_short is None:
                    self.cut_short = f"the HAL call {name} at virtual time {self.t:.6f} s was cut short by {e!r}"
                    self.stop_firmware()
                return 0
        return wrapped

    @_guard
    def spi_sequence(self, ctx, words, miso, n):
        self._events_due()
        if n == 0:  # (an empty list: nothing clocked, no time passes)
            return
        w = np.ctypeslib.as_array(words, shape=(n,))
        bad = np.flatnonzero(w["cs"] > MAX_SELECT_CODE)
        if bad.size:
            raise ValueError(f"word #{bad[0]} of {n}: cs = {w['cs'][bad[0]]}: a select code is 0 to "
                             f"{MAX_SELECT_CODE} (bt_hal.h: 1, 2, 4, 5, 6 = sensors 1..5, 7 = all, 0 = none)")
        start = self.t + w["offset_ns"] * 1e-9
        if self.command_ends is not None:
            self.command_ends.extend((start[w["mosi"] != 0] + 16.5 / SPI_CLOCK_HZ).tolist())  # (Transfer.end_s)
            del self.command_ends[:-COMMAND_ENDS_KEPT]  # (a firmware whose frames the bench never parses)
        keep, out = w["keep_cs"].astype(bool), np.ctypeslib.as_array(miso, shape=(n,))
        i = 0
        while i < n:  # the words before each reset due within the sequence, the reset, the rest
            j = n
            if self.resets and self.resets[0][0] <= start[-1]:
                j = max(i, int(np.searchsorted(start, self.resets[0][0], side="left")))
                while 0 < j < n and keep[j - 1]:  # not inside a window held open (a batch is one bus operation)
                    j += 1
            if j > i:
                out[i:j] = self.bus.exchange_words(start[i:j], w["cs"][i:j], w["mosi"][i:j], SPI_CLOCK_HZ, keep[i:j])
            if j < n:
                self._reset()
            i = j
        self.t = float(start[-1] + 16.5 / SPI_CLOCK_HZ)

    @_guard
    def spi_bytes(self, ctx, cs, keep_cs, tx, rx, n):
        self._events_due()
        if cs > MAX_SELECT_CODE:
            raise ValueError(f"cs = {cs}: a select code is 0 to {MAX_SELECT_CODE} (bt_hal.h: 1, 2, 4, 5, 6 = sensors "
                             f"1..5, 7 = all, 0 = none)")
        mosi = int.from_bytes(bytes(tx[:n]), "big") if n else 0
        tr = Transfer(self.t, int(cs), mosi, 8 * n, SPI_CLOCK_HZ, bool(keep_cs))
        bits = self.bus.transfer(tr)
        for i, byte in enumerate(bits.to_bytes(n, "big") if n else b""):
            rx[i] = byte
        self.t = tr.end_s + 0.5e-6

    @_guard
    def delay_us(self, ctx, us):
        self.t += us * 1e-6
        self._events_due()

    @_guard
    def micros(self, ctx):
        return int(self.t * 1e6)

    @_guard
    def uart_write(self, ctx, data, n):
        self.uart_out(bytes(data[:n]))

    @_guard
    def uart_read(self, ctx, buf, maxn):
        k = min(maxn, len(self.uart_in))
        for i in range(k):
            buf[i] = self.uart_in.popleft()
        return k

    del _guard


class CoSim:
    """Firmware + board: ``run(seconds)`` executes the firmware's main loop in virtual time.

    ``bt_init``, each ``bt_step`` and ``bt_set_pattern`` run under the step guard (``bench/hosts/c/step_guard.c``):
    :meth:`stop_step` leaves a hung step (or a hung ``bt_set_pattern``), and a fault in the firmware's own code
    (SIGSEGV, SIGBUS, SIGFPE, SIGILL; a stack overflow too) or its call of exit, _exit, abort or a failed assert (any
    firmware library: the guard takes over its calls of them) leaves the call instead of ending the process —
    :meth:`run` (the constructor for ``bt_init``, :meth:`set_pattern` for ``bt_set_pattern``) raises
    :class:`FirmwareError` naming it.  Either way the co-simulation is :attr:`stopped` for good.
    """

    def __init__(self, board: VirtualBoard, library: Path | None = None):
        if board.cut_short:
            raise FirmwareError(f"the board: {board.cut_short}: its record of time and of its sensors may be "
                                f"half-updated; make a new VirtualBoard for a new co-simulation")
        self.board = board
        self.library = Path(library or build_firmware())
        self.lib = load_firmware(self.library)
        self.lib.bt_bridge_size.restype = C.c_size_t
        self.state = C.create_string_buffer(self.lib.bt_bridge_size())
        self._cb = [SEQ_FN(board.spi_sequence), BYTES_FN(board.spi_bytes), DELAY_FN(board.delay_us),
                    MICROS_FN(board.micros), WRITE_FN(board.uart_write), READ_FN(board.uart_read)]
        self.hal = BtHal(None, *self._cb)
        # the firmware gets the step guard's HAL: each call blocks the guard's signal while the bench's HAL runs
        self._guard = step_guard()
        self._guarded_hal = BtHal()
        self._guard.bt_guard_wrap(C.byref(self.hal), C.byref(self._guarded_hal))
        self._step = C.cast(self.lib.bt_step, C.c_void_p)
        self._watch = C.create_string_buffer(self._guard.bt_guard_size())  # this firmware's guard: its code, its stop
        if self._guard.bt_guard_init(self._watch, self._step):
            raise FirmwareError(f"the step guard found no loaded library holding bt_step of {self.library}")
        # the firmware's exit, _exit, abort and failed asserts end the guarded call, not the process
        self._guard.bt_guard_take_exits(self._step)
        self._left_in = "bt_init"  # the firmware's function running when the guard left it (for _why_stopped)
        board.stop_firmware = lambda: self._guard.bt_guard_stop(self._watch)
        self._guarded("bt_init", lambda: self._guard.bt_guard_start(
            self._watch, C.cast(self.lib.bt_init, C.c_void_p), self.state, C.byref(self._guarded_hal)))

    @property
    def stopped(self) -> bool:
        """Whether this co-simulation was stopped — by :meth:`stop_step`, or its firmware faulting or calling exit in
        a step: it does not run again (its firmware's state was left midway); make a new one."""
        return bool(self._guard.bt_guard_stopped(self._watch))

    def stop_step(self, within_s: float = 1.0) -> str | None:
        """Stop this co-simulation's firmware for good — a watchdog giving up on a hung ``bt_step``, from another
        thread: the step running now is left (by a signal to its thread, :data:`GUARD_SIGNAL`, taken only where the
        thread is in the firmware's own code; tried again every :data:`GUARD_RETRY_S` until ``within_s`` wall s have
        passed) and :meth:`run` (:meth:`set_pattern`, for a hung ``bt_set_pattern``) raises :class:`FirmwareError`, now
        or at its next step; so does every later :meth:`run` and :meth:`set_pattern`.  Returns None when no step runs
        any more, or else why the step could not be left yet: inside one of the bench's HAL calls (it is left as that
        returns), or outside the firmware's code (a C library call, say, which may hold a lock: jumping out of it would
        deadlock the process's next call of it) or with the guard's signal handler replaced by something else in the
        process (a signal then might end the process: none is sent)."""
        self._guard.bt_guard_stop(self._watch)
        sig = int(GUARD_SIGNAL)
        deadline = time.monotonic() + within_s
        while True:
            if not self._guard.bt_guard_installed(sig):
                return (f"the handler of signal {_signal_name(sig)} was replaced after the bench installed it (by "
                        f"signal.signal or a library): the watchdog sends no signal")
            status = self._guard.bt_guard_poke(self._watch)
            if status == 0:
                return None
            if time.monotonic() >= deadline:
                if status == 2:
                    return (f"it is inside the bench's HAL function {self.board.last_hal_call}: its step is left as "
                            f"that returns")
                return (f"it is outside the firmware's code, in {code_at(self._guard.bt_guard_outside(self._watch))}, "
                        f"which the watchdog does not jump out of (a lock held there would deadlock the process)")
            time.sleep(GUARD_RETRY_S)

    def set_pattern(self, channels) -> None:
        """Set the firmware's sampling pattern directly (as its PATTERN command would, without a reply on the
        UART): 1–64 channel indices (or names), each PAC, PDC, TAC, TDC or E1..E24 (E20..E24 exist on a BioTac
        SP only; a 19-electrode sensor answers them with error words).  Entries are checked as the driver's
        (:meth:`bench.hosts.driver.BridgeDriver.pattern_bytes`: True is no channel, an index not a byte is
        refused before the firmware sees it); the firmware judges the channels.  ``bt_set_pattern`` runs under the step
        guard, as ``bt_step`` does: a crash, an exit or a hang the watchdog stops there is a :class:`FirmwareError`
        naming it, and the co-simulation is :attr:`stopped`."""
        channels = list(channels)
        payload = BridgeDriver.pattern_bytes(channels)  # (ValueError before the firmware sees anything)
        if self.stopped:
            raise FirmwareError(f"set_pattern: {self._why_stopped()}")
        result = C.c_uint8()
        self._guarded("bt_set_pattern", lambda: self._guard.bt_guard_set_pattern(
            self._watch, C.cast(self.lib.bt_set_pattern, C.c_void_p), self.state, payload, len(payload),
            C.byref(result)))
        result = result.value
        if result:
            raise ValueError(f"sampling pattern {list(channels)!r} refused by the firmware: "
                             + ("1 to 64 channels" if result == 1 else "channels are PAC, PDC, TAC, TDC, E1..E24"))

    def _why_stopped(self) -> str:
        """Why the firmware's bt_init or bt_step was left: a HAL call cut short, the firmware calling exit or the like,
        a fault in its code (its signal, or a stack overflow; where), or the watchdog (a hung bt_step)."""
        pc, addr, overflow = C.c_size_t(), C.c_size_t(), C.c_int()
        sig = self._guard.bt_guard_crash(self._watch, C.byref(pc), C.byref(addr), C.byref(overflow))
        again = "this co-simulation does not run again: make a new one"
        if self.board.cut_short:
            return (f"{self.board.cut_short}: the board's record of time and of its sensors may be half-updated; the "
                    f"bench left the firmware's {self._left_in} as that call returned; {again}")
        called = self._guard.bt_guard_exit_call(self._watch).decode(errors="replace")
        if called:
            return (f"the firmware called {called} in {self._left_in} at virtual time {self.board.t:.6f} s, which "
                    f"would have ended the process: the bench left its {self._left_in} and goes on; {again}")
        if sig:
            fault = "a stack overflow" if overflow.value else signal.Signals(sig).name
            return (f"the firmware crashed in {self._left_in} at virtual time {self.board.t:.6f} s: "
                    f"{fault} in {code_at(pc.value)} (touching address {addr.value:#x}); the "
                    f"bench left its {self._left_in} and goes on; {again}")
        return (f"the firmware's {self._left_in} was stopped by the bench's watchdog at virtual time "
                f"{self.board.t:.6f} s (it hung); {again}")

    def _guarded(self, entry: str, call) -> None:
        """Run the firmware's ``entry`` (its name: bt_init, bt_step, bt_set_pattern) by ``call()``, one of the step
        guard's functions (0: it returned); :class:`FirmwareError` saying why when the guard left it (or a stop was
        asked before), or the error a HAL call it made was cut short by."""
        if not self.stopped:  # (a stopped co-simulation says where it was left, not where it was asked to go on)
            self._left_in = entry
        if call():
            self._raise()  # (a HAL call cut short: Ctrl-C reaches the caller as the KeyboardInterrupt it is)
            raise FirmwareError(self._why_stopped())
        self._raise()

    def _raise(self):
        if self.board.error is not None:
            e, self.board.error = self.board.error, None
            # a test's own action (its message says which and why), or Ctrl-C (KeyboardInterrupt) or SystemExit in a
            # HAL call: as it came
            if isinstance(e, ActionError) or not isinstance(e, Exception):
                raise e
            what = str(e) if isinstance(e, ValueError) else repr(e)  # (a ValueError: the firmware's call refused)
            raise FirmwareError(f"the firmware's HAL call {self.board.error_in}: {what}") from e

    def run(self, seconds: float, realtime: bool = False, max_steps: int | None = None) -> None:
        """Run the firmware until ``seconds`` more of virtual time have passed.

        A firmware that stops advancing time (a hang in a loop that calls no HAL) is not interrupted from here:
        another thread can end its step (:meth:`stop_step`, :class:`FirmwareError` here), and ``max_steps`` bounds
        the number of main-loop passes, raising if they run out first.
        """
        end = self.board.t + seconds
        wall0, virt0 = time.perf_counter(), self.board.t
        steps = 0
        while self.board.t < end:
            self._guarded("bt_step", lambda: self._guard.bt_guard_step(self._watch, self._step, self.state))
            steps += 1
            if max_steps is not None and steps >= max_steps:
                raise FirmwareError(f"the firmware made {steps} passes without reaching t = {end:.3f} s "
                                    f"(virtual time {self.board.t:.3f} s): hung or idling without delays")
            if realtime:
                ahead = (self.board.t - virt0) - (time.perf_counter() - wall0)
                if ahead > 0:
                    time.sleep(ahead)


def default_sensors(n: int = 1, stimuli=(), seed: int = 0, variant: str = ch.DEFAULT_VARIANT,
                    **kw) -> dict[int, Sensor]:
    """n emulated sensors of ``variant`` reading its default frame's channels; sensor k draws its noise from
    ``seed + k - 1`` (:func:`bench.scenes.scene.sensor_seed`, as a scene's and the pytest plugin's sensor k)."""
    from bench.scenes.scene import sensor_seed

    frame = ch.variant(variant).frame_names
    return {k: Sensor(stimuli=stimuli if k == 1 else (), channels_read=frame, seed=sensor_seed(seed, k),
                      variant=variant, **kw)
            for k in range(1, n + 1)}
