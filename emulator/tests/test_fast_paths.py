"""The cheaper paths give the same numbers, bit for bit, as the plain formulas they replace.

* the electrode gaps, worked in place from each contact's precomputed footprint, against the array formula of
  ``electrode_gaps_mm``'s docstring written out directly (with and without a shear shift, several contacts);
* a first-order section run as a 2-tap ``lfilter`` against the same section as a 3-tap biquad;
* the mains hum read from one tabulated period against the per-sample formula at the absolute index;
* the static force curve on a block where every sample presses (no masks) against the same samples beside an idle one;
* ``filters.lfilter`` (a compiled loop, or lfilter's C routine called directly) against ``scipy.signal.lfilter``.
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from emulator import filters
from emulator.effects import Block
from emulator.electrodes import (Contact, bulge_balance, electrode_gaps_mm, electrode_positions_mm,
                                 indentation_fraction, resting_gaps_mm, surface_point_mm)
from emulator.extrinsic import MainsHum
from emulator.mechanics import static_pressure_from_force
from emulator.params import SensorParams


def _gaps_by_the_formula(p, contacts, t, positions, rest):
    """gap_i = max(g_i − (g₀ − g_min)·Σ a·exp(−u) + Σ (g₀ − g_min)·κ·a·u_s·exp(−u_s), g_min), on fresh arrays."""
    g0, gmin = p.resting_gap_mm, p.minimum_gap_mm
    frac, bulge = np.zeros((t.size, len(positions))), np.zeros((t.size, len(positions)))
    for c in contacts:
        f, ft = c.state(t)
        a = indentation_fraction(p, f)
        w2 = c.indenter_radius_mm**2 + p.skin_spread_mm**2
        kappa = bulge_balance(p, c.center_mm, np.sqrt(w2))
        rel = positions - c.center_mm[None, :]
        along = rel @ np.asarray(c.shear_direction, float)
        s_mm = p.shear_shift_mm_per_N * ft
        d2 = (rel * rel).sum(axis=1)[None, :] - 2 * np.outer(s_mm, along) + (s_mm * s_mm)[:, None]
        u = d2 / (2 * w2)
        us = u / p.bulge_width_ratio**2
        frac += a[:, None] * np.exp(-u)
        bulge += ((g0 - gmin) * kappa * a)[:, None] * (us * np.exp(-us))
    return np.maximum(rest[None, :] - (g0 - gmin) * frac + bulge, gmin)


def test_electrode_gaps_equal_the_array_formula_bit_for_bit():
    p = SensorParams(electrode_gap_spread_mm=0.7, electrode_gap_seed=11)
    pos = electrode_positions_mm()
    rest = resting_gaps_mm(p, len(pos))
    t = np.linspace(0.0, 2.0, 301)
    ramp = lambda s: np.clip(s, 0.0, 1.0) * 2.5  # noqa: E731  N
    contacts = [Contact(surface_point_mm(-4.0, 10.0), 3.0, ramp),  # no shear: the footprint's unshifted shapes
                Contact(surface_point_mm(2.0, -30.0), 2.0, lambda s: 0.8 * s, 0.5, (0.6, 0.8, 0.0)),  # sheared
                Contact(surface_point_mm(-12.0, 60.0), 5.0, lambda s: 4.0 + 0 * s)]  # bottoms the thin gaps
    for cs in (contacts[:1], contacts[1:2], contacts):
        expected = _gaps_by_the_formula(p, cs, t, pos, rest)
        assert np.array_equal(electrode_gaps_mm(p, cs, t, pos, rest), expected)


def test_a_first_order_section_runs_as_2_taps_with_the_biquads_numbers():
    sos = filters.discretize(*filters.highpass_1st(10.0), 8800.0, "prewarped", gain_at_hz=1000.0)
    assert sos[0, 2] == 0.0 and sos[0, 5] == 0.0
    x = 1.2 + 1e-3 * np.random.default_rng(4).standard_normal(5000)
    f = filters.SosFilter(sos)
    f.settle(1.2)
    zi = signal.sosfilt_zi(sos)[0] * 1.2
    expected, _ = signal.lfilter(sos[0, :3], sos[0, 3:], x, zi=zi)
    got = np.concatenate([f(x[:1234]), f(x[1234:1235]), f(x[1235:])])
    assert np.array_equal(got, expected)


def test_the_tabulated_hum_is_the_per_sample_formula_bit_for_bit():
    """Blocks read from one tabulated period equal the formula at each sample's absolute index, whatever the cut
    (a rig's exact-length reads, the sensor's 2 s blocks, ten hours in); a hum with no whole period on the grid
    (59.5 Hz) takes the formula itself."""
    p = SensorParams()
    for fs in (4400.0, 8800.0, 70400.0):
        h = MainsHum(p, 7)
        n0 = int(10 * 3600 * fs) if fs == 8800.0 else 0
        for n in (17600, 97, 1, 5000, 440, 20000, 333):
            got = h.process(Block(n0, n, fs), {})["stage1_input_V"]
            assert np.array_equal(got, h.at(n0 + np.arange(n, dtype=float), fs)), (fs, n)
            got += 1.0  # the graph sums into what an effect returns: the next block must not see it
            n0 += n
    assert MainsHum(p, 7).period(8800.0) == 440  # 60, 120 and 180 Hz all repeat after 440 samples of 8.8 kHz
    odd = MainsHum(p.replace(mains_frequency_Hz=59.5), 7)
    assert odd.period(8800.0) is None
    whole = odd.process(Block(0, 3000, 8800.0), {})["stage1_input_V"]
    cut = np.concatenate([odd.process(Block(a, b - a, 8800.0), {})["stage1_input_V"]
                          for a, b in ((0, 7), (7, 1234), (1234, 3000))])
    assert np.array_equal(cut, whole)


def _force_curve_by_the_formula(F, p):
    """k·(F − (1 − r)·w·(softplus((F − F_knee)/w) − softplus(−F_knee/w))), softplus(x) = x beyond x = 30."""
    k, r, w, Fk = p.force_to_pressure_Pa_per_N, p.force_slope_above_knee, p.force_knee_width_N, p.force_knee_N
    x = (F - Fk) / w
    softplus = np.where(x > 30, x, np.log1p(np.exp(np.minimum(x, 30))))
    return k * (F - (1 - r) * w * (softplus - np.log1p(np.exp(-Fk / w))))


def test_the_force_curve_of_a_block_that_presses_throughout_is_the_masked_formulas():
    p = SensorParams()
    rng = np.random.default_rng(2)
    for F in (np.exp(-np.linspace(0.0, 30.0, 5000)),  # a released contact creeping back: tiny but > 0
              rng.uniform(0.0, 3.0, 5000),  # through the knee
              rng.uniform(0.0, 8.0, 5000),  # x = (F − F_knee)/w up to 75: across 30, where softplus(x) = x
              rng.uniform(0.0, 40.0, 5000)):
        F[0] = max(F[0], 1e-3)
        every = static_pressure_from_force(F, p)
        beside_idle = static_pressure_from_force(np.concatenate([F, [0.0]]), p)  # one idle sample: the masks
        assert np.array_equal(every, beside_idle[:-1]) and beside_idle[-1] == 0.0
        assert np.array_equal(every, _force_curve_by_the_formula(F, p))


def test_lfilter_compiled_or_without_the_wrapper_gives_scipys_numbers():
    """1-D signals through 2 or 3 taps take the compiled loop, the rest lfilter's C routine: scipy's numbers either
    way, a NaN or an infinity included (propagated, never hidden); b = [1] padded with a zero is lfilter's own b."""
    rng = np.random.default_rng(5)
    x1, x2 = rng.standard_normal(3000), rng.standard_normal((400, 19))
    x1[[100, 2000]] = np.nan, np.inf
    for b, a in (([0.2, 0.2], [1.0, -0.6]), ([0.1, 0.2, 0.1], [1.0, -1.5, 0.6]), ([1.0], [1.0, -0.3]),
                 ([1.0, 0.0], [1.0, -0.3])):
        b, a = np.array(b), np.array(a)
        zi1 = rng.standard_normal(len(a) - 1)
        zi2 = rng.standard_normal((len(a) - 1, 19))
        kept = zi1.copy()
        for got, want in ((filters.lfilter(b, a, x1, zi1), signal.lfilter(b, a, x1, zi=zi1)),
                          (filters.lfilter(b, a, x1[:99], zi1), signal.lfilter(b, a, x1[:99], zi=zi1)),
                          (filters.lfilter(b, a, x2, zi2, axis=0), signal.lfilter(b, a, x2, axis=0, zi=zi2))):
            assert np.array_equal(got[0], want[0], equal_nan=True)
            assert np.array_equal(got[1], want[1], equal_nan=True)
        assert np.array_equal(zi1, kept)  # the caller's state is not touched
    y, _ = filters.lfilter(np.array([1.0, 0.0]), np.array([1.0, -0.3]), x1[:99], np.array([0.4]))
    assert np.array_equal(y, signal.lfilter([1.0], [1.0, -0.3], x1[:99], zi=[0.4])[0])

