"""The run's streaming summary (bench.running.aggregate.RunSummary) against numpy on the whole arrays: what
record.json states per channel (samples, bad samples, rail samples, rate, mean, standard deviation, minimum,
maximum), the median / MAD fall-back of the resting statistics, and the traces plot's envelope — the same numbers
whatever the chunks the samples arrived in (consistency, exact or to rounding)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bench.running.aggregate import RunSummary, hist_mad_sigma, hist_median

pytestmark = pytest.mark.unit

DURATION_S = 2.0


def _stream(seed: int, n: dict):
    """Per channel ``n[name]`` samples over the scene: random-walk codes clipped to the rails (so both rails
    hold samples), one in 40 flagged."""
    rng = np.random.default_rng(seed)
    out = {}
    for name, count in n.items():
        t = np.sort(rng.uniform(0.0, DURATION_S, count))
        code = np.clip(2048 + np.cumsum(rng.normal(0, 90, count)).astype(np.int64), 0, 4095).astype(np.uint16)
        status = (rng.random(count) < 1 / 40).astype(np.uint8)
        out[name] = (t, code, status)
    return out


def _summary(stream: dict, cuts: int, seed: int) -> RunSummary:
    scene = SimpleNamespace(duration_s=DURATION_S, stimuli=[], impact_detection=False)
    summary = RunSummary(scene, list(stream), bins=50)
    edges = np.sort(np.random.default_rng(seed).uniform(0, DURATION_S, cuts))
    for a, b in zip(np.concatenate([[-1.0], edges]), np.concatenate([edges, [DURATION_S + 1]])):
        summary.add_parts({name: tuple(arr[(t >= a) & (t < b)] for arr in (t, code, st))
                           for name, (t, code, st) in stream.items()})
    summary.finish()
    return summary


@pytest.mark.parametrize("seed, cuts", [(0, 0), (1, 7), (2, 31)])
def test_the_records_channel_figures_are_numpys_on_the_whole_arrays(seed, cuts):
    stream = _stream(seed, {"PAC": 3001, "PDC": 1200, "E7": 640})
    summary = _summary(stream, cuts, seed)
    for name, (t, code, st) in stream.items():
        good = code[st == 0].astype(np.int64)
        got = summary.channels[name].stats(DURATION_S)
        assert got["samples"] == code.size and got["bad_samples"] == int((st != 0).sum())
        assert got["rail_samples"] == int(((good == 0) | (good == 4095)).sum()) > 0
        assert got["rate_Hz"] == code.size / DURATION_S
        assert got["mean_code"] == pytest.approx(good.mean(), rel=1e-12)
        assert got["std_code"] == pytest.approx(good.std(), rel=1e-9)
        assert (got["min_code"], got["max_code"]) == (good.min(), good.max())


@pytest.mark.parametrize("seed, cuts", [(3, 5), (4, 12)])
def test_the_envelope_is_each_time_bins_lowest_highest_and_mean_code(seed, cuts):
    stream = _stream(seed, {"PAC": 2500, "PDC": 301})
    summary = _summary(stream, cuts, seed)
    width = DURATION_S / 50
    for name, (t, code, st) in stream.items():
        tt, x = t[st == 0], code[st == 0].astype(float)
        b = np.minimum((tt / width).astype(int), 49)
        used = np.unique(b)
        centres, lo, hi, mean = summary.channels[name].envelope()
        np.testing.assert_allclose(centres, (used + 0.5) * width, rtol=1e-12)
        assert np.array_equal(lo, [x[b == k].min() for k in used])
        assert np.array_equal(hi, [x[b == k].max() for k in used])
        np.testing.assert_allclose(mean, [x[b == k].mean() for k in used], rtol=1e-12)


@pytest.mark.parametrize("values", [[5, 1, 9, 9, 2], [5, 1, 9, 9], [7], [7, 8], [3, 3, 3, 40, 41, 42],
                                    list(np.random.default_rng(5).integers(0, 4096, 1000)),
                                    list(np.random.default_rng(6).integers(2000, 2010, 999))])
def test_the_histograms_median_and_mad_sigma_are_numpys(values):
    """Exact: the median of the values a histogram counts (the mean of the two middle ones for an even count) and
    1.4826 × the median absolute deviation from it — the resting statistics' fall-back (baseline and σ)."""
    x = np.asarray(values)
    hist = np.bincount(x, minlength=4096)
    med = hist_median(hist)
    assert med == np.median(x)
    assert hist_mad_sigma(hist, med) == pytest.approx(1.4826 * np.median(np.abs(x - med)), rel=1e-15, abs=0)


def test_an_empty_histogram_has_no_median_and_no_sigma():
    hist = np.zeros(4096, np.int64)
    assert math.isnan(hist_median(hist)) and math.isnan(hist_mad_sigma(hist, 0.0))
