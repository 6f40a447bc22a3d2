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
