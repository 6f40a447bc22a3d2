"""Issue 8's claim rows added for the figures that had none or a weaker one: the measures each row uses, shown
failing on inputs where the figure does not hold (a pure sinusoid has no harmonics, a flat force no ramp, a stick
phase as loud as the slip no rise, a replacement that keeps the worn ridges no restored repeatability)."""

import numpy as np
import pytest

from bench.textures.library import texture
from bench.verification.analysis import causal_band_pass, harmonic_levels_db, ramp_ratio, stick_phase
from bench.verification.claims import textures as rows
from bench.verification.claims.core import Bench
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.skin import Skin
from emulator.sliding import Slide

FS = 2200.0
F0 = 100 / 3  # Hz: 10 cm/s over a 3 mm grating


def _record(wave, seconds=2.0, noise_rms=0.05, seed=1):
    """``wave(phase)`` (phase in cycles of F0) sampled at FS over ``seconds`` plus white noise."""
    t = np.arange(int(seconds * FS)) / FS
    return wave(F0 * t) + noise_rms * np.random.default_rng(seed).standard_normal(t.size)


def _harmonics_row(x):
    levels = {"0.5 N @ 10 cm/s": harmonic_levels_db(x, FS, F0, range(1, 7), rows.HARMONIC_TOLERANCE)}
    return levels["0.5 N @ 10 cm/s"], rows._grating_harmonics_claim(levels, "0.5 N @ 10 cm/s")


def test_a_pure_sinusoid_has_a_fundamental_and_no_harmonics():
    levels, claim = _harmonics_row(_record(lambda c: np.sin(2 * np.pi * c)))
    assert levels[1] > 30
    assert all(abs(levels[n]) < rows.HARMONIC_MIN_DB for n in (2, 3, 4, 5, 6))
    assert claim.measured == 0 and not claim.passed


def test_a_square_wave_has_only_odd_harmonics_and_fails_the_row():
    # the library's grating profile (lands = grooves): 3rd and 5th present, 2nd and 4th absent -> 1 of 3
    levels, claim = _harmonics_row(_record(lambda c: np.sign(np.sin(2 * np.pi * c + 0.1))))
    assert levels[3] > 20 and levels[5] > 20
    assert levels[2] < rows.HARMONIC_MIN_DB and levels[4] < rows.HARMONIC_MIN_DB
    assert claim.measured == 1 and not claim.passed


def test_a_sawtooth_has_every_harmonic_and_passes_the_row():
    levels, claim = _harmonics_row(_record(lambda c: 2 * (c % 1.0) - 1))
    assert all(levels[n] > 20 for n in (2, 3, 4))
    assert claim.measured == 3 and claim.passed


def test_a_line_between_harmonics_is_not_counted():
    # a line at 2.5·f0 is no harmonic: neither the 2nd nor the 3rd; the same line at 2·f0 is the 2nd
    levels = harmonic_levels_db(_record(lambda c: np.sin(2 * np.pi * 2.5 * c)), FS, F0, [2, 3])
    assert max(levels.values()) < rows.HARMONIC_MIN_DB
    assert harmonic_levels_db(_record(lambda c: np.sin(2 * np.pi * 2 * c)), FS, F0, [2])[2] > 30


def test_harmonic_levels_refuse_a_record_too_short_or_a_floor_too_narrow():
    with pytest.raises(ValueError, match="fewer than one"):
        harmonic_levels_db(np.zeros(500), FS, F0, [2])
    with pytest.raises(ValueError, match="harmonic 12"):  # ± 5 % of 12·f0 covers the whole gap to its neighbours
        harmonic_levels_db(np.random.default_rng(0).standard_normal(4400), FS, F0, [12])


def test_ramp_ratio_of_a_ramp_a_flat_and_a_falling_force():
    ramp = np.linspace(0.1, 0.65, 44)
    assert ramp_ratio(ramp) == pytest.approx(6.5)
    assert ramp_ratio(np.full(44, 0.4)) == 0.0
    assert ramp_ratio(ramp[::-1]) == 0.0
    noisy_flat = 0.4 + 0.01 * np.random.default_rng(3).standard_normal(44)
    assert ramp_ratio(noisy_flat) < rows.STICK_RAMP_MIN
    assert ramp_ratio(np.linspace(0.0, 0.5, 10)) == pytest.approx(1000.0)  # from zero: capped, finite
    with pytest.raises(ValueError, match="at least 3"):
        ramp_ratio([0.1, 0.5])


def test_stick_phase_from_a_force_log():
    t = np.arange(0, 0.2, 0.01)
    stage = np.where(t > 0.045, 0.02, 0.0)
    slip = np.where(t >= 0.1, 0.02, 0.0005 * (t > 0.045))
    phase = stick_phase(t, stage, slip)
    assert (phase.stage_start_s, phase.last_stuck_s, phase.slip_onset_s) == pytest.approx((0.05, 0.09, 0.1))
    with pytest.raises(ValueError, match="never slips"):
        stick_phase(t, stage, np.zeros_like(t))
    with pytest.raises(ValueError, match="never moves"):
        stick_phase(t, np.zeros_like(t), slip)
    with pytest.raises(ValueError, match="slips at the stage's first move"):
        stick_phase(t, stage, stage)
    # the onset is the first instant the slip *reaches* half the stage's velocity (exactly half counts)
    half = stick_phase(np.arange(6) * 0.01, np.array([0, 1, 1, 1, 1, 1.0]), np.array([0, 0, 0.2, 0.5, 0.9, 1]))
    assert (half.stage_start_s, half.last_stuck_s, half.slip_onset_s) == pytest.approx((0.01, 0.02, 0.03))


def test_the_causal_band_pass_leaks_nothing_backward_and_keeps_its_band():
    t = np.arange(int(FS)) / FS
    burst = 2048 + np.where(t >= 0.5, 50 * np.sin(2 * np.pi * 100 * t), 0.0)  # codes: offset, then a 100 Hz burst
    y = causal_band_pass(burst, FS, 30, 200)
    assert np.max(np.abs(y[t < 0.5])) < 1e-9  # the offset makes nothing, the burst nothing before it starts
    assert np.std(y[t > 0.7]) == pytest.approx(50 / np.sqrt(2), rel=0.05)
    slow = causal_band_pass(np.sin(2 * np.pi * 3 * t), FS, 30, 200)
    assert np.std(slow[t > 0.5]) < 0.01


def test_the_slide_forces_do_not_depend_on_the_sensor_noise():
    # _slide_forces reads the forces of a noise-free run beside the acquisition's noisy one: they must be the same
    slide = Slide(0.1, texture(902), 1.0, 0.02, 0.01, approach_s=0.03, hold_s=0.1, accel_s=0.02)
    t = np.arange(0, slide.end_s, 1 / FS)
    logs = []
    for noise in (NoiseSources(), NoiseSources.none()):
        sensor = Sensor(None, [slide], ("PAC",), "default", 2012, noise)
        sensor.analog_trace("PAC", t)
        logs.append(next(e for e in sensor.graph.effects if e.name == "sliding_contact").force_log(0))
    for key in logs[0]:
        np.testing.assert_array_equal(logs[0][key], logs[1][key])


def test_slip_onset_rows_fail_when_the_stick_is_as_loud_as_the_slip():
    b = Bench()
    slide = Slide(0.5, texture(902), 1.0, 0.02, 0.06, approach_s=0.03, hold_s=0.5, accel_s=0.02)
    t = np.arange(0, slide.end_s, 1 / FS)
    steady = 2048 + 5 * np.random.default_rng(2).standard_normal(t.size)  # the same noise throughout
    rise, ramp = rows._slip_onset_claims(b, slide, t, steady)
    assert abs(rise.measured) < 3 and not rise.passed
    assert ramp.passed  # (the forces are the model's: the skin still sticks and ramps)
    assert 0.0 < rise.details["slip_onset_s"] - slide.slide_start_s < 0.2


@pytest.mark.parametrize("stiffness, reason", [(1e6, "slips at the stage's first move"),
                                               (1e4, "1 PAC samples: too short")])
def test_slip_onset_rows_fail_with_the_reason_when_the_skin_does_not_stick_long_enough(stiffness, reason):
    # a skin far stiffer tangentially than 1500 N/m reaches static friction within one or two log instants
    b = Bench(params=SensorParams().replace(skin_tangential_stiffness_N_per_m=stiffness))
    slide = Slide(0.5, texture(902), 1.0, 0.02, 0.06, approach_s=0.03, hold_s=0.5, accel_s=0.02)
    t = np.arange(0, slide.end_s, 1 / FS)
    rise, ramp = rows._slip_onset_claims(b, slide, t, 2048 + np.random.default_rng(2).standard_normal(t.size))
    assert not rise.passed and not ramp.passed
    assert np.isnan(rise.measured) and np.isnan(ramp.measured)
    assert reason in rise.details["no_stick_phase"]


def test_a_replacement_that_keeps_the_worn_ridges_fails_the_restored_spread_row():
    class NotRenewed(Skin):
        def replace(self):  # a new serial, the old ridges
            return Skin(ridge_height_m=self.ridge_height_m, serial=self.serial + 1)

    b = Bench()
    fresh = rows._roughness_on(b, Skin(), rows.SPREAD_TRIALS, "claims-wear")
    restored, _ = rows._replacement_spread(b, Skin(ridge_height_m=rows.WORN_RIDGE_M), fresh)
    kept_worn, _ = rows._replacement_spread(b, NotRenewed(ridge_height_m=rows.WORN_RIDGE_M), fresh)
    assert 0.5 <= restored <= 2.0
    assert kept_worn > 2.0


def test_highest_rank_says_whether_textures_lie_in_the_bottom_half():
    fineness = {10: 5.33, 30: 5.23, 43: 5.71, 46: 5.67, 47: 5.67, 84: 5.72, 87: 5.05, 100: 5.40}
    assert rows._highest_rank(fineness, (46, 47)) == 5  # mid-table: not the bottom half (< 4)
    assert rows._highest_rank(fineness, (87, 30)) == 1
    assert rows._highest_rank({**fineness, 46: 5.0, 47: 5.01}, (46, 47)) == 1
