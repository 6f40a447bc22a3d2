"""Discretization stage by stage, second-order sections, carried state."""

import numpy as np
import pytest
from scipy import signal

from emulator import filters

pytestmark = pytest.mark.unit


def _gain_db(sos, f, fs):
    _, h = signal.sosfreqz(sos, worN=[f], fs=fs)
    return 20 * np.log10(abs(h[0]))


def test_prewarping_puts_the_1040Hz_corner_where_it_belongs_near_nyquist():
    fs = 2200.0  # the corner sits at 95 % of Nyquist
    z, p, k = filters.lowpass_butter2(1040.0)
    pre = filters.discretize(z, p, k, fs, "prewarped")
    plain = filters.discretize(z, p, k, fs, "bilinear")
    assert _gain_db(pre, 1040.0, fs) == pytest.approx(-3.01, abs=0.05)
    assert _gain_db(plain, 1040.0, fs) < -6.0  # plain bilinear warps the corner far down


def test_dc_gain_matches_the_analog_prototype_for_every_method():
    z, p, k = filters.resonance(330.0, 0.02)
    for method in filters.DISCRETIZATIONS:
        sos = filters.discretize(z, p, k, 8800.0, method)
        assert _gain_db(sos, 0.0, 8800.0) == pytest.approx(0.0, abs=1e-6)


def test_resonance_rings_at_its_frequency_with_its_decay():
    z, p, k = filters.resonance(330.0, 0.02)
    assert np.allclose(-1 / p.real, 0.02)
    assert np.allclose(np.abs(p), 2 * np.pi * 330.0)


def test_unknown_method_is_refused():
    z, p, k = filters.lowpass_butter2(1040.0)
    with pytest.raises(ValueError, match="unknown discretization"):
        filters.discretize(z, p, k, 8800.0, "euler")


def test_corners_above_nyquist_fall_back_to_the_plain_bilinear_map_and_stay_stable():
    z, p, k = filters.lowpass_butter2(1040.0)
    pre = filters.discretize(z, p, k, 1500.0, "prewarped")
    plain = filters.discretize(z, p, k, 1500.0, "bilinear")
    assert np.allclose(pre, plain)
    assert np.all(np.abs(np.concatenate([np.roots(s[3:]) for s in pre])) < 1)


def test_sos_filter_output_is_independent_of_block_size():
    rng = np.random.default_rng(1)
    x = rng.standard_normal(5000)
    sos = filters.discretize(*filters.lowpass_butter2(1040.0), 8800.0, "prewarped")
    whole = filters.SosFilter(sos)(x)
    f = filters.SosFilter(sos)
    pieces = np.concatenate([f(x[i:i + n]) for i, n in zip(np.cumsum([0, 1, 7, 100, 999]), [1, 7, 100, 999, 3893])])
    assert np.array_equal(whole, pieces)


def test_settle_starts_at_steady_state_without_a_transient():
    sos = filters.discretize(*filters.highpass_1st(10.0), 8800.0, "prewarped", gain_at_hz=1000.0)
    f = filters.SosFilter(sos)
    f.settle(0.7)
    y = f(np.full(1000, 0.7))
    assert np.max(np.abs(y)) < 1e-12


def test_remembered_steady_state_is_scipys_and_a_fresh_array():
    """Consistency: the remembered ``sosfilt_zi`` equals scipy's to the bit, and a caller scaling or editing the
    array it got (SosFilter.settle multiplies it) never changes what the next sensor gets."""
    from emulator import electrodes

    sos = signal.butter(4, 0.1, output="sos")
    first = filters.sosfilt_zi(sos)
    assert np.array_equal(first, signal.sosfilt_zi(sos))
    first *= 7.0
    assert np.array_equal(filters.sosfilt_zi(sos), signal.sosfilt_zi(sos))
    table = electrodes.electrode_positions_mm()
    table[:] = 0.0
    assert np.any(electrodes.electrode_positions_mm() != 0.0)


@pytest.mark.parametrize("taps", [2, 3])
def test_columns_filtered_along_axis_0_are_lfilters_to_the_bit(taps):
    """Consistency: a 2-D signal filtered down its columns by the compiled loop gives scipy's lfilter output and
    final state bit for bit (the electrodes' filter runs this way); an empty block leaves the state as it was
    (scipy's final state is then undefined)."""
    rng = np.random.default_rng(3)
    b = rng.normal(size=taps)
    a = np.concatenate([[1.0], rng.uniform(-0.4, 0.4, taps - 1)])
    zi = rng.normal(size=(taps - 1, 19))
    y, zf = filters.lfilter(b, a, np.zeros((0, 19)), zi, axis=0)
    assert y.shape == (0, 19) and np.array_equal(zf, zi)
    for rows in (1, 1500):
        x = rng.normal(size=(rows, 19))
        zi = rng.normal(size=(taps - 1, 19))
        y, zf = filters.lfilter(b, a, x, zi, axis=0)
        y_ref, zf_ref = signal.lfilter(b, a, x, axis=0, zi=zi)
        assert np.array_equal(y, y_ref) and np.array_equal(zf, zf_ref)


def test_the_matched_z_design_maps_each_pole_by_exp_and_the_zeros_at_infinity_to_nyquist():
    """Matched z (s = r -> z = exp(r/fs)): a 2-pole low-pass at 1 kHz on an 8.8 kHz grid has its poles at exp(p/fs),
    its two zeros at infinity at z = −1 (no response at all at Nyquist, 4.4 kHz) and unit DC gain."""
    fs = 8800.0
    z, p, k = filters.lowpass_butter2(1000.0)
    sos = filters.discretize(z, p, k, fs, "matched")
    zd, pd, _ = signal.sos2zpk(sos)
    assert np.allclose(np.sort_complex(pd), np.sort_complex(np.exp(p / fs)))
    assert np.allclose(zd, -1.0)
    _, h = signal.sosfreqz(sos, worN=[0.0, fs / 2], fs=fs)
    assert abs(h[0]) == pytest.approx(1.0) and abs(h[1]) < 1e-9


def test_a_first_order_high_pass_has_its_3_db_corner_at_its_frequency():
    """highpass_1st(f): −3.01 dB at f (here 10 Hz on an 8.8 kHz grid, prewarped), unit gain far above it."""
    sos = filters.discretize(*filters.highpass_1st(10.0), 8800.0, "prewarped", gain_at_hz=1000.0)
    assert _gain_db(sos, 10.0, 8800.0) == pytest.approx(-3.01, abs=0.01)
    assert _gain_db(sos, 2000.0, 8800.0) == pytest.approx(0.0, abs=0.01)


def test_a_single_section_with_a_first_order_numerator_keeps_its_second_order_denominator():
    """SosFilter runs one section through 2 taps only when both b2 and a2 are 0: a section with one zero and two
    poles (b2 = 0, a2 ≠ 0) gives scipy's sosfilt output."""
    sos = np.array([[0.2, 0.1, 0.0, 1.0, -1.2, 0.5]])
    x = np.random.default_rng(4).standard_normal(500)
    assert np.allclose(filters.SosFilter(sos)(x), signal.sosfilt(sos, x))
