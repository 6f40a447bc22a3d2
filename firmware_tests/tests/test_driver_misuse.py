"""What a driver team gets wrong with the host driver gets one clear error: a sensor a frame does not carry (it was
"ValueError: 2 is not in list"), a channel outside the frame's pattern (a bare KeyError), and a driver used after
close() (pyserial's "argument must be an int, or have a fileno() method")."""

from __future__ import annotations

import numpy as np
import pytest

from bench.hosts.bridge import FirmwareBench
from bench.hosts.driver import BridgeDriver, DataFrame

pytestmark = pytest.mark.firmware


def frame() -> DataFrame:
    """A two-slot frame (PAC, PDC) of sensor 3 alone (mask 0x04); PDC's sample a parity error."""
    return DataFrame(seq=0, sensor_mask=0x04, channels=np.array([0, 1]), codes=np.array([[2048], [735]]),
                     status=np.array([[0], [1]]))


def test_a_sensor_the_frame_does_not_carry_is_named_with_those_it_does():
    f = frame()
    assert f.samples(3)["PAC"].tolist() == [2048] and f.samples(3)["PDC"].size == 0
    assert f.errors(3) == [(1, "PDC", "parity error")]
    for bad in (1, 0, True):
        with pytest.raises(ValueError, match=rf"sensor {bad!r} is not in this frame \(sensor mask 0x04: sensors "
                                             rf"\[3\]; numbered from 1\)"):
            f.samples(bad)
        with pytest.raises(ValueError, match=rf"sensor {bad!r} is not in this frame"):
            f.errors(bad)


def test_a_channel_outside_the_pattern_is_a_key_error_naming_the_frames_channels():
    samples = frame().samples(3)
    with pytest.raises(KeyError, match=r"'E22': not in this frame's pattern; it carries PAC, PDC"):
        samples["E22"]
    assert "E22" not in samples and samples.get("E22") is None  # a dict still: `in` and get() as usual


def test_a_driver_used_after_close_says_it_was_closed():
    with FirmwareBench(n_sensors=1) as bench:
        driver = BridgeDriver(bench.port)
        driver.start()
        assert next(driver.frames(max_frames=1)).codes.shape == (44, 1)
        driver.close()
        # frames already read are still served from the backlog; past them, frames() polls the closed port
        for call in (driver.poll, driver.start, driver.request_status, lambda: driver.set_pattern(["PAC"]),
                     lambda: list(driver.frames(max_frames=10**6))):
            with pytest.raises(RuntimeError, match=rf"BridgeDriver\.(poll|send)\(\): the driver's port {bench.port} "
                                                   r"is closed \(close\(\) was called\); open a new BridgeDriver"):
                call()
