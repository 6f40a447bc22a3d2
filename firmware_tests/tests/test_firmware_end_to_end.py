"""Bridge firmware + host driver end to end: the firmware runs natively against emulated sensors in virtual
time, its UART is a pty, and the pyserial driver reads it. Every wait is bounded by a timeout."""

import numpy as np
import pytest

from bench.verification import analysis
from bench.hosts.bridge import FirmwareBench
from bench.hosts.driver import CMD_PATTERN, CMD_START, CMD_STOP, BridgeDriver, Status
from emulator.stimuli import SPHERES, SphereDrop, Tap, Touch

pytestmark = pytest.mark.firmware


def stream(fb: FirmwareBench, n_frames: int, driver: BridgeDriver | None = None):
    drv = driver or BridgeDriver(fb.port)
    drv.start()
    assert drv.wait_for(CMD_START) == ("ack", CMD_START, 0)
    frames = list(drv.frames(max_frames=n_frames, timeout_s=10))
    return drv, frames


def pac(frames, sensor_col=0):
    return np.concatenate([f.codes[f.channels == 0, sensor_col] for f in frames]).astype(float)


def test_rest_noise_reaches_the_host_intact():
    with FirmwareBench(1) as fb:
        drv, frames = stream(fb, 300)
        drv.request_status()
        status = drv.wait_for(Status)
        drv.close()
    assert len(frames) == 300 and drv.parser.stats.crc_errors == 0 and drv.parser.stats.dropped_frames == 0
    assert np.all(np.diff([f.seq for f in frames]) == 1)
    assert all(not f.status.any() for f in frames)
    assert 1.2 < pac(frames).std() < 1.6  # the published 1.4 bits, through firmware, UART and driver
    assert status.sensor_mask == 1 and status.parity_errors == 0 and status.error_words == 0


def test_three_sensors_are_detected_and_streamed_together():
    with FirmwareBench(3) as fb:
        drv, frames = stream(fb, 50)
        drv.close()
    assert {f.sensor_mask for f in frames} == {0b111}
    assert frames[-1].codes.shape == (44, 3)


def test_the_host_detects_sphere_drops_and_sees_taps_and_presses():
    """The stream starts when the host's START arrives, at a virtual time that depends on how fast the host
    thread runs (the firmware runs ~30x real time meanwhile): the stimuli come late enough (6 s) to fall inside
    the stream, and the checks use times relative to each other."""
    stimuli = [SphereDrop(6.0, SPHERES["1 mm steel bearing"][0]), Tap(7.0, 0.5), Touch(7.5, 1.0, 0.2, 1.0)]
    with FirmwareBench(1, stimuli=stimuli) as fb:
        drv, frames = stream(fb, 1000)
        drv.close()
    seq0 = frames[0].seq
    t_pac = np.concatenate([(f.seq - seq0) * 0.01 + np.arange(22) / 2200.0 for f in frames])
    x = pac(frames)
    # find the drop by the dissertation's rule, with the noise of the stream's first half second
    rest = x[t_pac < 0.5]
    hits = analysis.StreamingDetector(rest.mean(), rest.std(), 2200.0)
    hits.update(x)
    # when each detection starts: a 100 ms window first holds more than 3 samples beyond 4 σ
    flags = np.concatenate([[0], np.cumsum(analysis.exceedances(x, rest.mean(), rest.std()))])
    counts = flags[220:] - flags[:-220]
    above = counts > 3
    onsets = t_pac[219:][np.flatnonzero(above & ~np.concatenate([[False], above[:-1]]))]
    # the drop is detected itself (the first event), and the tap one second after it
    assert hits.events == len(onsets) >= 2
    assert onsets[1] - onsets[0] == pytest.approx(1.0, abs=0.03)
    assert onsets[0] > 0.5, "the stream started after the drop: the host took too long to send START"
    pdc = np.array([f.codes[f.channels == 1, 0][0] for f in frames], float)
    t_pdc = np.array([(f.seq - seq0) * 0.01 for f in frames])
    press = (t_pdc > onsets[0] + 1.75) & (t_pdc < onsets[0] + 2.45)  # the press holds 1 N from 7.7 to 8.7 s
    assert np.median(pdc[press]) - np.median(pdc[:40]) == pytest.approx(87, abs=6)  # 11.5 mN per PDC bit


def test_host_commands_stop_and_change_the_pattern():
    with FirmwareBench(1) as fb:
        drv, frames = stream(fb, 5)
        drv.set_pattern([1, 0, 3])
        assert drv.wait_for(CMD_PATTERN) == ("ack", CMD_PATTERN, 0)
        # frames come in order, each once: those read while waiting for the ACK (the old pattern, however many a
        # slow host let pile up) first, then the new pattern's — take frames until 20 of the new pattern have come
        later, new = [], 0
        for f in drv.frames(max_frames=2000, timeout_s=5):
            later.append(f)
            new += list(f.channels) == [1, 0, 3]
            if new == 20:
                break
        drv.set_pattern([99])
        assert drv.wait_for(CMD_PATTERN) == ("ack", CMD_PATTERN, 3)  # refused: not a channel
        drv.send(0x7E)  # no such command
        assert drv.wait_for(0x7E) == ("ack", 0x7E, 2)  # bt_bridge.h: 2 unknown
        drv.request_status()
        status = drv.wait_for(Status)
        drv.stop()
        assert drv.wait_for(CMD_STOP) == ("ack", CMD_STOP, 0)
        drv.close()
    first_new = next(k for k, f in enumerate(later) if list(f.channels) == [1, 0, 3])
    assert all(list(f.channels) == [1, 0, 3] for f in later[first_new:]) and len(later) - first_new == 20
    assert all(len(f.channels) == 44 for f in later[:first_new])  # the default frame until the change, not after
    # the refused pattern and the unknown command are the command errors; the sensor present at power-on was
    # found, not found again
    assert (status.command_errors, status.finds, status.losses) == (2, 0, 0)


def replies_to(data: bytes, seconds: float = 0.02):
    """Feed ``data`` to the firmware (one quiet sensor, virtual time) in 7-byte pieces, as a UART delivers
    them, then ask for its status: returns every reply parsed (ACKs as ("ack", type, result), the Status last)."""
    from bench.hosts.cosim import CoSim, VirtualBoard, default_sensors
    from bench.hosts.driver import CMD_STATUS, FrameParser, encode

    out = bytearray()
    board = VirtualBoard(default_sensors(1), uart_out=out.extend)
    try:
        sim = CoSim(board)
        for k in range(0, len(data), 7):
            board.send_to_firmware(data[k:k + 7])
            sim.run(0.001)
        sim.run(seconds)
        board.send_to_firmware(encode(CMD_STATUS))
        sim.run(0.005)
    finally:
        board.bus.close()
    return [f for f in FrameParser().feed(bytes(out), now=0.0) if not hasattr(f, "seq")]


@pytest.mark.parametrize("n", [0, 65, 300, 5000])
def test_a_pattern_of_a_length_the_firmware_cannot_take_is_answered_bad_length(n):
    """bt_bridge.h: PATTERN takes 1..64 channels, ACK 1 "bad length" otherwise, also for a frame longer than its
    receive buffer (followed as it passes, its CRC checked on the way): one command error, the default pattern
    stays (the STATUS after it still answers, and reports the one error)."""
    from bench.hosts.driver import encode

    replies = replies_to(encode(CMD_PATTERN, bytes([1]) * n) + encode(CMD_START))
    assert replies[:2] == [("ack", CMD_PATTERN, 1), ("ack", CMD_START, 0)]
    assert isinstance(replies[2], Status) and replies[2].command_errors == 1 and replies[2].streaming


def _too_long_pattern() -> bytes:
    from bench.hosts.driver import encode

    return encode(CMD_PATTERN, bytes([1]) * 65)


@pytest.mark.parametrize("garbage", [
    b"\xaa\x55",  # a stray sync: with the PATTERN's own, a header announcing 0x0355 bytes
    b"\xaa\x55\x02\x0a\x00",  # a cut header waiting for 10 bytes: the PATTERN's header reaches the front late
    b"\xaa\x55\x01\xff\xff",  # a header announcing 65 535 bytes
    "first 20 bytes of the PATTERN",  # a host's retry after a send cut short
], ids=["stray-sync", "cut-header", "huge-length", "retry"])
def test_a_too_long_pattern_behind_garbage_is_still_answered_bad_length(garbage):
    """bt_bridge.h: a frame of more than 64 payload bytes is answered ACK 1 if its CRC holds — also behind garbage
    that starts a long frame of its own or holds it back (several are followed at once, each from the bytes
    already received behind its header); the garbage is what counts as command errors, besides the ACK's one."""
    from bench.hosts.driver import encode

    long_pattern = _too_long_pattern()
    garbage = long_pattern[:20] if isinstance(garbage, str) else garbage
    replies = replies_to(garbage + long_pattern + encode(CMD_START))
    assert replies[:2] == [("ack", CMD_PATTERN, 1), ("ack", CMD_START, 0)]
    assert isinstance(replies[2], Status) and replies[2].command_errors == len(garbage) + 1


def test_a_valid_frame_ending_a_long_frame_is_served_and_the_long_one_is_not():
    """bt_bridge.h: a valid frame inside a long frame is served and ends it — even one whose last bytes are the
    long frame's CRC (crafted: two filler bytes chosen so that the long frame's CRC is the START's)."""
    import binascii

    from bench.hosts.driver import SYNC, encode

    start = encode(CMD_START)
    body = bytes([0x09]) + (70).to_bytes(2, "little")
    for filler in range(1 << 16):
        payload = bytes(63) + filler.to_bytes(2, "big") + start[:5]
        if binascii.crc_hqx(body + payload, 0xFFFF).to_bytes(2, "little") == start[5:]:
            break
    long_frame = SYNC + body + payload + start[5:]
    assert long_frame.endswith(start) and len(long_frame) == 77
    replies = replies_to(long_frame)
    assert replies[0] == ("ack", CMD_START, 0) and isinstance(replies[1], Status) and len(replies) == 2


def test_a_long_frame_with_a_bad_crc_is_garbage_and_answered_nothing():
    """A 65-channel PATTERN whose CRC does not hold is no frame: no ACK; every one of its 72 bytes is skipped and
    counted as a command error, and the START behind it is served."""
    from bench.hosts.driver import encode

    bad = bytearray(encode(CMD_PATTERN, bytes([1]) * 65))
    bad[-1] ^= 0x40
    replies = replies_to(bytes(bad) + encode(CMD_START))
    assert replies[0] == ("ack", CMD_START, 0)
    assert isinstance(replies[1], Status) and replies[1].command_errors == len(bad)


@pytest.mark.parametrize("length", [64, 0xFFFF])
def test_a_corrupted_length_delays_no_command_behind_it(length):
    """A header announcing more bytes than come (a length corrupted on the line: the most a frame may hold, or
    65 535) is not waited for: a START right behind it is answered at once, before the bytes it announced could
    have arrived, and the stream starts; the five header bytes count as command errors."""
    from bench.hosts.driver import SYNC, encode

    header = SYNC + bytes([CMD_PATTERN, length & 0xFF, length >> 8])
    replies = replies_to(header + encode(CMD_START), seconds=0.0)
    assert replies[0] == ("ack", CMD_START, 0)
    assert isinstance(replies[1], Status) and replies[1].streaming and replies[1].command_errors == 5


def test_firmware_that_does_not_compile_reports_the_compiler_and_caches_nothing(tmp_path):
    """Users plug in their own firmware: a compile error names the file and line and leaves no library behind."""
    from bench.hosts.cosim import FIRMWARE_DIR, build_firmware
    from bench.errors import BuildError

    broken = tmp_path / "broken.c"
    broken.write_text('#include "bt_hal.h"\nint bt_broken(void) { return undeclared_name; }\n')
    sources = sorted(FIRMWARE_DIR.glob("*.c")) + [broken]
    with pytest.raises(BuildError, match=r"the firmware does not compile:(.|\n)*broken\.c:2"):
        build_firmware(sources, out_dir=tmp_path / "out")
    assert not list((tmp_path / "out").rglob("*.so")), "a failed build must not leave a cached library"
    assert not list((tmp_path / "out").rglob("*.partial"))


def test_a_refused_pattern_leaves_the_pattern_as_it_was():
    """CoSim.set_pattern: an entry that is no byte (273, which a byte would wrap to E1), True (channel 1 as a
    number) or a whole float (3.0) is refused before the firmware sees it, naming the entry as the driver does; an
    index no channel has — 16 (SENSOR.md: channels 0–3, HAL 15, E1.. from 17), HAL's 15 (no signal), 99 — is
    refused by the firmware.  Either way the pattern set before stays, frame after frame."""
    from bench.hosts.cosim import CoSim, VirtualBoard, default_sensors
    from bench.hosts.driver import DataFrame, FrameParser, encode

    out = bytearray()
    board = VirtualBoard(default_sensors(1), uart_out=out.extend)
    try:
        sim = CoSim(board)
        sim.set_pattern([1, 0])
        for refused, why in (([273], r"pattern\[0\] = 273: a channel index 0 to 255"),
                             ([0, True], r"pattern\[1\] = True: a channel index 0 to 255"),
                             ([3.0], r"pattern\[0\] = 3\.0: a channel index 0 to 255 .*; give 3, an int"),
                             ([16], "refused by the firmware: channels are PAC, PDC"),
                             ([15], "refused by the firmware: channels are PAC, PDC"),
                             ([99], "refused by the firmware: channels are PAC, PDC")):
            with pytest.raises(ValueError, match=why):
                sim.set_pattern(refused)
        board.send_to_firmware(encode(CMD_START))
        sim.run(0.05)
    finally:
        board.bus.close()
    frames = [f for f in FrameParser().feed(bytes(out), now=0.0) if isinstance(f, DataFrame)]
    assert frames and all(list(f.channels) == [1, 0] for f in frames)
