"""Bridge firmware + host driver end to end: the firmware runs natively against emulated sensors in virtual
time, its UART is a pty, and the pyserial driver reads it. Every wait is bounded by a timeout."""

import numpy as np
import pytest

from bench.verification import analysis
from bench.hosts.bridge import FirmwareBench
from bench.hosts.driver import CMD_PATTERN, CMD_START, CMD_STOP, BridgeDriver, Status
from emulator.sensor import Sensor
from emulator.channels import DEFAULT_FRAME_NAMES
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
    stimuli = [SphereDrop(1.0, SPHERES["1 mm steel bearing"][0]), Tap(2.0, 0.5), Touch(2.5, 1.0, 0.2, 1.0)]
    with FirmwareBench(1, stimuli=stimuli) as fb:
        drv, frames = stream(fb, 400)
        drv.close()
    seq0 = frames[0].seq
    t_pac = np.concatenate([(f.seq - seq0) * 0.01 + np.arange(22) / 2200.0 for f in frames])
    x = pac(frames)
    # frames start after detection (~ a few ms); find the drop by the dissertation's rule
    rest = x[t_pac < 0.5]
    hits = analysis.StreamingDetector(rest.mean(), rest.std(), 2200.0)
    hits.update(x)
    assert hits.events >= 2  # the drop, and the tap
    pdc = np.array([f.codes[f.channels == 1, 0][0] for f in frames], float)
    assert pdc.max() - np.median(pdc[:40]) > 60  # a 1 N press: ~87 PDC bits


def test_host_commands_stop_and_change_the_pattern():
    with FirmwareBench(1) as fb:
        drv, frames = stream(fb, 5)
        drv.set_pattern([1, 0, 3])
        assert drv.wait_for(CMD_PATTERN) == ("ack", CMD_PATTERN, 0)
        later = list(drv.frames(max_frames=20, timeout_s=5))
        drv.set_pattern([99])
        assert drv.wait_for(CMD_PATTERN) == ("ack", CMD_PATTERN, 3)  # refused: not a channel
        drv.stop()
        assert drv.wait_for(CMD_STOP) == ("ack", CMD_STOP, 0)
        drv.close()
    assert list(later[-1].channels) == [1, 0, 3]


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
