"""The virtual time of every sample a host reads from the emulated bridge: ``FirmwareBench.sample_times`` and the
``t_s`` column ``BridgeDriver(port, sample_times=...)`` gives each DataFrame, checked against the instants the
sensors were really asked for their samples and against the firmware's sampling period (1/4400 s a slot)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from bench.hosts.driver import BridgeDriver

pytestmark = pytest.mark.firmware

SLOT_S = 1 / 4400  # the bridge firmware's sampling period: one slot


class RecordingSensor:
    """An emulated sensor that notes every (channel, instant) it is asked to sample (the bus calls ``sample``)."""

    def __init__(self, sensor):
        self._sensor, self.asked = sensor, []

    def sample(self, channels, times, bus_active=None):
        self.asked += zip(np.atleast_1d(channels).tolist(), np.atleast_1d(times).tolist())
        return self._sensor.sample(channels, times, bus_active)

    def __getattr__(self, name):
        return getattr(self._sensor, name)


@pytest.mark.parametrize("n_sensors", [1, 2])
def test_each_slots_time_is_when_its_sensors_sampled_it_one_slot_period_apart(biotac_bridge, n_sensors):
    """Over 12 frames of the 44-slot default pattern: every slot's ``t_s`` is an instant at which every sensor was
    asked for that slot's channel (to the nanosecond), slots are 1/4400 s apart within a frame and frames 44/4400 s
    apart (the firmware pads each frame to whole microseconds: within 1 µs), and the times run on from power-on."""
    from bench.pytest_plugin.fixtures import unit_sensors

    sensors = {k: RecordingSensor(s) for k, s in unit_sensors(n_sensors).items()}
    bench = biotac_bridge(sensors=sensors)
    driver = BridgeDriver(bench.port, sample_times=bench.sample_times)
    driver.start()
    frames = list(driver.frames(max_frames=12, timeout_s=20))
    driver.close()
    bench.stop()
    assert len(frames) == 12
    for frame in frames:
        assert frame.t_s is not None and frame.t_s.shape == (44,)
        assert np.allclose(np.diff(frame.t_s), SLOT_S, rtol=0, atol=1e-9), np.diff(frame.t_s)
        for sensor in sensors.values():
            asked = np.array([t for c, t in sensor.asked])
            channel_at = dict((round(t, 9), c) for c, t in sensor.asked)
            nearest = asked[np.abs(asked[:, None] - frame.t_s[None, :]).argmin(axis=0)]
            assert np.allclose(nearest, frame.t_s, rtol=0, atol=1e-9)
            assert [channel_at[round(t, 9)] for t in nearest] == frame.channels.tolist()
    starts = np.array([f.t_s[0] for f in frames])
    assert np.allclose(np.diff(starts), 44 * SLOT_S, rtol=0, atol=1e-6), np.diff(starts)
    assert 0 < starts[0] < 1.0


def test_without_sample_times_a_frame_has_none_and_a_bad_one_is_refused(biotac_bridge):
    """The wire carries no time: a driver without ``sample_times`` leaves ``t_s`` None; something that is not a
    callable is refused by name before the port is opened."""
    bench = biotac_bridge()
    with pytest.raises(ValueError, match=r"sample_times = 3: a callable taking a DataFrame"):
        BridgeDriver(bench.port, sample_times=3)
    driver = BridgeDriver(bench.port)
    driver.start()
    frame = next(driver.frames(max_frames=1, timeout_s=20))
    driver.close()
    assert frame.t_s is None and bench.sample_times(frame) is not None


def test_a_firmware_whose_frames_never_parse_keeps_no_growing_record_of_its_commands(tmp_path):
    """The bench notes when each sampling command ended until the data frame it belongs to leaves the firmware; a
    firmware whose frames the bench cannot parse (here: a wrong CRC on every data frame) never sends one, so the
    notes were never emptied — 4400 a virtual second, without end on a bench left running.  Only the latest
    :data:`~bench.hosts.cosim.COMMAND_ENDS_KEPT` (the most slots a frame holds) are kept."""
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.cosim import COMMAND_ENDS_KEPT, FIRMWARE_DIR

    reference = (FIRMWARE_DIR / "bt_bridge.c").read_text()
    tail = "    uint8_t tail[2] = {(uint8_t)(crc & 0xFF), (uint8_t)(crc >> 8)};\n"
    assert reference.count(tail) == 1, "the reference firmware's send() changed: update this test's edit"
    src = tmp_path / "bad_crc.c"
    src.write_text(reference.replace(tail, tail + "    if (type == 0x10) tail[0] ^= 1;\n"))
    with FirmwareBench(firmware=[src]) as bench:
        driver = BridgeDriver(bench.port)
        driver.start()  # (acknowledged: only data frames carry the wrong CRC)
        deadline = time.monotonic() + 60  # (a cold start compiles the emulator's kernels first: seconds)
        while driver.parser.stats.crc_errors < 20 and time.monotonic() < deadline:
            assert list(driver.frames(max_frames=1, timeout_s=0.2)) == []
        assert driver.parser.stats.crc_errors >= 20  # 20 frames of 44 slots streamed, none the host could take
        assert 0 < len(bench.board.command_ends) <= COMMAND_ENDS_KEPT
        driver.close()
