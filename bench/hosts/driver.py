"""Host driver for the bridge firmware's serial stream (protocol in firmware_tests/firmware/bt_bridge.h).

:class:`FrameParser` turns bytes into frames: it hunts for the 0xAA 0x55 sync, checks the length and the
CRC-16, and after corruption resynchronises on the next sync, counting what it skipped.  Sequence numbers
reveal dropped frames (:class:`SequenceTracker`: robust to reordering, duplicates, the 16-bit counter's
wrap-around and gaps longer than it).  :class:`BridgeDriver` runs the parser on a pyserial port (a device path,
or URLs such as ``loop://`` and ``socket://host:port``), sends commands and matches each reply to the command
that asked for it, and offers an iterator and a callback API.
"""

from __future__ import annotations

import binascii
import math
import struct
import time
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from emulator import conversions as conv

SYNC = b"\xaa\x55"
T_DATA, T_STATUS, T_ACK = 0x10, 0x11, 0x12
CMD_START, CMD_STOP, CMD_PATTERN, CMD_STATUS = 0x01, 0x02, 0x03, 0x04
MAX_PAYLOAD = 4 + 64 * (1 + 2 * 5)
#: The most channels a PATTERN may hold (the firmware's BT_MAX_PATTERN): a longer one is answered ACK 1 (bad length).
MAX_PATTERN = 64
ACK_RESULTS = {0: "ok", 1: "bad length", 2: "unknown command", 3: "bad value"}
SLOT_RATE_HZ = 4400.0  # the firmware's sampling slots: a frame of n slots lasts n / 4400 s
#: A command whose reply has not come within this many seconds is taken as lost (its reply, if it ever comes,
#: is then matched to a later command of the same type, or counted as unsolicited).
REPLY_HORIZON_S = 5.0
#: Data frames read but not yet taken by :meth:`BridgeDriver.frames` are kept, oldest first, up to this many (60 s
#: of 44-slot frames); beyond it the oldest are discarded and counted in ``BridgeDriver.backlog_discarded``.
BACKLOG_FRAMES = 6000


def _crc16_bitwise(data: bytes) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final XOR), bit by bit: the reference."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def _crc16_table(data: bytes) -> int:
    return binascii.crc_hqx(data, 0xFFFF)


#: CRC-16/CCITT-FALSE of ``data``.  The standard library's ``binascii.crc_hqx`` is the same CRC (polynomial
#: 0x1021, MSB first, no final XOR: CRC-16/XMODEM's algorithm) and, started from 0xFFFF, gives CCITT-FALSE —
#: table-driven C, ~1000x the bitwise loop.  It is used only if it agrees with the bitwise reference on the
#: standard check input "123456789" (0x29B1), so the reference stays the definition.
crc16 = _crc16_table if _crc16_table(b"123456789") == _crc16_bitwise(b"123456789") else _crc16_bitwise


def encode(frame_type: int, payload: bytes = b"") -> bytes:
    body = bytes([frame_type]) + struct.pack("<H", len(payload)) + payload
    return SYNC + body + struct.pack("<H", crc16(body))


class FrameChannels(dict):
    """A frame's codes by channel name: a channel it does not carry is a KeyError naming the ones it does."""

    def __missing__(self, name):
        raise KeyError(f"{name!r}: not in this frame's pattern; it carries {', '.join(self) or 'no channel'} "
                       f"(set the pattern with BridgeDriver.set_pattern, or the bench's pattern=)")


@dataclass
class DataFrame:
    """One frame of samples: ``codes[slot, sensor]`` (12 bits) and ``status`` (0 ok, 1 parity, 2 error word);
    ``t_s[slot]``: the virtual time (s from the emulated bridge's power-on) of each slot's sample, from a
    :class:`BridgeDriver` given ``sample_times=`` (:meth:`bench.hosts.bridge.FirmwareBench.sample_times`), else None
    (the wire carries no time)."""

    seq: int
    sensor_mask: int
    channels: np.ndarray
    codes: np.ndarray
    status: np.ndarray
    t_s: np.ndarray | None = None

    @property
    def sensors(self) -> list[int]:
        return [n for n in range(1, 6) if self.sensor_mask >> (n - 1) & 1]

    @property
    def ok(self) -> np.ndarray:
        """``ok[slot, sensor]``: the slot carries a code (status 0); an error word or a parity error never does."""
        return self.status == 0

    def _column(self, sensor) -> int:
        """The codes' column of ``sensor`` (a number 1–5 in this frame's mask); ValueError naming those present."""
        if sensor not in self.sensors or isinstance(sensor, bool):
            raise ValueError(f"sensor {sensor!r} is not in this frame (sensor mask 0x{self.sensor_mask:02X}: sensors "
                             f"{self.sensors or 'none'}; numbered from 1)")
        return self.sensors.index(sensor)

    def samples(self, sensor: int) -> dict[str, np.ndarray]:
        """Sensor ``sensor``'s codes by channel name (PAC, E20 …), only the slots with status 0; a channel the frame
        does not carry is a KeyError naming the channels it does."""
        k = self._column(sensor)
        out = FrameChannels()
        for name in dict.fromkeys(channel_name(c) for c in self.channels):
            sel = (np.array([channel_name(c) for c in self.channels]) == name) & self.ok[:, k]
            out[name] = self.codes[sel, k]
        return out

    def errors(self, sensor: int) -> list[tuple[int, str, str]]:
        """Sensor ``sensor``'s failed slots: (slot, channel name, "error word" or "parity error") — e.g. E20..E24
        asked of a 19-electrode BioTac, which answers each with its "channel not recognized" error word."""
        k = self._column(sensor)
        return [(int(i), channel_name(self.channels[i]), STATUS_NAMES[int(self.status[i, k])])
                for i in np.flatnonzero(self.status[:, k] != 0)]


#: The firmware's per-sample status codes.
STATUS_NAMES = {0: "ok", 1: "parity error", 2: "error word"}


def channel_name(index: int) -> str:
    """Name of a channel index of either variant (E1..E24 = 17..40), else ``"ch<index>"``."""
    from emulator.channels import variant

    return variant("biotac-sp").channel_name.get(int(index), f"ch{int(index)}")


@dataclass
class Status:
    sensor_mask: int
    streaming: bool
    frames: int
    parity_errors: int
    error_words: int
    losses: int
    finds: int
    command_errors: int
    sp_mask: int = 0  # bit n-1: sensor n is a BioTac SP (serial "BTSP…"); firmwares before the SP omit it

    @property
    def sp_sensors(self) -> list[int]:
        return [n for n in range(1, 6) if self.sp_mask >> (n - 1) & 1]


@dataclass
class ParserStats:
    frames: int = 0
    crc_errors: int = 0
    bad_lengths: int = 0
    bytes_skipped: int = 0
    dropped_frames: int = 0  # frames missing from the sequence (a late frame that fills a gap is taken back out)
    resyncs: int = 0
    last_seq: int | None = None  # the newest sequence number seen (16 bits, as sent)
    malformed: int = 0
    reordered: int = 0  # frames that arrived after a later one (they are delivered, and filled their gap)
    duplicates: int = 0  # frames whose sequence number was already seen, or older than anything missing: not delivered


class SequenceTracker:
    """Counts the frames missing from the firmware's 16-bit sequence numbers.

    Sequence numbers are unwrapped into a running count.  A frame ahead of the newest one adds the frames in
    between to the missing ones; a frame behind it either fills a gap counted earlier (a reordered frame: it is
    taken back out of the missing count) or repeats one already seen (a duplicate).  A 16-bit counter cannot
    tell a gap of ``d`` frames from ``d + 65536·k``, nor a far jump ahead from a frame from the past: the
    arrival time decides, from the stream's measured frame rate (or the nominal one, 4400 slots/s divided by
    the frame's slots, before there is a measurement).
    """

    KEEP = 1 << 15  # missing frames are remembered (to recognise late arrivals) this far behind the newest

    def __init__(self, stats: ParserStats):
        self.stats = stats
        self.top: int | None = None  # unwrapped newest sequence number
        self.top_t = 0.0
        self._first: tuple[int, float] | None = None
        self._gaps: deque[list[int]] = deque()  # [first, end) of missing unwrapped numbers, ascending
        self._nominal_rate = 100.0

    def rate(self) -> float:
        """Frames per second of arrival time: measured over the stream (≥ 0.5 s of it), else nominal."""
        if self._first is not None and self.top is not None:
            n, t = self.top - self._first[0], self.top_t - self._first[1]
            if t >= 0.5 and n >= 10:
                return n / t
        return self._nominal_rate

    def _take_from_gap(self, u: int) -> bool:
        for i, (a, b) in enumerate(self._gaps):
            if a <= u < b:
                if a == u and b == u + 1:
                    del self._gaps[i]
                elif a == u:
                    self._gaps[i][0] = u + 1
                elif b == u + 1:
                    self._gaps[i][1] = u
                else:
                    self._gaps[i][1] = u
                    self._gaps.insert(i + 1, [u + 1, b])
                return True
        return False

    def _forget_old(self) -> None:
        floor = self.top - self.KEEP
        while self._gaps and self._gaps[0][1] <= floor:
            self._gaps.popleft()
        if self._gaps and self._gaps[0][0] < floor:
            self._gaps[0][0] = floor

    def accept(self, seq: int, now: float, slots: int = 44) -> bool:
        """Count frame ``seq`` arriving at ``now`` (s); False for a duplicate that should not be delivered."""
        if slots > 0:
            self._nominal_rate = SLOT_RATE_HZ / slots
        st = self.stats
        if self.top is None:
            self.top, self.top_t, self._first = seq, now, (seq, now)
            st.last_seq = seq
            return True
        d = (seq - self.top) & 0xFFFF  # ahead by d, or behind by 65536 - d
        behind = self.top + d - 0x10000
        if d >= 0x8000 and self._take_from_gap(behind):  # a late frame: up to 32 768 behind
            st.dropped_frames -= 1
            st.reordered += 1
            return True
        expected = max(0.0, now - self.top_t) * self.rate()  # frames the elapsed time says went by
        if (d == 0 or d >= 0x8000) and expected < 0x8000:  # behind the newest, and not one that was missing
            st.duplicates += 1
            return False
        wraps = max(0, math.floor((expected - d) / 0x10000 + 0.5))
        ahead = d + wraps * 0x10000 or 0x10000
        if ahead > 1:
            self._gaps.append([self.top + 1, self.top + ahead])
            st.dropped_frames += ahead - 1
        self.top += ahead
        self.top_t = now
        st.last_seq = seq
        self._forget_old()
        return True


@dataclass
class FrameParser:
    """Bytes in, frames out; survives any garbage."""

    stats: ParserStats = field(default_factory=ParserStats)
    _buf: bytearray = field(default_factory=bytearray)

    def __post_init__(self):
        self.sequence = SequenceTracker(self.stats)

    def count_afresh(self) -> None:
        """Start the statistics and the sequence tracking over from here (bytes already buffered are kept): what
        came before — a stream an earlier host left running, cut off mid-frame — is not this session's."""
        self.stats = ParserStats()
        self.sequence = SequenceTracker(self.stats)

    def feed(self, data: bytes, now: float | None = None) -> list:
        """Parse ``data`` (arriving at ``now``, monotonic seconds; default: the clock now)."""
        now = time.monotonic() if now is None else now
        self._buf += data
        out = []
        buf = self._buf
        while True:
            i = buf.find(SYNC)
            if i < 0:
                keep = 1 if buf.endswith(SYNC[:1]) else 0
                self._skip(len(buf) - keep)
                break
            if i:
                self._skip(i)
            if len(buf) < 5:
                break
            ftype, length = buf[2], struct.unpack_from("<H", buf, 3)[0]
            if length > MAX_PAYLOAD:
                self.stats.bad_lengths += 1
                self._skip(1)
                continue
            if len(buf) < 5 + length + 2:
                break
            body = bytes(buf[2:5 + length])
            if struct.unpack_from("<H", buf, 5 + length)[0] != crc16(body):
                self.stats.crc_errors += 1
                self._skip(1)
                continue
            payload = body[3:]
            del buf[:5 + length + 2]
            frame = self._decode(ftype, payload, now)
            if frame is not None:
                out.append(frame)
        return out

    def _skip(self, n: int) -> None:
        if n <= 0:
            return
        self.stats.resyncs += 1
        self.stats.bytes_skipped += n
        del self._buf[:n]

    def _decode(self, ftype: int, p: bytes, now: float):
        try:
            if ftype == T_DATA:
                seq, mask, slots = struct.unpack_from("<HBB", p)
                ns = bin(mask & 0x1F).count("1")
                if len(p) != 4 + slots * (1 + 2 * ns):
                    raise ValueError("data frame length does not match its header")
                rec = np.frombuffer(p[4:], dtype=np.uint8).reshape(slots, 1 + 2 * ns)
                words = rec[:, 1:].copy().view("<u2").reshape(slots, ns)
                if not self.sequence.accept(seq, now, slots):
                    return None
                self.stats.frames += 1
                return DataFrame(seq, mask, rec[:, 0].astype(int), (words & 0x0FFF).astype(np.uint16),
                                 (words >> 12).astype(np.uint8))
            if ftype == T_STATUS:
                mask, streaming, *counters = struct.unpack("<BB6I", p[:26])
                if len(p) not in (26, 27):
                    raise ValueError("status frame length")
                return Status(mask, bool(streaming), *counters, sp_mask=p[26] if len(p) == 27 else 0)
            if ftype == T_ACK:
                cmd, result = struct.unpack("<BB", p)
                return ("ack", cmd, result)
        except (struct.error, ValueError):
            self.stats.malformed += 1
            return None
        self.stats.malformed += 1
        return None


def to_physical(frame: DataFrame, pac_offset: float = 2048.0, pdc_offset: float | None = None) -> dict:
    """Published conversions of one frame: PAC in Pa, PDC in kPa (relative to ``pdc_offset``), TDC in °C,
    electrode impedances in Ω; per sensor, samples with a bad status are NaN."""
    out = {}
    for k, n in enumerate(frame.sensors):
        codes = frame.codes[:, k].astype(float)
        codes[frame.status[:, k] != 0] = np.nan
        by = {}
        for ch_index, name, fn in ((0, "PAC_Pa", lambda c: conv.pac_to_pa(c, pac_offset)),
                                   (1, "PDC_kPa", lambda c: conv.pdc_to_kpa(c, pdc_offset or 0.0)),
                                   (3, "TDC_C", conv.tdc_to_celsius)):
            sel = frame.channels == ch_index
            if sel.any():
                by[name] = fn(codes[sel])
        sel = frame.channels >= 17
        if sel.any():
            by["electrodes_ohm"] = dict(zip((f"E{c - 16}" for c in frame.channels[sel]), conv.impedance_ohm(codes[sel])))
        out[n] = by
    return out


class BridgeDriver:
    """The firmware's serial stream through pyserial: commands, frames as an iterator or by callback.

    Replies are matched to the command that asked for them: the firmware answers each command in order
    (an ACK carrying the command's type, or a STATUS for a STATUS request), so a reply goes to the oldest
    command of its type still waiting (commands unanswered for :data:`REPLY_HORIZON_S` are taken as lost),
    and :meth:`wait_for` returns the reply to the *latest* command of that type — never a stale reply to an
    earlier one.  Replies nobody asked for are counted in ``unsolicited_replies`` and dropped.

    Every data frame read, whoever read it (:meth:`frames`, :meth:`wait_for`, :meth:`poll`), goes to the callbacks
    at once and waits in a backlog until :meth:`frames` yields it: each frame is yielded once, in order, also
    across calls that stop at ``max_frames`` and across waits for a reply (:data:`BACKLOG_FRAMES` at most).
    """

    def __init__(self, port, baudrate: int = 3_000_000, timeout: float = 0.05, sample_times=None):
        """``sample_times``: None, or a callable giving a data frame's sample times (s, one per slot, or None), put in
        each frame's ``t_s`` as it is read: an emulated bridge's :meth:`~bench.hosts.bridge.FirmwareBench.sample_times`
        (``BridgeDriver(bench.port, sample_times=bench.sample_times)``)."""
        import serial

        if sample_times is not None and not callable(sample_times):
            raise ValueError(f"sample_times = {sample_times!r}: a callable taking a DataFrame (e.g. a FirmwareBench's "
                             f"bench.sample_times), or None")
        self.sample_times = sample_times

        if isinstance(port, str):
            # exclusive: a second host on the same port (two `record`s) is refused at open, rather than each
            # stealing the other's bytes and blaming the bridge
            self.serial = serial.serial_for_url(port, baudrate=baudrate, timeout=timeout, rtscts=False,
                                                dsrdtr=False, do_not_open=False, exclusive=True)
        else:
            self.serial = port
        self.parser = FrameParser()
        self.callbacks = []
        self.disconnected = False
        self.unsolicited_replies = 0
        self._sent = 0  # commands sent so far (each gets the next number)
        self._waiting: dict[int, deque] = {}  # command type -> deque of (number, time sent), oldest first
        self._latest: dict[int, int] = {}  # command type -> number of the latest command of that type
        self._answers: dict[int, object] = {}  # command number -> its reply
        self._backlog: deque = deque()  # data frames read, not yet yielded by frames(), oldest first
        self.backlog_discarded = 0  # frames dropped from a full backlog (nobody took them with frames())
        self._frames_read = 0  # data frames read so far (the backlog holds the last of them)
        self._reply_marks: dict[int, int] = {}  # command number -> data frames read before its reply

    def close(self) -> None:
        self.serial.close()

    def _check_open(self, what: str) -> None:
        """Refuse a call after :meth:`close` (pyserial's own error there was a TypeError about a file number)."""
        if not getattr(self.serial, "is_open", True):
            raise RuntimeError(f"BridgeDriver.{what}(): the driver's port {getattr(self.serial, 'port', '?')} is "
                               f"closed (close() was called); open a new BridgeDriver(port) to talk to the bridge")

    def send(self, frame_type: int, payload: bytes = b"") -> int:
        """Send a command frame; returns its number (for :meth:`reply_to`)."""
        self._check_open("send")
        self.serial.write(encode(frame_type, payload))
        self.serial.flush()
        self._sent += 1
        self._waiting.setdefault(frame_type, deque()).append((self._sent, time.monotonic()))
        self._latest[frame_type] = self._sent
        return self._sent

    def start(self) -> int:
        return self.send(CMD_START)

    def stop(self) -> int:
        return self.send(CMD_STOP)

    def set_pattern(self, channels) -> int:
        """Send PATTERN (channel indices 0–255 or names such as "PAC", "E7"; at most :data:`MAX_PATTERN`); the
        firmware ACKs 0, or 1 for an empty pattern and 3 for an index it does not sample.  A longer pattern is
        refused here (ValueError), sending nothing (the firmware would answer it ACK 1), and so is an entry that is
        not a byte (:meth:`pattern_bytes`)."""
        payload = self.pattern_bytes(channels)
        if len(payload) > MAX_PATTERN:
            raise ValueError(f"a pattern of {len(payload)} channels: the bridge firmware takes at most {MAX_PATTERN}")
        return self.send(CMD_PATTERN, payload)

    @staticmethod
    def pattern_bytes(channels) -> bytes:
        """The payload of a PATTERN command for ``channels``: each an index 0–255 (an int, numpy's too) or a channel
        name ("PAC", "e7").  An index no channel has (16, HAL's 15, 99) is sent: the firmware judges it and answers
        ACK 3 (SENSOR.md's channels are 0–3, 15 and 17–40; a test of the firmware sends such indices on purpose).
        ValueError, naming the entry by position, for anything else: 0.5 or True had gone out as channel 0 or 1, and
        a whole float (3.0) is refused too — an index names a channel, as a scene's whole-number fields refuse 3.0."""
        from emulator.channels import channel_index

        indices = []
        for k, c in enumerate(channels):
            if isinstance(c, str):
                c = channel_index(c)  # ValueError naming the known channels
            elif isinstance(c, (bool, np.bool_)) or not isinstance(c, (int, np.integer)) or not 0 <= c <= 255:
                whole = isinstance(c, float) and c.is_integer() and 0 <= c <= 255
                raise ValueError(f"pattern[{k}] = {c!r}: a channel index 0 to 255 or a channel name (\"PAC\", \"E7\")"
                                 + (f"; give {int(c)}, an int (an index names a channel)" if whole else ""))
            indices.append(int(c))
        return bytes(indices)

    def request_status(self) -> int:
        return self.send(CMD_STATUS)

    def on_frame(self, callback) -> None:
        self.callbacks.append(callback)

    def _file_reply(self, item) -> None:
        ctype = CMD_STATUS if isinstance(item, Status) else item[1]
        waiting = self._waiting.get(ctype)
        now = time.monotonic()
        while waiting and now - waiting[0][1] > REPLY_HORIZON_S:  # lost: never answered
            waiting.popleft()
        if not waiting:
            self.unsolicited_replies += 1
            return
        number, _ = waiting.popleft()
        self._answers[number] = item
        self._reply_marks[number] = self._frames_read
        if len(self._answers) > 256:  # replies nobody collected: keep the newest
            for k in sorted(self._answers)[:-256]:
                del self._answers[k]
        for k in sorted(self._reply_marks)[:-256]:
            del self._reply_marks[k]

    def count_afresh(self, after_reply_to: int | None = None) -> None:
        """From here on: the parser's statistics and sequence tracking start over, and the frames read so far but
        not yet taken by :meth:`frames` are forgotten (what an earlier session left streaming is not this one's).

        ``after_reply_to``: a command's number (``drv.start()``'s): the frames read *after* its reply are this
        session's and are kept for :meth:`frames`, counted afresh (a slow host reads START's ACK together with the
        first frames behind it; they had been forgotten, uncounted, and the recording started late)."""
        mark = self._reply_marks.get(after_reply_to) if after_reply_to is not None else None
        first = self._frames_read - len(self._backlog)  # read number of the oldest frame in the backlog
        keep = list(self._backlog)[max(0, mark - first):] if mark is not None else []
        self.parser.count_afresh()
        self._backlog.clear()
        now = time.monotonic()
        for f in keep:  # counted again from the start of the new count, in the order they came
            self.parser.sequence.accept(f.seq, now, len(f.channels))
            self.parser.stats.frames += 1
            self._backlog.append(f)

    def poll(self) -> list:
        """Read what has arrived; returns the decoded items (frames, statuses, acks).  Low level: the data frames
        among them also wait in the backlog for :meth:`frames` (use one or the other to take frames)."""
        self._check_open("poll")
        try:
            data = self.serial.read(max(1, self.serial.in_waiting or 1))
        except OSError:  # EIO: the other side of the pty went away (pyserial's SerialException is an OSError)
            self.disconnected = True
            return []
        items = self.parser.feed(data) if data else []
        for item in items:
            if isinstance(item, DataFrame):
                if self.sample_times is not None:
                    item.t_s = self.sample_times(item)
                for cb in self.callbacks:
                    cb(item)
                if len(self._backlog) >= BACKLOG_FRAMES:
                    self._backlog.popleft()
                    self.backlog_discarded += 1
                self._backlog.append(item)
                self._frames_read += 1
            else:
                self._file_reply(item)
        return items

    def reply_to(self, number: int):
        """The reply to command ``number`` if it has come (and was not taken yet), else None."""
        return self._answers.pop(number, None)

    def wait_for(self, want, timeout_s: float = 2.0):
        """The reply to the latest command of type ``want`` (an int: its ACK ``("ack", type, result)``; or
        ``Status`` after :meth:`request_status`), or None on timeout or if no such command was sent."""
        ctype = CMD_STATUS if want is Status else int(want)
        number = self._latest.get(ctype)
        if number is None:
            return None
        deadline = time.monotonic() + timeout_s
        while True:
            reply = self._answers.pop(number, None)
            if reply is not None:
                return reply
            if time.monotonic() >= deadline or self.disconnected:
                return None
            self.poll()

    def frames(self, max_frames: int | None = None, timeout_s: float = 5.0):
        """Yield data frames, each once and in order (those read earlier first, see the class); stops after
        ``max_frames`` or when no frame arrives for ``timeout_s`` (the time your loop spends on a frame not counted)."""
        got = 0
        idle_since = time.monotonic()
        while max_frames is None or got < max_frames:
            if self._backlog:
                got += 1
                yield self._backlog.popleft()
                idle_since = time.monotonic()  # the caller had the frame: the wait starts again
                continue
            if not self.poll() and (self.disconnected or time.monotonic() - idle_since > timeout_s):
                return
