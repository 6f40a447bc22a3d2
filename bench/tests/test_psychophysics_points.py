"""The human threshold curve is built from published data points (bench/verification/psychophysics.py)."""

import numpy as np
import pytest

from bench.verification.psychophysics import HUMAN_THRESHOLD_POINTS, human_threshold_m


def test_every_point_carries_a_source_and_the_curve_passes_through_the_points():
    assert all(src for _, _, src in HUMAN_THRESHOLD_POINTS)
    f = np.array([x[0] for x in HUMAN_THRESHOLD_POINTS])
    db = np.array([x[1] for x in HUMAN_THRESHOLD_POINTS])
    assert np.all(np.diff(f) > 0)
    assert 20 * np.log10(human_threshold_m(f) / 1e-6) == pytest.approx(db, abs=1e-9)


def test_the_curve_is_the_pacinian_u_with_its_minimum_near_250_to_300_Hz():
    f = np.geomspace(10, 900, 400)
    d = human_threshold_m(f)
    assert 200 <= f[np.argmin(d)] <= 320
    assert d.min() == pytest.approx(0.09e-6, rel=0.1)  # ≈ −21 dB re 1 µm
    # between points it is interpolated in dB over log-frequency: halfway (geometric) is the mean in dB
    f0, d0, _ = HUMAN_THRESHOLD_POINTS[3]
    f1, d1, _ = HUMAN_THRESHOLD_POINTS[4]
    assert 20 * np.log10(human_threshold_m(np.sqrt(f0 * f1)) / 1e-6) == pytest.approx((d0 + d1) / 2)


def test_the_curve_at_250_hz_agrees_with_verrillo_1963_for_the_same_contactor():
    """A second source (the module's docstring): Verrillo (1963, J. Acoust. Soc. Am. 35) gives ≈ −20 dB re 1 µm near
    250 Hz for the same 2.9 cm² contactor; the Bolanowski reading there must agree within the ± 3 dB reading
    uncertainty, at 250 Hz itself as well as at the curve's minimum."""
    assert 20 * np.log10(human_threshold_m(250.0) / 1e-6) == pytest.approx(-20.0, abs=3.0)
