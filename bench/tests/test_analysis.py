"""The measurement functions, on synthetic signals with known answers."""

import numpy as np
import pytest

from bench.verification import analysis

pytestmark = pytest.mark.unit


def test_detection_rule_needs_more_than_three_points_beyond_four_sigma():
    t = np.arange(2200) / 2200.0
    x = np.zeros_like(t)
    x[[100, 110, 120]] = 10.0  # three points: not a detection
    assert not analysis.detected_in_window(x, t, 0.0, 0.0, 1.0)
    x[130] = -10.0  # a fourth (either sign): detection
    assert analysis.detected_in_window(x, t, 0.0, 0.0, 1.0)
    assert not analysis.detected_in_window(x, t, 0.2, 0.0, 1.0)


def test_streaming_detector_counts_events_across_block_boundaries():
    x = np.zeros(22000)
    x[[5000, 5050, 5100, 5150, 5200]] = 9.0  # one event
    x[[15000, 15001, 15002, 15003]] = 9.0  # another, straddling a block edge below
    whole = analysis.StreamingDetector(0.0, 1.0, 2200.0)
    whole.update(x)
    parts = analysis.StreamingDetector(0.0, 1.0, 2200.0)
    for a, b in [(0, 5120), (5120, 15002), (15002, 22000)]:
        parts.update(x[a:b])
    assert whole.events == parts.events == 2


def test_fit_recovers_a_decaying_sinusoid():
    t = np.arange(0, 0.1, 1 / 4400)
    x = 50 * np.exp(-t / 0.02) * np.sin(2 * np.pi * 330 * t + 0.3) + np.random.default_rng(0).normal(0, 0.5, t.size)
    fit = analysis.fit_decaying_sinusoid(t, x)
    assert fit.frequency_Hz == pytest.approx(330, abs=1) and fit.decay_s == pytest.approx(0.02, rel=0.03)


def test_band_power_of_a_sinusoid_is_half_its_squared_amplitude():
    t = np.arange(2200) / 2200.0
    x = 3.0 * np.sin(2 * np.pi * 330.0 * t)
    assert analysis.band_power_2hz(x, 2200.0, 330.0) == pytest.approx(4.5, rel=1e-3)
    f, p = analysis.largest_2hz_band(x + 0.1 * np.sin(2 * np.pi * 60 * t), 2200.0)
    assert f == pytest.approx(330.0)


def test_spectrum_is_parseval_true_for_white_noise():
    x = np.random.default_rng(1).normal(0, 2.0, 2200)
    _, p = analysis.spectrum_1s(x, 2200.0)
    assert p.sum() == pytest.approx(x.var(), rel=0.1)


def test_minimum_detectable_amplitude_is_eq_5_3():
    assert analysis.minimum_detectable_amplitude(1e-6, 0.4) == pytest.approx(1e-6)
    assert analysis.minimum_detectable_amplitude(1e-6, 40.0) == pytest.approx(1e-7)


def test_line_fits_report_r_squared():
    x = np.linspace(0, 1, 50)
    assert analysis.fit_line(x, 3 * x + 1).r_squared == pytest.approx(1.0)
    assert analysis.fit_proportional(x, 2 * x).slope == pytest.approx(2.0)


@pytest.mark.parametrize("seed", range(4))
def test_streaming_detection_is_the_sliding_windows_rising_edges_whatever_the_blocks(seed):
    """Against a brute-force reference on the whole stream (the window of ``window_n`` samples ending at each
    sample, an event where its count first exceeds ``min_points``): bursts of exceedances of every length, some
    spanning exactly the window or one sample more, cut into random blocks (single samples too) — the same count
    whatever the cuts, including events still in progress across a cut."""
    rng = np.random.default_rng(seed)
    rate, n = 2200.0, 20000
    det = analysis.StreamingDetector(0.0, 1.0, rate)
    w, k = det.window_n, det.rule.min_points
    x = np.zeros(n)
    for start in rng.choice(np.arange(0, n - 2 * w, 3 * w // 2), 8, replace=False):  # bursts a window apart
        points = int(rng.integers(2, 9))
        span = int(rng.choice([points, w - 1, w, w + 1, 2 * w]))
        x[start + np.linspace(0, span, points).astype(int)] = rng.choice([-9.0, 9.0])
    flags = (np.abs(x) > 4.0).astype(int)
    c = np.concatenate([[0], np.cumsum(flags)])
    counts = c[np.arange(1, n + 1)] - c[np.maximum(np.arange(n) - w + 1, 0)]
    above = counts > k
    expected = int(above[0]) + int(np.count_nonzero(above[1:] & ~above[:-1]))
    assert expected >= 2  # the draw makes events (and bursts that fall short)
    for cuts in (np.sort(rng.choice(np.arange(1, n), 40, replace=False)), np.arange(4990, 5010)):
        parts = analysis.StreamingDetector(0.0, 1.0, rate)
        for a, b in zip(np.r_[0, cuts], np.r_[cuts, n]):
            parts.update(x[a:b])
        assert parts.events == expected


def test_the_detection_rule_is_ds_four_sigma_in_a_100_ms_window():
    """D ch. 5's rule as DetectionRule's defaults: four points at 4.1 σ within 100 ms are detected, at 3.9 σ they are
    not, and the window [t, t + 0.1 s) leaves out a point at its end (times in s, σ = 1)."""
    t = np.arange(2200) / 2200.0
    x = np.zeros_like(t)
    x[[10, 20, 30, 40]] = 3.9
    assert not analysis.detected_in_window(x, t, 0.0, 0.0, 1.0)
    x[[10, 20, 30, 40]] = 4.1
    assert analysis.detected_in_window(x, t, 0.0, 0.0, 1.0)
    x[40], x[220] = 0.0, 4.1  # the fourth point at t = 0.1 s exactly: outside [0, 0.1)
    assert t[220] == 0.0 + 0.1
    assert not analysis.detected_in_window(x, t, 0.0, 0.0, 1.0)
    x[220], x[300] = 0.0, 4.1  # the fourth point 136 ms after the first: no 100 ms window holds all four
    det = analysis.StreamingDetector(0.0, 1.0, 2200.0)
    det.update(x)
    assert det.events == 0 and det.samples == 2200
    det.update(x[:100])
    assert det.samples == 2300  # the samples seen in all, over every block


@pytest.mark.parametrize("rate_Hz", [1106.0, 2205.7, 4400.0])
def test_the_streaming_window_is_the_nearest_whole_number_of_samples(rate_Hz):
    """The sliding window spans the rule's 0.1 s to within half a sample at rates that do not divide it."""
    assert abs(analysis.StreamingDetector(0.0, 1.0, rate_Hz).window_n - 0.1 * rate_Hz) <= 0.5


def test_a_proportional_fits_r_squared_is_taken_against_the_mean():
    """R² = 1 − Σ(y − s·x)² / Σ(y − ȳ)²: data far from the origin fitted through it explain less than their
    spread (here R² < 0, where the uncentred 1 − Σr²/Σy² would be 0.98)."""
    x = np.linspace(1.0, 2.0, 50)
    y = x + 10.0
    fit = analysis.fit_proportional(x, y)
    expected = 1 - np.sum((y - fit.slope * x) ** 2) / np.sum((y - y.mean()) ** 2)
    assert fit.r_squared == pytest.approx(expected) and fit.r_squared < 0


def test_the_welch_spectrum_is_in_db_of_power():
    """White noise of variance σ² at fs has a one-sided density 2σ²/fs (units²/Hz): welch_db gives
    10·log10 of it (within 0.3 dB over 2^16 samples)."""
    fs, sigma = 1000.0, 3.0
    f, db = analysis.welch_db(np.random.default_rng(2).normal(0, sigma, 1 << 16), fs)
    assert np.median(db[1:-1]) == pytest.approx(10 * np.log10(2 * sigma**2 / fs), abs=0.3)


def test_the_causal_band_pass_starts_in_the_steady_state_of_its_first_sample():
    """A constant signal (an offset the band-pass removes) gives no output at all, its first samples included: the
    filter starts as if the signal had always been there."""
    y = analysis.causal_band_pass(np.full(2000, 500.0), 10000.0, 30.0, 200.0)
    assert np.max(np.abs(y)) < 1e-9 * 500.0


def test_the_stick_phase_runs_from_the_stages_first_move_to_the_last_instant_before_half_slip():
    """A log (1 ms steps) whose stage starts at 0.1 s at 10 mm/s and whose skin slips at 40 % of it from 0.2 s and
    at 60 % from 0.25 s: the stage starts at 0.1 s, the last stuck instant is 0.249 s, the onset 0.25 s (slip ≥ half
    the stage's velocity)."""
    t = np.arange(400) / 1000.0
    v = np.where(t >= 0.1, 0.01, 0.0)
    slip = np.select([t >= 0.25, t >= 0.2], [0.006, 0.004], 0.0)
    phase = analysis.stick_phase(t, v, slip)
    assert (phase.stage_start_s, phase.last_stuck_s, phase.slip_onset_s) == pytest.approx((0.1, 0.249, 0.25))


def test_a_ramp_from_zero_is_capped_at_the_floor_and_a_falling_force_is_no_ramp():
    """A force rising from 0 N counts its first value as 1e-3 of its last (ratio 1000, never inf); a force that
    falls, even ending above where it started at one sample, is no ramp (0)."""
    assert analysis.ramp_ratio(np.linspace(0.0, 2.0, 10)) == pytest.approx(1000.0)
    falling = np.array([1.0, 3.0, 2.5, 2.0, 1.5, 1.2])
    assert analysis.ramp_ratio(falling) == 0.0


def test_harmonic_levels_are_each_lines_peak_over_the_median_floor_beside_it():
    """White noise (σ = 1) and unit sines on bin centres at 2·f0 and 3·f0 (f0 = 10 bins of the default 1024-sample
    segments at 10 kHz: bins ≤ f0/8): a Hann-windowed Welch line stands A²·nperseg/(6σ²) over the density 2σ²/fs,
    22.3 dB. A louder sine 30 Hz beside the second harmonic, inside its floor band, leaves the level as it was (the
    floor is the band's median); with no tolerance a line 1.5 bins off its nominal frequency is still found (±2
    bins, the Hann main lobe), within its 1.42 dB scalloping loss."""
    fs, n = 10000.0, 1 << 18
    f0 = 10 * fs / 1024
    t = np.arange(n) / fs
    noise = np.random.default_rng(5).normal(0.0, 1.0, n)
    x = noise + np.sin(2 * np.pi * 2 * f0 * t) + np.sin(2 * np.pi * 3 * f0 * t)
    expected = 10 * np.log10(1024 / 6)
    levels = analysis.harmonic_levels_db(x, fs, f0, [2, 3])
    assert levels[2] == pytest.approx(expected, abs=0.5) and levels[3] == pytest.approx(expected, abs=0.5)
    beside = x + 3.0 * np.sin(2 * np.pi * (2 * f0 + 30.0) * t)
    assert analysis.harmonic_levels_db(beside, fs, f0, [2], nperseg=8192)[2] == pytest.approx(
        10 * np.log10(8192 / 6), abs=0.5)
    off = noise + np.sin(2 * np.pi * (2 * f0 + 1.5 * fs / 1024) * t)
    assert analysis.harmonic_levels_db(off, fs, f0, [2], tolerance=0.0)[2] == pytest.approx(expected - 1.42, abs=0.5)
