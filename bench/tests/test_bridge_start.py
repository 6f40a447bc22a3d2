"""Unpaced, the bridge bench's virtual time waits for the host's first byte: however long a host takes before it
sends START, a stimulus scripted at 0.5 s falls inside the stream at the same place, and the same host gives the
same frames on every run, over the software and the RTL SPI alike."""

import time

import numpy as np
import pytest

from bench.hosts.bridge import FirmwareBench
from bench.hosts.driver import CMD_START, BridgeDriver
from emulator.stimuli import Tap

pytestmark = pytest.mark.firmware
PDC = 1
FRAMES = 100  # 1 s of stream at 100 frames/s
TAP = Tap(0.5, 1.0)


def _stream(setup_delay_s: float, spi: str = "software") -> list:
    """The first :data:`FRAMES` frames a host gets that waits ``setup_delay_s`` (wall s) before sending START."""
    # a receive buffer that holds the whole stream: a host starved of CPU on a busy machine loses nothing
    with FirmwareBench(1, stimuli=[TAP], seed=5, spi=spi, rx_buffer=1 << 20) as fb:
        time.sleep(setup_delay_s)
        drv = BridgeDriver(fb.port)
        frames = []
        drv.on_frame(frames.append)  # every frame, also those that came with the acknowledgement
        try:
            drv.start()
            assert drv.wait_for(CMD_START, timeout_s=30) is not None
            for _ in drv.frames(max_frames=FRAMES, timeout_s=60):
                if len(frames) >= FRAMES:
                    break
        finally:
            drv.close()
        assert fb.link.bytes_overrun == 0
    assert len(frames) >= FRAMES and frames[0].seq == 0
    return frames[:FRAMES]


def _pdc(frames) -> np.ndarray:
    return np.array([f.codes[f.channels == PDC, 0][0] for f in frames], float)


def _assert_same(a: list, b: list, what: str) -> None:
    for i, (x, y) in enumerate(zip(a, b)):
        same = (x.seq, x.sensor_mask) == (y.seq, y.sensor_mask) and np.array_equal(x.channels, y.channels) \
            and np.array_equal(x.codes, y.codes) and np.array_equal(x.status, y.status)
        assert same, f"{what}: frame {i} differs (seq {x.seq} / {y.seq})"


def test_virtual_time_stands_still_until_the_host_sends_its_first_byte():
    with FirmwareBench(1) as fb:
        t0 = fb.virtual_time
        time.sleep(0.3)
        assert fb.virtual_time == t0 < 0.1, "virtual time ran before the host said anything"
        drv = BridgeDriver(fb.port)
        try:
            drv.start()
            assert drv.wait_for(CMD_START) is not None
            list(drv.frames(max_frames=5, timeout_s=10))
        finally:
            drv.close()
        assert fb.virtual_time > t0 + 0.04  # and runs once it has


def test_a_tap_at_half_a_second_is_seen_at_the_same_place_however_long_the_host_takes():
    """A host that sends START at once and one that sets up for 1 s first see the same 100 frames: the tap
    (1 N at 0.5 s of virtual time from power-on) inside them, about 0.5 s into the stream."""
    prompt, slow = _stream(0.0), _stream(1.0)
    pdc = _pdc(prompt)
    rest = np.median(pdc[:20])
    assert pdc.max() - rest > 40, "the tap is not in the stream"
    assert 40 <= int(np.argmax(pdc)) <= 60, "the tap is not about 0.5 s into the stream"
    _assert_same(prompt, slow, "a host that waited 1 s before START")


@pytest.mark.rtl
def test_the_same_host_gets_identical_frames_over_the_software_and_the_rtl_spi():
    """README: identical frames over both, whatever the host's set-up time (here 1 s before START on the RTL)."""
    _assert_same(_stream(0.0), _stream(1.0, spi="rtl"), "software vs RTL")
