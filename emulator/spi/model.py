"""The sensor's SPI peripheral as a state machine, and the bus several sensors share (SENSOR.md §6).

This is the reference every implementation must match bit for bit (the RTL twin is checked against
it by golden vectors and a differential test).  Semantics, precisely:

Transfers and chip select
    A transfer clocks ``nbits`` bits (mode 0, MSB first) at ``clock_hz``: chip select falls at
    ``start_s``, the k-th rising SCK edge comes at start + (k + ½)·T, chip select rises at
    start + (nbits + ½)·T.  ``keep_cs`` leaves chip select asserted so the next transfer continues
    the same window (how hosts stream property bytes).  The host's 3-bit select code picks a sensor
    (1, 2, 4, 5, 6 for sensors 1–5), all of them (7) or none (0).

Time
    The sensor measures delays with a 1 MHz timer: ``ticks(t) = ⌊t·10⁶⌋``.  The result of a command is
    ready 50 ticks after its chip select rose (100 with the ``slow_response`` fault); a sampling command
    for a recognised channel less than 5 ticks after the previous one answers ``E-`` (the ADC is busy).

What MISO carries
    At chip-select fall the sensor chooses what it will shift out: the prepared result if it is ready
    and not yet consumed; ``E.`` if it is not ready yet; ``E_`` if there is none.  A word is 16 bits
    followed by zeros; a property is its bytes (strings end with NUL) followed by 0xFF.  This holds for
    every transfer — during a command the host simply ignores MISO.

What MOSI does (decided when chip select rises)
    * first byte 0x00 (the host clocking 0x0000 or 0x0001): a read; if it received the prepared word
      (≥ 16 bits) the word is consumed and kept for resend; a property stream ends with its window;
    * fewer than 16 bits otherwise: ignored (counted in ``incomplete``);
    * first byte 0x20 or 0x50 (library and manual spellings): resend the last word read, else ``E_``;
    * even parity of the first byte: ``EE``;
    * ``1SSSSSSP``: sample channel S at the instant chip select rose -> the code's response word;
      a channel the sensor does not have (or was not built to provide) answers ``EX``;
    * 0x61 + property id: stream that property (``EX`` for an unknown id);
    * 0x40 + ``NNNNVVVP``: write V to parameter N: even parity of the second byte ``EE``; N ≥ 4 is
      read-only ``ER``; V = 7 is reserved ``EW``; otherwise acknowledged with the word carrying N·8 + V;
    * anything else: ``E?``.

The conversion of a sampling command happens just after its chip select rises; it is disturbed by
SPI coupling if the bus clocks again within ``adc_conversion_s``.  It is therefore resolved when the
next transfer on the bus starts (or at :meth:`Bus.flush`), so results never depend on batching.

A call is whole
    :meth:`Bus.transfer`, :meth:`Bus.exchange_words` and :meth:`SensorPort.exchange` change the bus, its ports and
    their sensors step by step; an exception a Python signal handler raises midway (KeyboardInterrupt from Ctrl-C)
    would leave them part-way through a batch.  Such handlers run after the call instead (:func:`whole_call`), so
    an interrupted caller finds the bus wholly before or wholly after its call.
"""

from __future__ import annotations

import functools
import _signal  # (signal's own C functions: signal.getsignal's enum conversion costs 85 µs a call over every signal)
import math
import signal
import threading
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from emulator import channels as ch
from emulator.spi import protocol as proto

_SIGNALS = tuple(int(sig) for sig in signal.valid_signals())
_holding = threading.local()  # .active: the main thread is inside a call that holds signal handlers back


@contextmanager
def signals_held():
    """Hold back every Python signal handler over the block: a signal that comes inside it runs its handler as the
    block ends (in the order the signals came), so an exception a handler raises — KeyboardInterrupt from SIGINT,
    say — never lands midway.  Every signal that came runs its handler, even after one of them raised (as Python
    runs the others at its next check); the last exception raised propagates, with the earlier ones as its context.
    Python runs signal handlers in the main thread only: elsewhere, and inside a block already holding them, the
    block runs as it is.  Signals whose handler is not a Python function (the default action, ignored, or a C
    library's) are left alone, and a handler the block itself installs stays."""
    if getattr(_holding, "active", False) or threading.current_thread() is not threading.main_thread():
        yield
        return
    came, handlers = [], {}

    def later(sig, frame):
        if getattr(_holding, "active", False):
            came.append((sig, frame))
        else:  # (the block is over: a handler not put back yet runs as it would have)
            handlers[sig](sig, frame)

    _holding.active = True
    try:
        for sig in _SIGNALS:
            handler = _signal.getsignal(sig)
            if callable(handler):
                handlers[sig] = handler
                _signal.signal(sig, later)
        yield
    finally:
        _holding.active = False
        try:
            _run_handlers(came, handlers)
        finally:
            for sig, handler in handlers.items():
                if _signal.getsignal(sig) is later:  # (one the block installed itself stays)
                    _signal.signal(sig, handler)


def _run_handlers(came: list, handlers: dict) -> None:
    """Each signal in ``came`` ((signal, frame) pairs) given to its handler in ``handlers``, in order; one that
    raises does not keep the others from running (they run inside its handling, so a later exception has it as
    its context)."""
    for k, (sig, frame) in enumerate(came):
        try:
            handlers[sig](sig, frame)
        except BaseException:
            _run_handlers(came[k + 1:], handlers)
            raise


def whole_call(method):
    """``method`` run with Python signal handlers held back to its end (:func:`signals_held`): an interrupt never
    leaves its changes to the bus half made."""
    @functools.wraps(method)
    def held(*args, **kwargs):
        with signals_held():
            return method(*args, **kwargs)
    return held


TIMER_HZ = 1e6
SAMPLE_DELAY_TICKS = 50
SLOW_DELAY_TICKS = 100
CONVERSION_TICKS = 5
#: MISO is valid this long after it changes; above 1/(2·45 ns) ≈ 11.1 MHz the host samples stale bits.
MISO_VALID_DELAY_S = 45e-9


def late_bits(half_period_s: float) -> int:
    """How many bits late the host samples MISO at this SCK half period (0 within spec).

    The host samples at the k-th rising edge, h·(2k+1), the line as it was 45 ns before: bit
    k + ⌊(h − 45 ns)/(2h)⌋.
    """
    return max(0, -math.floor((half_period_s - MISO_VALID_DELAY_S) / (2 * half_period_s) + 1e-9))

SELECT_CODE = {1: 0b001, 2: 0b010, 3: 0b100, 4: 0b101, 5: 0b110}
SELECT_ALL, SELECT_NONE = 0b111, 0b000

CMD_READ_PROPERTY, CMD_WRITE, CMD_RESEND, CMD_RESEND_MANUAL = 0x61, 0x40, 0x20, 0x50
WRITABLE_PARAMETERS = 4  # N = 0..3 are writable user registers (model choice)
RESERVED_VALUE = 7

PROP_FLEX, PROP_FIRMWARE, PROP_SERIAL, PROP_CPU, PROP_FS, PROP_PATTERN = 0x10, 0x13, 0x15, 0x61, 0x70, 0x73


def ticks(t: float) -> int:
    """The sensor timer's count at instant ``t`` (s): ⌊t·10⁶⌋, with 1 ns of slack for float rounding."""
    return int(math.floor(t * TIMER_HZ + 1e-3))


def ticks_array(t: np.ndarray) -> np.ndarray:
    return np.floor(np.asarray(t, float) * TIMER_HZ + 1e-3).astype(np.int64)


#: Serial-number prefix of each variant: the host library decides a sensor is present by "BT"; the SP's serials
#: start "BTSP" (Shadow Robot, sr-ros-interface issue #377: "Serial number starts with BTSP instead of BT2P").
SERIAL_PREFIX = {"biotac": "BT0101", "biotac-sp": "BTSP01"}
#: (flex version, firmware version) strings of each variant (model choice: the SP's are not published).
VERSIONS = {"biotac": (b"20", b"0206"), "biotac-sp": (b"SP", b"0300")}
SERIAL_LENGTH = 16


def default_serial(index: int = 1, variant: str = ch.DEFAULT_VARIANT) -> str:
    """The 16-character serial number of sensor ``index`` of a variant (``BT0101EMU0000001``, ``BTSP01EMU0000001``)."""
    return f"{SERIAL_PREFIX[ch.variant(variant).name]}EMU00000{index:02d}"


def check_serial(serial: str) -> bytes:
    """The serial as ASCII bytes, refusing what a host could not read back: must start "BT", 2..16 printable
    characters, no NUL (the string ends at NUL)."""
    if not isinstance(serial, str) or not serial.startswith("BT") or not 2 <= len(serial) <= SERIAL_LENGTH \
            or not all(0x20 < ord(c) < 0x7F for c in serial):
        raise ValueError(f"serial {serial!r}: must be 2..{SERIAL_LENGTH} printable ASCII characters (no spaces) "
                         f"starting with \"BT\" (the host library's presence check)")
    return serial.encode("ascii")


def serial_variant_problem(serial: str, variant: str = ch.DEFAULT_VARIANT) -> str | None:
    """Why a sensor of ``variant`` cannot answer ``serial`` (None if it can): a serial starting "BTSP" is what a
    host tells a BioTac SP by (firmware ``has_bt_serial``), so a sensor of another variant answering it would be
    taken for an SP and asked for electrodes it does not have."""
    sp_prefix = SERIAL_PREFIX["biotac-sp"][:4]
    v = ch.variant(variant).name
    if v == "biotac-sp" or not isinstance(serial, str) or not serial.startswith(sp_prefix):
        return None
    from emulator.units import seed_of_serial, serial_for

    hint = f'a serial not starting "{sp_prefix}"'
    try:
        seed = seed_of_serial(serial)
    except ValueError:  # a seed out of range: the serial is refused by name where it is given
        seed = None
    if seed is not None and variant_serial(serial_for(seed), "biotac-sp") == serial:  # an SP's form of unit `seed`
        hint = f'unit = {seed} (or "{serial_for(seed)}")'
    return (f'serial "{serial}" starts "{sp_prefix}", which a host reads as a BioTac SP\'s (E1..E24), but this sensor '
            f'is a "{v}" (E1..E{ch.variant(v).n_electrodes}): give variant = "biotac-sp", or {hint}')


def variant_serial(serial: str, variant: str = ch.DEFAULT_VARIANT) -> str:
    """The serial a sensor of ``variant`` reports for a unit's serial number: unchanged, except that a BioTac SP's
    must start "BTSP" (the host tells the variants apart by it: firmware ``has_bt_serial``), so an SP unit whose
    serial does not is reported as "BTSP" + the last 12 characters after its "BT" (``BTU0000000000005`` ->
    ``BTSP000000000005``).  A sensor of another variant whose serial starts "BTSP" is refused
    (:func:`serial_variant_problem`): a host would take it for an SP and ask it for E20..E24."""
    sp_prefix = SERIAL_PREFIX["biotac-sp"][:4]
    if problem := serial_variant_problem(serial, variant):
        raise ValueError(problem)
    if ch.variant(variant).name != "biotac-sp" or serial.startswith(sp_prefix):
        return serial
    return sp_prefix + serial[2:][-(SERIAL_LENGTH - len(sp_prefix)):]


def default_properties(index: int = 1, variant: str = ch.DEFAULT_VARIANT,
                       serial: str | None = None) -> dict[int, tuple[bytes, bool]]:
    """Property id -> (bytes, is_string) for sensor ``index`` (1–5) of a variant. Strings are sent with a NUL.

    ``serial`` overrides the serial number (each manufacturing unit its own); it must start with "BT".
    The sampling-pattern property holds the variant's default frame (44 commands, 54 on the SP).
    """
    v = ch.variant(variant)
    pattern = _pattern(v.name)
    flex, firmware = VERSIONS[v.name]
    return {
        PROP_FLEX: (flex, True),
        PROP_FIRMWARE: (firmware, True),
        PROP_SERIAL: (check_serial(default_serial(index, v.name) if serial is None else serial), True),
        PROP_CPU: ((40000).to_bytes(2, "big"), False),  # kHz: 40 MIPS dsPIC33
        PROP_FS: ((4400).to_bytes(2, "big"), False),
        PROP_PATTERN: (pattern, True),
    }


@functools.lru_cache(maxsize=None)
def _pattern(variant: str) -> bytes:
    """The sampling commands of a variant's default frame (the sampling-pattern property's bytes)."""
    v = ch.variant(variant)
    return bytes(int(proto.sample_command(v.channel_index[n])) for n in v.frame_names)


@dataclass
class Faults:
    """Faults of one sensor's SPI side; each is documented in docs/faults.md with what a host sees."""

    miso_flip_bit: int | None = None  # invert this bit position (from chip-select fall) of every transfer
    mosi_flip_bit: int | None = None  # the sensor receives this bit position inverted
    miso_stuck: int | None = None  # MISO stuck at 0 or 1
    bad_parity: bool = False  # data words leave with the first byte's parity bit inverted
    slow_response: bool = False  # results take 100 µs instead of 50 µs

    def __post_init__(self):
        self.miso_flip_bit = _fault_value("miso_flip_bit", self.miso_flip_bit, range(16),
                                          "None or a bit position 0 to 15 (from chip-select fall)")
        self.mosi_flip_bit = _fault_value("mosi_flip_bit", self.mosi_flip_bit, range(16),
                                          "None or a bit position 0 to 15 (from chip-select fall)")
        self.miso_stuck = _fault_value("miso_stuck", self.miso_stuck, (0, 1), "None, 0 or 1")
        for name in ("bad_parity", "slow_response"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"Faults.{name} = {getattr(self, name)!r}: must be True or False")

    @property
    def any(self) -> bool:
        """Whether any fault is set (bit 0 and stuck-at-0 count: they are faults too)."""
        return (self.miso_flip_bit is not None or self.mosi_flip_bit is not None or self.miso_stuck is not None
                or self.bad_parity or self.slow_response)


def _fault_value(name: str, value, allowed, what: str) -> int | None:
    """A fault setting as an int, or None (no fault); refused outside ``allowed`` (a bool is not a number here)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) not in allowed:
        raise ValueError(f"Faults.{name} = {value!r}: must be {what}")
    return int(value)


@dataclass
class Transfer:
    """One stretch of clocking with chip select asserted: ``nbits`` bits of ``mosi`` (MSB first)."""

    start_s: float
    cs: int = SELECT_CODE[1]
    mosi: int = 0
    nbits: int = 16
    clock_hz: float = proto.HOST_DEFAULT_CLOCK_HZ
    keep_cs: bool = False

    @property
    def period_s(self) -> float:
        return 1.0 / self.clock_hz

    @property
    def end_s(self) -> float:
        return self.start_s + (self.nbits + 0.5) * self.period_s


@dataclass
class _Prepared:
    kind: str  # "word", "pending" (a conversion not yet resolved) or "property"
    ready_tick: int
    word: int = 0
    data: bytes = b""
    is_string: bool = False
    consumed: bool = False
    sample: bool = False  # a sampling result: ``bad_parity`` inverts its parity bit as it is served


class SensorPort:
    """One sensor's SPI peripheral. ``sensor`` serves ADC codes: ``sample(channels, times, bus_active)``.
    Without ``properties`` the port serves its variant's defaults with the sensor's own serial number
    (``sensor.serial``, set on scene-built sensors; :func:`variant_serial`), or sensor ``index``'s default one."""

    def __init__(self, sensor, index: int = 1, faults: Faults | None = None, properties=None):
        self.sensor = sensor
        self.index = index
        self.faults = Faults() if faults is None else faults
        self.variant = ch.variant(getattr(sensor, "variant", ch.DEFAULT_VARIANT))
        self.recognized = self.variant.sampled_channels  # channels this variant has (others answer EX)
        serial = getattr(sensor, "serial", None)  # a unit's own serial (scene-built sensors); None: the default
        self.properties = properties or default_properties(
            index, self.variant.name, serial=None if serial is None else variant_serial(serial, self.variant.name))
        self.provided = frozenset(int(c) for c in sensor.channels_read) & self.recognized
        self.provided_lut = np.zeros(64, dtype=bool)
        self.provided_lut[list(self.provided)] = True
        self.conversion_s = sensor.params.adc_conversion_s
        self.reset()
        # counters a report can show
        self.incomplete = 0
        self.empty_windows = 0  # chip-select windows with no clock edge (a glitch on the line: ignored)
        self.unprovided_requests = 0
        self.coupled_conversions = 0


    @property
    def faults(self) -> Faults:
        """The SPI faults in force (``port.faults = Faults(...)``; ``Faults()`` clears them): on the software bus
        from the next transfer, over the RTL from the bus's next transfer too."""
        return self._faults

    @faults.setter
    def faults(self, faults) -> None:
        if not isinstance(faults, Faults):
            raise ValueError(f"sensor {self.index}: faults = {faults!r:.80}: must be an emulator.spi.model.Faults, "
                             f"e.g. Faults(bad_parity=True), Faults(miso_stuck=1); Faults() clears them")
        self._faults = faults
    def reset(self) -> None:
        """Power-on state: nothing prepared, nothing to resend, the writable registers 0 (as the RTL's reset clears
        them; the ``reset`` fault calls this mid-stream).

        A conversion already started completes (the ADC is not reset); its result is never served.
        """
        self.registers = [0] * WRITABLE_PARAMETERS
        self.prepared: _Prepared | None = None
        self.last_sent: int | None = None
        self.last_sampling_tick: int | None = None
        self._deferred: tuple[int, float] | None = getattr(self, "_deferred", None)  # (channel, instant)
        self._window_open = False
        self._out = b""
        self._out_fill = 0
        self._served_word = 0  # the data word the open window serves (what a read of it keeps for resend)
        self._bitpos = 0
        self._rx = 0
        self._delivered_full_word = False

    # --- conversions ----------------------------------------------------------------
    def resolve_conversion(self, next_activity_s: float) -> None:
        """Convert a pending sample now that the next SPI activity on the bus is known."""
        if self._deferred is None:
            return
        channel, t = self._deferred
        self._deferred = None
        coupled = next_activity_s < t + self.conversion_s
        self.coupled_conversions += int(coupled)
        code = int(self.sensor.sample(np.array([channel]), np.array([t]), bus_active=np.array([coupled]))[0])
        if self.prepared is not None and self.prepared.kind == "pending":
            self.prepared.kind = "word"
            self.prepared.word = int(proto.RESPONSE_WORD[code])  # (parity fault applied as it is served)

    def _data_word(self, value: int) -> int:
        """A write's acknowledgement word: the parity fault in force when the write is taken (as the RTL's)."""
        word = int(proto.RESPONSE_WORD[value])
        return word ^ 0x0100 if self.faults.bad_parity else word

    # --- chip select and clocking -------------------------------------------------------
    def cs_fall(self, t: float) -> None:
        """Chip select asserted at ``t``: choose what MISO will carry."""
        self._window_open = True
        self._bitpos = 0
        self._rx = 0
        self._delivered_full_word = False
        p = self.prepared
        delay = SLOW_DELAY_TICKS if self.faults.slow_response else SAMPLE_DELAY_TICKS
        self._serving = False
        if p is None or p.consumed:
            self._out, self._out_fill = proto.ERROR_WORDS["nothing_to_resend"].to_bytes(2, "big"), 0x00
        elif ticks(t) - p.ready_tick < delay:
            self._out, self._out_fill = proto.ERROR_WORDS["insufficient_delay"].to_bytes(2, "big"), 0x00
        elif p.kind == "property":
            self._out = p.data + (b"\x00" if p.is_string else b"")
            self._out_fill = 0xFF
            self._serving = True
        else:
            # a sampling result takes the parity fault in force as it leaves (the RTL's word at chip-select fall),
            # so a fault set or cleared between a conversion and its read acts on that read
            self._served_word = p.word ^ 0x0100 if p.sample and self.faults.bad_parity else p.word
            self._out, self._out_fill = self._served_word.to_bytes(2, "big"), 0x00
            self._serving = True

    def miso_bit(self, pos: int) -> int:
        """The bit this sensor drives at position ``pos`` of the open window (faults applied)."""
        f = self.faults
        byte_i, bit_i = divmod(pos, 8)
        byte = self._out[byte_i] if byte_i < len(self._out) else self._out_fill
        bit = (byte >> (7 - bit_i)) & 1
        if f.miso_flip_bit is not None and pos == f.miso_flip_bit:
            bit ^= 1
        if f.miso_stuck is not None:
            bit = f.miso_stuck
        return bit

    @property
    def position(self) -> int:
        """Bits clocked so far in the open window."""
        return self._bitpos

    def clock(self, mosi: int, nbits: int) -> int:
        """Shift ``nbits`` bits: returns the MISO bits this sensor drives (MSB first)."""
        miso = 0
        f = self.faults
        for k in range(nbits):
            pos = self._bitpos + k
            miso = (miso << 1) | self.miso_bit(pos)
            rx_bit = (mosi >> (nbits - 1 - k)) & 1
            if f.mosi_flip_bit is not None and pos == f.mosi_flip_bit:
                rx_bit ^= 1
            if pos < 16:
                self._rx = (self._rx << 1) | rx_bit
        self._bitpos += nbits
        return miso

    def cs_rise(self, t: float) -> None:
        """Chip select released at ``t``: act on what was received."""
        self._window_open = False
        n = self._bitpos
        if n < 8:
            if n:
                self.incomplete += 1
            else:
                self.empty_windows += 1
            return
        b0 = (self._rx >> (min(n, 16) - 8)) & 0xFF
        if b0 == 0x00:  # a read
            p = self.prepared
            if self._serving and p is not None:
                if p.kind == "property":
                    p.consumed = True
                elif n >= 16:
                    p.consumed = True
                    self.last_sent = self._served_word  # resent as it was read
            return
        if n < 16:
            self.incomplete += 1
            return
        b1 = self._rx & 0xFF
        self._command(b0, b1, t)

    def _prepare_word(self, word: int, t: float) -> None:
        self.prepared = _Prepared("word", ticks(t), word=word)

    def _command(self, b0: int, b1: int, t: float) -> None:
        err = proto.ERROR_WORDS
        if b0 in (CMD_RESEND, CMD_RESEND_MANUAL):
            self._prepare_word(self.last_sent if self.last_sent is not None else err["nothing_to_resend"], t)
        elif not proto.ODD_PARITY_OK[b0]:
            self._prepare_word(err["parity"], t)
        elif b0 & 0x80:
            channel = (b0 >> 1) & 0x3F
            if channel not in self.recognized:
                self._prepare_word(err["channel_not_recognized"], t)
                return
            now = ticks(t)
            busy = self.last_sampling_tick is not None and now - self.last_sampling_tick < CONVERSION_TICKS
            self.last_sampling_tick = now
            if busy:
                self._prepare_word(err["insufficient_sampling_delay"], t)
            elif channel not in self.provided:
                self.unprovided_requests += 1
                self._prepare_word(err["channel_not_recognized"], t)
            else:
                self.prepared = _Prepared("pending", now, sample=True)
                self._deferred = (channel, t)
        elif b0 == CMD_READ_PROPERTY:
            if b1 in self.properties:
                data, is_string = self.properties[b1]
                self.prepared = _Prepared("property", ticks(t), data=data, is_string=is_string)
            else:
                self._prepare_word(err["channel_not_recognized"], t)
        elif b0 == CMD_WRITE:
            n, v = b1 >> 4, (b1 >> 1) & 0x7
            if not proto.ODD_PARITY_OK[b1]:
                self._prepare_word(err["parity"], t)
            elif n >= WRITABLE_PARAMETERS:
                self._prepare_word(err["read_only"], t)
            elif v == RESERVED_VALUE:
                self._prepare_word(err["write_error"], t)
            else:
                self.registers[n] = v
                self._prepare_word(self._data_word(n * 8 + v), t)
        else:
            self._prepare_word(err["unknown_command"], t)

    # --- a sensor alone on its bus (the host sampler's path) ------------------------------
    @whole_call
    def exchange(self, batch) -> np.ndarray:
        """MISO words for a batch of 16-bit transfers to this sensor alone (``TransferBatch``).

        Runs of plain sampling commands and reads go through a vectorized routine; anything else
        (properties, resend, writes, faults, a property in progress) through the transfer-level path.
        """
        from emulator.spi.fastpath import exchange_words, is_plain

        start, mosi, clock, end = checked_batch(batch, getattr(self, "_last_end", -np.inf))
        if start.size == 0:
            return np.zeros(0, np.uint16)
        if is_plain(self, mosi):
            miso = exchange_words(self, start, end, mosi)
        else:
            bus = Bus({self.index: self})
            miso = np.array([bus.transfer(Transfer(float(s), SELECT_CODE.get(self.index, 1), int(m), 16, float(c)))
                             for s, m, c in zip(start, mosi, clock)], dtype=np.uint16)
        self._last_end = float(end[-1])
        return miso


def checked_transfer_ends(start, nbits, clock, previous_end_s: float, clock_range=None) -> np.ndarray:
    """When each transfer of a call releases chip select (s): start + (nbits + ½)/clock.  The one check of a call's
    transfers, on every bus and port: a ValueError naming the first transfer (its place in the call), what is wrong
    with it and what is allowed — a start that is not a finite time (s), bits < 0, a clock (Hz) that is not finite
    and > 0 (or outside ``clock_range`` = (lo, hi) Hz, where a caller serves only those), or a start before the
    transfer before it ended (in this call, or ``previous_end_s``: the previous call's last), within
    ``protocol.TIME_TOLERANCE_S``."""
    start = np.atleast_1d(np.asarray(start, float))
    nbits = np.broadcast_to(np.asarray(nbits), start.shape)
    clock = np.broadcast_to(np.asarray(clock, float), start.shape)
    if not start.size:
        return start
    if clock_range is None:
        bad_clock, allowed = ~(clock > 0) | ~np.isfinite(clock), "a finite frequency > 0"
    else:
        lo, hi = clock_range
        bad_clock, allowed = ~((clock >= lo) & (clock <= hi)), f"{lo:.0f}–{hi:.0f} Hz (SENSOR.md §6)"
    problems = ((~np.isfinite(start), lambda k: f"start_s = {float(start[k])!r}: must be a finite time (s)"),
                (nbits < 0, lambda k: f"{int(nbits[k])} bits: must be 0 or more"),
                (bad_clock, lambda k: f"SCK {float(clock[k]):.10g} Hz: must be {allowed}"))
    for bad, says in problems:
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise ValueError(f"transfer #{k} of the call: {says(k)}")
    end = start + (nbits + 0.5) / clock
    before = np.concatenate(([previous_end_s], end[:-1]))
    early = np.flatnonzero(start < before - proto.TIME_TOLERANCE_S)
    if early.size:
        k = int(early[0])
        after = (f"the previous call's last transfer ended ({previous_end_s:.9g} s)" if k == 0 else
                 f"transfer #{k - 1} (from {start[k - 1]:.9g} s) ends at {end[k - 1]:.9g} s")
        raise ValueError(f"transfer #{k} of the call starts at {start[k]:.9g} s, before {after}: transfers must be in "
                         f"time order and must not overlap (a transfer holds chip select for its bits + ½ SCK "
                         f"periods)")
    return end


def checked_batch(batch, previous_end_s: float):
    """A lone sensor's batch of 16-bit transfers (a ``TransferBatch``) as arrays — start s, MOSI words, SCK Hz (one
    per transfer) — and when each ends (s), checked by :func:`checked_transfer_ends` within the SPI clock range (a
    lone sensor's host clocks within spec: the buses count a clock outside it, ``out_of_spec_transfers``), and one
    MOSI word per start.  The same check for every lone-sensor route (:meth:`SensorPort.exchange`, the RTL's
    ``HarnessPeripheral``)."""
    start = np.atleast_1d(np.asarray(batch.start_s, float))
    mosi = np.atleast_1d(np.asarray(batch.mosi, dtype=np.uint16))
    if start.shape != mosi.shape:
        raise ValueError(f"a batch of {start.size} start times and {mosi.size} MOSI words: one word per start")
    clock = np.broadcast_to(np.asarray(batch.clock_hz, float), start.shape)
    return start, mosi, clock, checked_transfer_ends(start, 16, clock, previous_end_s, proto.SPI_CLOCK_RANGE_HZ)


#: What a sensor's port counts (on every bus, and on a lone sensor's port): chip-select windows with fewer bits than
#: the sensor acts on (``incomplete``), with no clock edge (``empty_windows``), sampling commands for a channel the
#: sensor recognises but does not provide (``unprovided_requests``), conversions the bus clocked into
#: (``coupled_conversions``).
PORT_COUNTERS = ("incomplete", "empty_windows", "unprovided_requests", "coupled_conversions")


@dataclass
class Bus:
    """Up to five sensors sharing SCK, MOSI and MISO, selected by a 3-bit code.

    ``ports`` maps sensor number (1–5) to its :class:`SensorPort`; a number with no port is an absent
    sensor.  MISO is the OR of the sensors driving it; with nobody driving it idles at 0
    (``pull_up=False``) or 1, so an absent sensor reads back 0x00 or 0xFF bytes.  Removing a port unplugs the
    sensor, also with chip select held on it (its window goes with it: nothing it received is acted on); a port
    put in plugs one in, which sees chip select fall at the next transfer that selects it.
    """

    ports: dict[int, SensorPort]
    pull_up: bool = False
    out_of_spec_transfers: int = 0
    _selected: dict = field(default_factory=dict)  # sensor -> its port, while chip select is held on it
    _last_end: float = -math.inf
    _open: bool = False
    _line: list = field(default_factory=list)  # recent (time, level) changes of the MISO line

    def __post_init__(self):
        first: dict[int, int] = {}  # id of a port object -> the first sensor number it was given
        for n, p in self.ports.items():
            if id(p) in first:  # one port answering two selects: each window would garble the other's state
                raise ValueError(f"Bus: sensors {first[id(p)]} and {n} are the same SensorPort object: each sensor "
                                 f"number needs a port (and a sensor) of its own")
            first[id(p)] = n

    def close(self) -> None:
        """Nothing to release (a bus backed by a simulator process, like the RTL one, stops it here)."""

    def _level(self, selected: set[int], pos_of=None) -> int:
        """The MISO line level while ``selected`` sensors drive their next bits (OR), or the pull level."""
        if not selected:
            return int(self.pull_up)
        level = 0
        for n in selected:
            p = self.ports[n]
            level |= p.miso_bit(p.position if pos_of is None else pos_of)
        return level

    def _record(self, t: float, level: int) -> None:
        self._line.append((t, level))
        if len(self._line) > 256:
            del self._line[:128]

    def _line_at(self, t: float) -> int:
        for when, level in reversed(self._line):
            if when <= t:
                return level
        return int(self.pull_up)

    def selected_by(self, code: int) -> set[int]:
        if code == SELECT_ALL:
            return set(self.ports)
        return {n for n, c in SELECT_CODE.items() if c == code and n in self.ports}

    @whole_call
    def transfer(self, tr: Transfer) -> int:
        """Clock one transfer; returns the MISO bits the host samples (``nbits`` bits, MSB first)."""
        if not (tr.nbits >= 0 and 0 < tr.clock_hz < math.inf and math.isfinite(tr.start_s)
                and tr.start_s >= self._last_end - proto.TIME_TOLERANCE_S):  # (scalar test first: per-transfer path)
            checked_transfer_ends(tr.start_s, tr.nbits, tr.clock_hz, self._last_end)
        lo, hi = proto.SPI_CLOCK_RANGE_HZ
        if not lo <= tr.clock_hz <= hi:
            self.out_of_spec_transfers += 1
        for port in self.ports.values():
            port.resolve_conversion(tr.start_s)
        now = self.selected_by(tr.cs)
        # a sensor unplugged (or its port replaced) with chip select held on it took its window along: nothing is
        # left to see chip select rise, and the one plugged in sees it fall as the held select code reaches it
        held = {n for n, port in self._selected.items() if self.ports.get(n) is port}
        for n in held - now:  # select code changed with chip select held: those sensors see CS rise
            self.ports[n].cs_rise(tr.start_s)
        for n in now - held if self._open else now:
            self.ports[n].cs_fall(tr.start_s)
        # the line: first bit (or pull level) from chip-select fall, the next bit at every falling edge
        self._record(tr.start_s, self._level(now))
        first_pos = {n: self.ports[n].position for n in now}
        bits = [self.ports[n].clock(tr.mosi, tr.nbits) for n in sorted(now)]
        miso = 0
        for b in bits:
            miso |= b
        if not now and self.pull_up:
            miso = (1 << tr.nbits) - 1
        T = tr.period_s
        for k in range(tr.nbits):
            level = int(self.pull_up) if not now else 0
            for n in now:
                level |= self.ports[n].miso_bit(first_pos[n] + k + 1)
            self._record(tr.start_s + (k + 1) * T, level)
        if late_bits(T / 2):  # the host samples the line as it was 45 ns before each rising edge
            miso = 0
            for k in range(tr.nbits):
                miso = (miso << 1) | self._line_at(tr.start_s + (k + 0.5) * T - MISO_VALID_DELAY_S)
        self._last_end = tr.end_s
        if tr.keep_cs:
            self._selected, self._open = {n: self.ports[n] for n in now}, True
        else:
            for n in now:
                self.ports[n].cs_rise(tr.end_s)
            self._selected, self._open = {}, False
            self._record(tr.end_s, int(self.pull_up))
        return miso

    def run(self, transfers) -> list[int]:
        return [self.transfer(t) for t in transfers]

    @whole_call
    def exchange_words(self, start, cs, mosi, clock_hz, keep_cs=None) -> np.ndarray:
        """MISO for a batch of 16-bit transfers with select codes ``cs`` (the firmware's usual traffic).

        Plain word traffic to any set of sensors is split per sensor and evaluated with each port's
        vectorized path (a transfer with chip select held into the next one, the select code switching, is the
        same for each sensor as two separate windows); anything else goes transfer by transfer.
        """
        from emulator.spi.fastpath import exchange_words, is_plain

        start = np.asarray(start, float)
        cs = np.asarray(cs, dtype=np.int64)
        mosi = np.asarray(mosi, dtype=np.uint16)
        clock = np.broadcast_to(np.asarray(clock_hz, float), start.shape)
        keep = np.zeros(start.shape, bool) if keep_cs is None else np.asarray(keep_cs, bool)
        if start.size == 0:
            return np.zeros(0, np.uint16)
        end = checked_transfer_ends(start, 16, clock, self._last_end)
        lo, hi = proto.SPI_CLOCK_RANGE_HZ
        selected = {n: (cs == SELECT_ALL) | (cs == SELECT_CODE[n]) for n in self.ports}
        same_sensor_held = any(np.any(keep[:-1] & sel[:-1] & sel[1:]) for sel in selected.values())
        plain = (not self._open and not keep[-1] and clock.min() >= lo and clock.max() <= hi and not same_sensor_held
                 and all(is_plain(p, mosi[selected[n]]) for n, p in self.ports.items()))  # (times: checked above)
        if not plain:
            return np.array([self.transfer(Transfer(float(t), int(c), int(m), 16, float(f), bool(k)))
                             for t, c, m, f, k in zip(start, cs, mosi, clock, keep)], dtype=np.uint16)
        for port in self.ports.values():
            port.resolve_conversion(float(start[0]))
        # a transfer holding chip select into one that selects other sensors (or none) is its sensors' window until
        # that one starts, as on the transfer-level path: its command acts then, and the bus's next activity after
        # it is the transfer after that one
        next_bus = np.append(start[1:], np.inf)
        rise = np.where(keep, next_bus, end)
        after = np.where(keep, np.append(start[2:], [np.inf, np.inf])[:start.size], next_bus)
        miso = np.zeros(start.shape, dtype=np.uint16)
        anyone = np.zeros(start.shape, bool)
        for n, port in self.ports.items():
            sel = selected[n]
            if sel.any():
                miso[sel] |= exchange_words(port, start[sel], rise[sel], mosi[sel], after[sel])
                anyone |= sel
        if self.pull_up:
            miso[~anyone] = 0xFFFF
        self._last_end = float(end[-1])
        self._record(float(end[-1]), int(self.pull_up))  # (the line history matters only for late sampling)
        return miso

    def flush(self, t_s: float = math.inf) -> None:
        """Resolve pending conversions (no further bus activity before ``t_s``)."""
        for port in self.ports.values():
            port.resolve_conversion(t_s)
