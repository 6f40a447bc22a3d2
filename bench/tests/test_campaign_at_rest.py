"""The campaign's ``none`` case (no fault) checks that the data read as a sensor at rest and that nothing was
flagged: a broken "healthy" path — codes shifted, another unit's sensor, a firmware counting faults that did not
happen — fails it, where the link-level check alone (no CRC errors, drops or flagged samples) passed it."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from bench.campaigns import faults as campaign
from bench.campaigns.faults import run_case

pytestmark = pytest.mark.unit

STATUS_COUNTERS = ("parity_errors", "error_words", "losses", "finds", "command_errors")


@pytest.mark.parametrize("scene", ["rest", "taps", "sphere_drops", "press"])
def test_the_none_case_checks_the_frames_before_each_scenes_first_stimulus_and_passes(scene, monkeypatch):
    """In every scene the healthy case passes, and its at-rest check looked at the frames before the scene's first
    stimulus: all 150 at rest, at least the minimum before a press at 0.3 s — never one after a stimulus began."""
    seen = []
    real = campaign.not_at_rest

    def spy(frames, sensors, stimuli, start_s):
        seen.append((len(frames), [st.start_s for st in stimuli], start_s))
        return real(frames, sensors, stimuli, start_s)

    monkeypatch.setattr(campaign, "not_at_rest", spy)
    result = run_case(campaign.FAULTS["none"], scene, 0)
    assert result["passed"], result
    ((n_frames, starts, start_s),) = seen
    assert n_frames == 150 and (not starts) == (scene == "rest") and 0 <= start_s < 0.1


@pytest.mark.parametrize("shift", [+12, -12])
def test_codes_shifted_on_a_healthy_link_fail_the_none_case_naming_the_channel_and_band(shift, monkeypatch):
    """A sensor whose every code is 12 codes off (a broken conversion on the healthy path; PAC's band is ±9.5
    codes, the quiet channels' ±4.2) streams cleanly — no CRC error, drop or flag — yet fails the case: the
    problem names the sensor, the channel, the code, the frame and the resting band."""
    from emulator.sensor import Sensor

    real = Sensor.sample

    def shifted(self, channels, times, bus_active=None):
        return (real(self, channels, times, bus_active).astype(int) + shift).clip(0, 4095).astype(np.uint16)

    monkeypatch.setattr(Sensor, "sample", shifted)
    result = run_case(campaign.FAULTS["none"], "rest", 0)
    assert not result["passed"], result
    assert result["problem"].startswith("sensor 1 at rest read ") and "outside its resting band" in result["problem"]


def test_the_resting_band_is_the_sensors_own_units(monkeypatch):
    """A bench whose sensor is a drawn unit (unit 17: its bridge offset, biases and electrode gaps its own) passes
    the case, its bands taken from its own parameters; the same frames judged against the nominal unit's bands fail
    (the units differ by far more than the noise): the check tells one unit from another."""
    from emulator.params import SensorParams
    from emulator.sensor import Sensor
    from emulator.units import draw_params

    unit = draw_params(17)
    real_init = Sensor.__init__

    def as_unit(self, *args, **kwargs):
        if not args and "params" not in kwargs:  # the bench's sensors (not the noise budget's own)
            kwargs["params"] = unit
        real_init(self, *args, **kwargs)

    monkeypatch.setattr(Sensor, "__init__", as_unit)
    result = run_case(campaign.FAULTS["none"], "rest", 0)
    assert result["passed"], result
    real = campaign.not_at_rest

    def judged_as_nominal(frames, sensors, stimuli, start_s):
        nominal = {n: SimpleNamespace(params=SensorParams(), variant=s.variant) for n, s in sensors.items()}
        return real(frames, nominal, stimuli, start_s)

    monkeypatch.setattr(campaign, "not_at_rest", judged_as_nominal)
    result = run_case(campaign.FAULTS["none"], "rest", 0)
    assert not result["passed"] and "outside its resting band" in result["problem"], result


@pytest.mark.parametrize("counter", STATUS_COUNTERS)
def test_a_firmware_counter_of_faults_on_a_healthy_link_fails_the_none_check(counter):
    """Each of the firmware's fault counters, non-zero on frames that are otherwise clean, fails ``none``'s check by
    name (the flagged-samples check alone passed it: a firmware counting faults it did not flag went unseen)."""
    frames = [SimpleNamespace(sensor_mask=0b01, status=np.zeros((2, 1), np.uint8)) for _ in range(3)]
    status = SimpleNamespace(**{**dict.fromkeys(STATUS_COUNTERS, 0), counter: 2})
    stats = SimpleNamespace(crc_errors=0, dropped_frames=0)
    assert campaign._clean(frames, status, stats) is None
    problem = campaign.FAULTS["none"].check(frames, status, stats)
    assert problem == f"the firmware flagged faults on a healthy link ({counter} 2)", problem
    status = SimpleNamespace(**dict.fromkeys(STATUS_COUNTERS, 0))
    assert campaign.FAULTS["none"].check(frames, status, stats) is None
    frames[1].sensor_mask = 0b11
    assert "sensor masks seen: [1, 3]" in campaign.FAULTS["none"].check(frames, status, stats)


def test_a_scene_stimulated_too_early_to_check_rest_fails_rather_than_checking_nothing():
    """Fewer than REST_MIN_FRAMES frames before the first stimulus: the at-rest check says so (a case that checks
    nothing never passes)."""
    from emulator.stimuli import Tap

    frames = [SimpleNamespace(seq=k, channels=np.zeros(44, int)) for k in range(150)]
    problem = campaign.not_at_rest(frames, {}, [Tap(0.05, 1.0)], 0.001)
    assert problem is not None and problem.startswith("only 2 frames before the scene's first stimulus at 0.05 s")


def test_a_unit_whose_electrodes_rest_far_apart_passes_read_in_its_frames_order(monkeypatch):
    """The multiplexer keeps a fraction exp(−t_acq/τ) of the previous electrode's value in each sample: in a
    streamed frame E1 follows the previous frame's last electrode, not the electrode order the noise budget reads
    them in.  A "biotac-sp" of unit 1234 (E24 rests ~1200 codes below E1, so E1 reads ~8 codes low in every frame
    but the first) at rest passes the case: each band is centred on the code the sensor reads at rest in the
    frame's own order."""
    import dataclasses

    from emulator.sensor import Sensor
    from emulator.units import draw_params

    unit = draw_params(1234)
    real_init = Sensor.__init__

    def as_unit(self, *args, **kwargs):
        if not args and "params" not in kwargs:  # the bench's sensors
            kwargs["params"] = unit
        real_init(self, *args, **kwargs)

    monkeypatch.setattr(Sensor, "__init__", as_unit)
    case = dataclasses.replace(campaign.FAULTS["none"], bench_kw={"variant": "biotac-sp"})
    for seed in (0, 1):
        result = run_case(case, "rest", seed)
        assert result["passed"], result
