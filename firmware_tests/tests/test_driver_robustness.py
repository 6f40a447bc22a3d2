"""The host driver's bookkeeping (issue 12, item 4): dropped frames counted from sequence numbers that arrive out of
order, repeat, wrap around 16 bits or jump by more than 65 536; replies matched to the command that asked; the
CRC through the standard library's table-driven crc_hqx (the same polynomial as the firmware's CRC-16)."""

import re
import struct
import time

import numpy as np
import pytest

from bench.hosts import driver as D
from bench.hosts.driver import CMD_PATTERN, CMD_START, CMD_STATUS, BridgeDriver, DataFrame, FrameParser, Status

pytestmark = pytest.mark.unit


def data_frame(seq: int, slots: int = 44) -> bytes:
    payload = struct.pack("<HBB", seq & 0xFFFF, 0b1, slots) + bytes([0, 0x00, 0x08]) * slots
    return D.encode(D.T_DATA, payload)


def feed(parser, seqs, t0=0.0, rate=100.0):
    """Frames ``seqs`` arriving one by one at ``rate`` per second from ``t0``; returns the sequence numbers
    delivered."""
    got = []
    for k, s in enumerate(seqs):
        got += [f.seq for f in parser.feed(data_frame(s), now=t0 + k / rate) if isinstance(f, DataFrame)]
    return got


def test_a_reordered_frame_fills_its_gap_and_is_not_a_drop():
    p = FrameParser()
    assert feed(p, [1, 2, 3, 5, 4, 6]) == [1, 2, 3, 5, 4, 6]
    assert p.stats.dropped_frames == 0 and p.stats.reordered == 1 and p.stats.duplicates == 0


def test_one_stale_frame_does_not_count_as_fifty_two_drops():
    """Issue 12: one frame from the past (seq 48 after 100) made the next frame count 52 drops."""
    p = FrameParser()
    assert feed(p, list(range(101)) + [48, 101]) == list(range(101)) + [101]
    assert p.stats.dropped_frames == 0 and p.stats.duplicates == 1 and p.stats.last_seq == 101


def test_a_repeated_frame_is_delivered_once():
    p = FrameParser()
    assert feed(p, [7, 8, 8, 9]) == [7, 8, 9]
    assert p.stats.dropped_frames == 0 and p.stats.duplicates == 1


def test_wrap_around_is_not_a_gap_and_a_gap_across_it_counts_exactly():
    p = FrameParser()
    feed(p, [65533, 65534, 65535, 0, 1, 2])
    assert p.stats.dropped_frames == 0
    q = FrameParser()
    feed(q, [65534, 3])  # 65535, 0, 1, 2 missing
    assert q.stats.dropped_frames == 4


@pytest.mark.parametrize("gap", [40_000, 65_535, 65_536, 70_000, 200_000])
def test_gaps_longer_than_half_the_counter_are_counted_from_the_arrival_time(gap):
    """Issue 12: a 40 000-frame gap counted 0.  At 100 frames/s the arrival time tells how many went by."""
    p = FrameParser()
    feed(p, range(200))  # 2 s at 100 frames/s: the rate is measured
    later = 199 + gap + 1
    p.feed(data_frame(later), now=1.99 + (gap + 1) / 100.0)
    assert p.stats.dropped_frames == gap
    p.feed(data_frame(later + 1), now=1.99 + (gap + 2) / 100.0)
    assert p.stats.dropped_frames == gap and p.stats.duplicates == 0


@pytest.mark.parametrize("gap", [65_536, 70_000])
def test_a_long_gap_is_counted_at_the_measured_rate_not_the_nominal_one(gap):
    """A 44-slot stream arriving at 50 frames/s (a host or firmware slower than the nominal 4400/44 = 100): the
    frames a long gap hid are counted from the measured 50/s; at the nominal rate the gap's time would say twice
    as many went by, a whole counter wrap too many."""
    p = FrameParser()
    feed(p, range(200), rate=50.0)  # 4 s: the rate is measured
    later = 199 + gap + 1
    p.feed(data_frame(later), now=199 / 50.0 + (gap + 1) / 50.0)
    assert p.stats.dropped_frames == gap


def test_before_a_measurement_a_gap_is_counted_at_the_frames_nominal_rate():
    """Until half a second of stream is measured, the rate is the nominal 4400 slots/s over the frame's slots: 22
    slots make 200 frames/s, so 400 s of silence hid 80 000 frames (a 44-slot frame's 100/s would say 40 000)."""
    p = FrameParser()
    for k in range(3):
        p.feed(data_frame(k, slots=22), now=k / 200.0)
    gap = 80_000
    p.feed(data_frame(2 + gap + 1, slots=22), now=2 / 200.0 + (gap + 1) / 200.0)
    assert p.stats.dropped_frames == gap


def test_a_late_frame_after_a_long_gap_is_still_recognised():
    p = FrameParser()
    feed(p, list(range(10)) + [15, 16, 12])
    assert p.stats.dropped_frames == 4 and p.stats.reordered == 1


def test_the_crc_is_the_standard_librarys_and_keeps_up_with_pathological_input():
    """crc_hqx from 0xFFFF is CRC-16/CCITT-FALSE (same polynomial 0x1021 as the firmware's C): the driver uses it.
    Pathological input — a sync with the longest legal length every 5 bytes, so every byte starts a CRC over
    ~700 bytes — parses at well over 100 kB/s (the bitwise loop managed ~7 kB/s)."""
    assert D.crc16 is D._crc16_table
    assert D.crc16(b"123456789") == D._crc16_bitwise(b"123456789") == 0x29B1
    evil = (b"\xaa\x55\x10" + struct.pack("<H", D.MAX_PAYLOAD)) * 40_000  # 200 kB
    p = FrameParser()
    t0 = time.perf_counter()
    p.feed(evil)
    p.feed(b"\x00" * (D.MAX_PAYLOAD + 7))
    rate = len(evil) / (time.perf_counter() - t0)
    assert p.stats.crc_errors >= 39_000
    assert rate > 100e3, f"{rate / 1e3:.0f} kB/s"


class FakeFirmware:
    """A serial port whose far end answers each command in order (ack or status), when told to."""

    def __init__(self):
        self.rx = bytearray()
        self.commands = []
        self.in_waiting = 0

    def write(self, data):
        self.commands += [x for x in FrameParser().feed(bytes(data))] or [("cmd", data[2], data[5:-2])]

    def flush(self):
        pass

    def answer(self, ctype, result=0):
        if ctype == CMD_STATUS:
            self.rx += D.encode(D.T_STATUS, struct.pack("<BB6I", 1, 1, 5, 0, 0, 0, 0, result))
        else:
            self.rx += D.encode(D.T_ACK, bytes([ctype, result]))
        self.in_waiting = len(self.rx)

    def read(self, n):
        out, self.rx[:] = bytes(self.rx[:n]), self.rx[n:]
        self.in_waiting = len(self.rx)
        return out

    def close(self):
        pass


def test_a_stale_acknowledgement_is_not_returned_to_a_later_wait():
    """Two PATTERN commands: the first (refused, 3) is answered late; waiting after the second returns the second's
    answer, not the first's."""
    port = FakeFirmware()
    drv = BridgeDriver(port)
    drv.set_pattern([99])
    drv.set_pattern([1, 0])
    port.answer(CMD_PATTERN, 3)
    assert drv.wait_for(CMD_PATTERN, timeout_s=0.2) is None  # only the first command's answer has come
    port.answer(CMD_PATTERN, 0)
    assert drv.wait_for(CMD_PATTERN, timeout_s=0.5) == ("ack", CMD_PATTERN, 0)
    assert drv.wait_for(CMD_PATTERN, timeout_s=0.1) is None  # taken: never returned twice


def test_a_command_unanswered_past_the_horizon_is_lost_and_its_reply_goes_to_the_next(monkeypatch):
    """REPLY_HORIZON_S: a START never answered within the horizon is taken as lost, so the reply that comes after a
    second START is that one's (wait_for returns it); within the horizon the same reply went to the first."""
    monkeypatch.setattr(D, "REPLY_HORIZON_S", 0.05)
    port = FakeFirmware()
    drv = BridgeDriver(port)
    first = drv.start()
    time.sleep(0.1)
    second = drv.start()
    port.answer(CMD_START)
    assert drv.wait_for(CMD_START, timeout_s=0.5) == ("ack", CMD_START, 0)
    assert drv.reply_to(first) is None and drv.unsolicited_replies == 0
    third = drv.start()
    drv.start()
    port.answer(CMD_START)
    drv.poll()
    assert drv.reply_to(third) == ("ack", CMD_START, 0) and second != third


def test_replies_nobody_asked_for_are_counted_and_dropped():
    port = FakeFirmware()
    drv = BridgeDriver(port)
    port.answer(CMD_START)  # e.g. left over from a previous program on the same port
    drv.poll()
    assert drv.unsolicited_replies == 1
    assert drv.wait_for(CMD_START, timeout_s=0.1) is None  # nothing was sent
    n = drv.start()
    port.answer(CMD_START)
    assert drv.wait_for(CMD_START, timeout_s=0.5) == ("ack", CMD_START, 0) and drv.reply_to(n) is None
    drv.request_status()
    port.answer(CMD_STATUS, 7)
    st = drv.wait_for(Status, timeout_s=0.5)
    assert isinstance(st, Status) and st.command_errors == 7


def test_to_physical_converts_each_channel_and_leaves_bad_slots_nan():
    """The published conversions per sensor: PAC (code − 2048) × 0.37 Pa (D Table 4-1), electrodes named E1..E24 by
    their channel (17..40), and a slot with an error word (status 2) or a parity error (1) reads NaN, not a number."""
    import numpy as np

    from emulator import conversions as conv

    channels = np.array([0, 1, 3, 17, 35, 40, 0])
    codes = np.array([[2100, 2048], [900, 905], [2500, 2501], [3000, 3001], [2900, 2901], [2800, 2801], [2000, 1990]],
                     np.uint16)
    status = np.zeros_like(codes, np.uint8)
    status[6, 0], status[3, 1] = 2, 1
    out = D.to_physical(DataFrame(7, 0b101, channels, codes, status))
    assert set(out) == {1, 3}
    first, third = out[1], out[3]
    assert first["PAC_Pa"][0] == pytest.approx((2100 - 2048) * 0.37) and np.isnan(first["PAC_Pa"][1])
    assert third["PAC_Pa"] == pytest.approx([0.0, (1990 - 2048) * 0.37])
    assert set(first["electrodes_ohm"]) == {"E1", "E19", "E24"}
    assert first["electrodes_ohm"]["E19"] == pytest.approx(conv.impedance_ohm(2900.0))
    assert np.isnan(third["electrodes_ohm"]["E1"]) and not np.isnan(third["electrodes_ohm"]["E24"])
    assert first["TDC_C"] == pytest.approx(conv.tdc_to_celsius(2500.0))


def test_to_physical_reads_pdc_from_its_channel_in_kpa_above_the_given_rest():
    """SENSOR.md §4: fluid pressure = (PDC − offset) · 0.0365 kPa/bit.  ``pdc_offset`` is that offset (the rest's
    code), none reading from code 0; only PDC's slots (channel 1) make the series, not TAC's (channel 2).
    (A mutation hunt: an ignored offset or PDC read from the TAC slot passed.)"""
    channels = np.array([1, 2, 1, 0, 1])
    codes = np.array([[1000], [3000], [1100], [2048], [900]], np.uint16)
    frame = DataFrame(1, 0b1, channels, codes, np.zeros_like(codes, np.uint8))
    rested = D.to_physical(frame, pdc_offset=1000.0)[1]["PDC_kPa"]
    np.testing.assert_allclose(rested, [0.0, 100 * 0.0365, -100 * 0.0365], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(D.to_physical(frame)[1]["PDC_kPa"], [1000 * 0.0365, 1100 * 0.0365, 900 * 0.0365],
                               rtol=1e-12)


def test_counting_afresh_forgets_what_an_earlier_host_left_in_the_stream():
    """`record` after a host that was killed mid-stream: the tail of an old frame and the frames the bridge lost while
    nobody read are the earlier session's; counted afresh from the new START, a contiguous recording shows no CRC
    error, no skipped byte and no drop."""
    p = FrameParser()
    stale = data_frame(10)
    p.feed(stale[7:], now=0.0)  # cut off mid-frame
    feed(p, [11, 12], t0=0.01)
    assert p.stats.bytes_skipped > 0
    half = data_frame(120)
    p.feed(half[:9], now=0.1)  # bytes already buffered when the count starts over are kept
    p.count_afresh()
    got = [f.seq for f in p.feed(half[9:], now=0.11) if isinstance(f, DataFrame)] + feed(p, range(121, 130), t0=0.12)
    assert got == list(range(120, 130))
    assert (p.stats.crc_errors, p.stats.bytes_skipped, p.stats.dropped_frames, p.stats.frames) == (0, 0, 0, 10)


def test_a_second_host_on_one_port_is_refused_at_open_naming_why():
    """Two `record`s on one port each stole the other's bytes and blamed the bridge ("no answer to START"); the
    driver opens a port exclusively, so the second is refused at once."""
    import os
    import pty

    from bench.cli.hosts import _open_driver

    master, slave = pty.openpty()
    name = os.ttyname(slave)
    first = _open_driver(name, 3_000_000)
    try:
        with pytest.raises(OSError, match="another program has it open"):
            _open_driver(name, 3_000_000)
    finally:
        first.close()
        os.close(master)
        os.close(slave)


def test_the_default_bench_sensors_each_have_their_own_noise_and_only_sensor_1_feels_the_stimuli():
    """default_sensors(n, stimuli): sensor k draws from seed + k - 1, and the stimuli are sensor 1's (the others
    rest) — as FirmwareBench and CheetahBench document."""
    import numpy as np

    from bench.hosts.cosim import default_sensors
    from emulator.channels import channel_index
    from emulator.stimuli import Tap

    sensors = default_sensors(2, stimuli=[Tap(0.2, 1.0)], seed=5)
    t = np.arange(0.0, 0.6, 1 / 2200.0)
    both = np.tile([channel_index("PAC"), channel_index("PDC")], t.size)
    codes = {k: s.sample(both, np.repeat(t, 2)).astype(float) for k, s in sensors.items()}  # in time order
    pac = {k: c[0::2] for k, c in codes.items()}
    pdc = {k: c[1::2] for k, c in codes.items()}
    at_tap = (t > 0.2) & (t < 0.3)
    assert pdc[1][at_tap].max() - pdc[1][:200].mean() > 20 and np.ptp(pdc[2]) < 8  # only sensor 1 is tapped
    rest = t < 0.15
    assert abs(np.corrcoef(pac[1][rest], pac[2][rest])[0, 1]) < 0.2  # independent noise


# --- a helper's mutation hunt found these unguarded ----------------------------------------------------------------


def test_late_frames_in_the_middle_of_a_gap_keep_the_rest_of_it_open():
    """0, then 6 (1–5 missing), then 3, 1 and 5 arrive late: each fills its own place in the gap, none is taken for
    a duplicate, and the two never seen (2, 4) are the drops."""
    p = FrameParser()
    assert feed(p, [0, 6, 3, 1, 5]) == [0, 6, 3, 1, 5]
    assert p.stats.dropped_frames == 2 and p.stats.duplicates == 0


def test_frames_fed_one_byte_at_a_time_all_decode():
    """A serial read may end anywhere in a frame — inside its 5-byte header too: fed one byte at a time, three
    frames decode, in order, with nothing counted as bad."""
    p = FrameParser()
    got = []
    for byte in b"".join(data_frame(s) for s in (7, 8, 9)):
        got += [f.seq for f in p.feed(bytes([byte]), now=0.0) if isinstance(f, DataFrame)]
    assert got == [7, 8, 9] and p.stats.crc_errors == 0 and p.stats.dropped_frames == 0


def test_a_frame_of_five_sps_decodes_every_sensor():
    """The largest frame the bridge sends: all five sensors (mask 0b11111), 64 slots — each slot a channel byte and
    five words, 708 bytes of payload: codes (64, 5), sensors 1–5, sensor 5's own samples."""
    words = [(100 * k + slot) & 0x0FFF for slot in range(64) for k in range(1, 6)]
    payload = struct.pack("<HBB", 1, 0b11111, 64) + b"".join(
        bytes([0]) + struct.pack("<5H", *words[5 * slot:5 * slot + 5]) for slot in range(64))
    assert len(payload) == 708
    frames = [f for f in FrameParser().feed(D.encode(D.T_DATA, payload), now=0.0) if isinstance(f, DataFrame)]
    assert len(frames) == 1 and frames[0].codes.shape == (64, 5) and frames[0].sensors == [1, 2, 3, 4, 5]
    assert list(frames[0].samples(5)["PAC"][:3]) == [500, 501, 502]


@pytest.mark.firmware
def test_frames_keep_coming_past_the_idle_timeout_while_they_arrive():
    """``frames(timeout_s=…)`` ends after ``timeout_s`` *without* a frame, not after ``timeout_s`` in all (what
    ``biotac-bench record``'s idle timeout relies on): paced in real time (100 frames/s), 150 frames (1.5 s) arrive
    through a 0.5 s idle timeout (after 30 frames read with a long one: a cold numba cache compiles kernels while
    the first frames are computed, a one-off stall longer than 0.2 s)."""
    from bench.hosts.bridge import FirmwareBench

    with FirmwareBench(1, realtime=True) as fb:
        drv = BridgeDriver(fb.port)
        try:
            drv.start()
            assert drv.wait_for(CMD_START, timeout_s=5) is not None
            assert len(list(drv.frames(max_frames=30, timeout_s=10))) == 30  # streaming
            got = list(drv.frames(max_frames=150, timeout_s=0.5))
        finally:
            drv.close()
    assert len(got) == 150



@pytest.mark.firmware
@pytest.mark.parametrize("bad", [0.5, True, -1, 256, None])
def test_a_pattern_entry_that_is_no_channel_is_refused_before_anything_is_sent(bad):
    """0.5 and True had gone out as channels 0 and 1 (a silently different pattern); -1 and 256 failed with "bytes
    must be in range(0, 256)", naming neither the pattern nor the entry.  Each is refused naming its position."""
    port = FakeFirmware()
    drv = BridgeDriver(port)
    with pytest.raises(ValueError, match=rf"pattern\[1\] = {re.escape(repr(bad))}: a channel index 0 to 255 or a "
                                         rf"channel name"):
        drv.set_pattern([1, bad])
    assert port.commands == []


@pytest.mark.firmware
def test_a_whole_float_in_a_pattern_is_refused_saying_which_int_to_give_and_a_non_channel_index_is_sent():
    """A channel index names a channel: 3.0 is refused (as a scene's whole-number fields refuse it), the message
    saying to give 3; an index no channel has (16) is a byte and goes to the firmware, which answers ACK 3 — the
    firmware is what a host test checks."""
    port = FakeFirmware()
    drv = BridgeDriver(port)
    with pytest.raises(ValueError, match=r"pattern\[0\] = 3\.0: a channel index 0 to 255 .*; give 3, an int"):
        drv.set_pattern([3.0, 1])
    assert port.commands == []
    drv.set_pattern([16])
    assert port.commands == [("cmd", CMD_PATTERN, bytes([16]))]


def test_a_pattern_may_name_its_channels():
    port = FakeFirmware()
    drv = BridgeDriver(port)
    drv.set_pattern(["PDC", "e7", np.int64(1), 0])
    assert port.commands == [("cmd", CMD_PATTERN, bytes([1, 23, 1, 0]))]
    with pytest.raises(ValueError, match="unknown channel 'XYZ'"):
        drv.set_pattern(["XYZ"])


def test_a_pattern_longer_than_the_firmware_takes_is_refused_before_it_is_sent():
    """The firmware's receive buffer holds a PATTERN of at most 64 channels; a longer frame is skipped as garbage
    and never answered (the host would wait for an ACK that cannot come), so the driver refuses it, naming the
    limit, and sends nothing (the firmware counts no command error); 64 channels are sent and answered."""
    from bench.hosts.bridge import FirmwareBench

    with FirmwareBench(1) as fb:
        drv = BridgeDriver(fb.port)
        try:
            with pytest.raises(ValueError, match="65 channels: the bridge firmware takes at most 64"):
                drv.set_pattern(range(65))
            drv.set_pattern([0, 1, 3, 2] * 16)
            assert drv.wait_for(CMD_PATTERN, timeout_s=5) == ("ack", CMD_PATTERN, 0)
            drv.request_status()
            status = drv.wait_for(Status, timeout_s=5)
        finally:
            drv.close()
    assert status is not None and status.command_errors == 0


def test_frames_yields_every_frame_once_in_order_across_calls_and_waits_for_replies():
    """Frames that arrive in one read beyond ``max_frames``, and frames read while waiting for an ACK, are yielded
    by the next ``frames()`` call, in order: nothing between two calls is lost without a count (they used to be,
    silently: the parser had counted them, so no drop showed)."""
    port = FakeFirmware()
    drv = BridgeDriver(port)
    port.rx += b"".join(data_frame(s) for s in range(5))
    port.in_waiting = len(port.rx)
    assert [f.seq for f in drv.frames(max_frames=2, timeout_s=0.1)] == [0, 1]  # 0-4 arrived in one read
    drv.set_pattern([0, 1])
    port.rx += data_frame(5)
    port.answer(CMD_PATTERN)
    port.rx += data_frame(6)
    port.in_waiting = len(port.rx)
    assert drv.wait_for(CMD_PATTERN, timeout_s=0.5) == ("ack", CMD_PATTERN, 0)
    assert [f.seq for f in drv.frames(timeout_s=0.1)] == [2, 3, 4, 5, 6]
    assert drv.parser.stats.frames == 7 and drv.parser.stats.dropped_frames == 0 and drv.backlog_discarded == 0


def test_a_backlog_nobody_takes_is_bounded_and_counts_what_it_discards(monkeypatch):
    """A program that only uses callbacks never calls ``frames()``: the backlog keeps the newest
    ``BACKLOG_FRAMES`` and counts the rest, rather than growing for ever; the callbacks saw every frame."""
    monkeypatch.setattr(D, "BACKLOG_FRAMES", 3)
    port = FakeFirmware()
    drv = BridgeDriver(port)
    seen = []
    drv.on_frame(lambda f: seen.append(f.seq))
    port.rx += b"".join(data_frame(s) for s in range(8))
    port.in_waiting = len(port.rx)
    drv.poll()
    assert seen == list(range(8)) and drv.backlog_discarded == 5
    assert [f.seq for f in drv.frames(timeout_s=0.05)] == [5, 6, 7]


def test_the_backlog_holds_sixty_seconds_of_frames_as_documented():
    """README: the iterator's backlog keeps at most 6000 frames — 60 s of the default frame at 100 frames/s — and
    counts what a program that never iterates lets it discard. 6100 frames read at once: the oldest 100 go."""
    documented = 60 * 100  # 60 s × 100 frames/s (44 slots at 4.4 kHz), stated independently of the driver
    port = FakeFirmware()
    drv = BridgeDriver(port)
    port.rx += b"".join(data_frame(s) for s in range(documented + 100))
    port.in_waiting = len(port.rx)
    drv.poll()
    assert drv.backlog_discarded == 100
    first = next(iter(drv.frames(max_frames=1, timeout_s=0.05)))
    assert first.seq == 100


def test_count_afresh_forgets_the_frames_not_yet_taken_with_the_old_counts():
    """What ``record`` does after START's ACK: frames of an earlier session still waiting are not this one's."""
    port = FakeFirmware()
    drv = BridgeDriver(port)
    port.rx += b"".join(data_frame(s) for s in (40, 41))
    port.in_waiting = len(port.rx)
    drv.poll()
    drv.count_afresh()
    port.rx += data_frame(0)
    port.in_waiting = len(port.rx)
    assert [f.seq for f in drv.frames(timeout_s=0.05)] == [0]
    assert drv.parser.stats.frames == 1


def test_count_afresh_after_starts_reply_keeps_the_frames_behind_the_ack_and_counts_from_them():
    """``record``: a slow host reads START's ACK together with the frames that follow it; those are the recording's
    first frames (they had been forgotten with the earlier session's, uncounted: the recording started late).  The
    frames before the ACK are still forgotten, and a gap after the kept frames is counted as a drop."""
    port = FakeFirmware()
    drv = BridgeDriver(port)
    n = drv.start()
    port.rx += b"".join(data_frame(s) for s in (65534, 65535))  # an earlier session's stream, still arriving
    port.answer(CMD_START)
    port.rx += b"".join(data_frame(s) for s in (0, 1, 2))
    port.in_waiting = len(port.rx)
    assert drv.wait_for(CMD_START, timeout_s=0.5) == ("ack", CMD_START, 0)
    drv.count_afresh(after_reply_to=n)
    port.rx += data_frame(4)  # frame 3 lost on the line
    port.in_waiting = len(port.rx)
    assert [f.seq for f in drv.frames(timeout_s=0.05)] == [0, 1, 2, 4]
    assert drv.parser.stats.frames == 4 and drv.parser.stats.dropped_frames == 1


def test_the_idle_timeout_does_not_count_the_time_a_loop_spends_on_its_frames():
    """``frames(timeout_s=0.2)`` over three frames read at once, each taking the loop 0.25 s: the next frame, which
    the port has only at the third read after the loop is done with them, is still yielded — the wait for it starts
    when the loop asks again (it ended at once: the loop's own 0.75 s had been counted as the stream's silence)."""

    class LatePort(FakeFirmware):
        empty_reads_left = None  # armed: reads that find nothing before frame 3 is there

        def read(self, n):
            if self.empty_reads_left is not None:
                if self.empty_reads_left == 0:
                    self.empty_reads_left = None
                    self.rx += data_frame(3)
                    self.in_waiting = len(self.rx)
                else:
                    self.empty_reads_left -= 1
                    return b""
            return super().read(n)

    port = LatePort()
    drv = BridgeDriver(port)
    port.rx += b"".join(data_frame(s) for s in range(3))
    port.in_waiting = len(port.rx)
    got = []
    for f in drv.frames(timeout_s=0.2):
        got.append(f.seq)
        if f.seq < 3:
            time.sleep(0.25)  # the loop's own work on the frame
        if f.seq == 2:
            port.empty_reads_left = 2
    assert got == [0, 1, 2, 3]
