"""Host driver for the bridge firmware's serial stream (protocol in firmware_tests/firmware/bt_bridge.h).

:class:`FrameParser` turns bytes into frames: it hunts for the 0xAA 0x55 sync, checks the length and the
CRC-16, and after corruption resynchronises on the next sync, counting what it skipped.  Sequence numbers
reveal dropped frames.  :class:`BridgeDriver` runs the parser on a pyserial port (a device path, or URLs
such as ``loop://`` and ``socket://host:port``), sends commands, and offers an iterator and a callback API.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

import numpy as np

from emulator import conversions as conv

SYNC = b"\xaa\x55"
T_DATA, T_STATUS, T_ACK = 0x10, 0x11, 0x12
CMD_START, CMD_STOP, CMD_PATTERN, CMD_STATUS = 0x01, 0x02, 0x03, 0x04
MAX_PAYLOAD = 4 + 64 * (1 + 2 * 5)
ACK_RESULTS = {0: "ok", 1: "bad length", 2: "unknown command", 3: "bad value"}


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF)."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def encode(frame_type: int, payload: bytes = b"") -> bytes:
    body = bytes([frame_type]) + struct.pack("<H", len(payload)) + payload
    return SYNC + body + struct.pack("<H", crc16(body))


@dataclass
class DataFrame:
    """One frame of samples: ``codes[slot, sensor]`` (12 bits) and ``status`` (0 ok, 1 parity, 2 error word)."""

    seq: int
    sensor_mask: int
    channels: np.ndarray
    codes: np.ndarray
    status: np.ndarray

    @property
    def sensors(self) -> list[int]:
        return [n for n in range(1, 6) if self.sensor_mask >> (n - 1) & 1]


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


@dataclass
class ParserStats:
    frames: int = 0
    crc_errors: int = 0
    bad_lengths: int = 0
    bytes_skipped: int = 0
    dropped_frames: int = 0
    resyncs: int = 0
    last_seq: int | None = None
    malformed: int = 0


@dataclass
class FrameParser:
    """Bytes in, frames out; survives any garbage."""

    stats: ParserStats = field(default_factory=ParserStats)
    _buf: bytearray = field(default_factory=bytearray)

    def feed(self, data: bytes) -> list:
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
            frame = self._decode(ftype, payload)
            if frame is not None:
                out.append(frame)
        return out

    def _skip(self, n: int) -> None:
        if n <= 0:
            return
        if self.stats.bytes_skipped == 0 or n:
            self.stats.resyncs += 1
        self.stats.bytes_skipped += n
        del self._buf[:n]

    def _decode(self, ftype: int, p: bytes):
        try:
            if ftype == T_DATA:
                seq, mask, slots = struct.unpack_from("<HBB", p)
                ns = bin(mask & 0x1F).count("1")
                if len(p) != 4 + slots * (1 + 2 * ns):
                    raise ValueError("data frame length does not match its header")
                rec = np.frombuffer(p[4:], dtype=np.uint8).reshape(slots, 1 + 2 * ns)
                words = rec[:, 1:].copy().view("<u2").reshape(slots, ns)
                self._count_seq(seq)
                self.stats.frames += 1
                return DataFrame(seq, mask, rec[:, 0].astype(int), (words & 0x0FFF).astype(np.uint16),
                                 (words >> 12).astype(np.uint8))
            if ftype == T_STATUS:
                mask, streaming, *counters = struct.unpack("<BB6I", p)
                return Status(mask, bool(streaming), *counters)
            if ftype == T_ACK:
                cmd, result = struct.unpack("<BB", p)
                return ("ack", cmd, result)
        except (struct.error, ValueError):
            self.stats.malformed += 1
            return None
        self.stats.malformed += 1
        return None

    def _count_seq(self, seq: int) -> None:
        last = self.stats.last_seq
        if last is not None:
            gap = (seq - last - 1) & 0xFFFF
            if gap < 0x8000:
                self.stats.dropped_frames += gap
        self.stats.last_seq = seq


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
    """The firmware's serial stream through pyserial: commands, frames as an iterator or by callback."""

    def __init__(self, port, baudrate: int = 3_000_000, timeout: float = 0.05):
        import serial

        if isinstance(port, str):
            self.serial = serial.serial_for_url(port, baudrate=baudrate, timeout=timeout, rtscts=False,
                                                dsrdtr=False, do_not_open=False)
        else:
            self.serial = port
        self.parser = FrameParser()
        self.callbacks = []
        self.replies: list = []  # statuses and acks, for wait_for
        self.disconnected = False

    def close(self) -> None:
        self.serial.close()

    def send(self, frame_type: int, payload: bytes = b"") -> None:
        self.serial.write(encode(frame_type, payload))
        self.serial.flush()

    def start(self):
        self.send(CMD_START)

    def stop(self):
        self.send(CMD_STOP)

    def set_pattern(self, channels) -> None:
        self.send(CMD_PATTERN, bytes(int(c) for c in channels))

    def request_status(self):
        self.send(CMD_STATUS)

    def on_frame(self, callback) -> None:
        self.callbacks.append(callback)

    def poll(self) -> list:
        """Read what has arrived; returns the decoded items (frames, statuses, acks)."""
        try:
            data = self.serial.read(max(1, self.serial.in_waiting or 1))
        except OSError:  # EIO: the other side of the pty went away
            self.disconnected = True
            return []
        items = self.parser.feed(data) if data else []
        for item in items:
            if isinstance(item, DataFrame):
                for cb in self.callbacks:
                    cb(item)
            else:
                self.replies.append(item)
        return items

    def wait_for(self, want, timeout_s: float = 2.0):
        """The next status (``want=Status``) or ack of command type ``want`` (an int), or None on timeout."""
        import time

        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and not self.disconnected:
            for item in list(self.replies):
                if (want is Status and isinstance(item, Status)) or (
                        isinstance(item, tuple) and item[0] == "ack" and item[1] == want):
                    self.replies.remove(item)
                    return item
            self.poll()
        return None

    def frames(self, max_frames: int | None = None, timeout_s: float = 5.0):
        """Yield data frames; stops after ``max_frames`` or when nothing arrives for ``timeout_s``."""
        import time

        got = 0
        idle_since = time.monotonic()
        while max_frames is None or got < max_frames:
            items = self.poll()
            if items:
                idle_since = time.monotonic()
            for item in items:
                if isinstance(item, DataFrame):
                    got += 1
                    yield item
                    if max_frames is not None and got >= max_frames:
                        return
            if self.disconnected or time.monotonic() - idle_since > timeout_s:
                return
