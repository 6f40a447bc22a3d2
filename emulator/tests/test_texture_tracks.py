"""Texture tracks (emulator.texture): the random component has the texture's RMS height over the band resolved at
the reference spacing and zero mean, and coarser tracks are the same surface with the fine components absent."""

import numpy as np
import pytest

from emulator.texture import PeriodicComponent, Texture, periodic_on_grid, periodic_profile, random_profile

ROUGH = Texture(906, "rough", "test", rms_height_m=3e-6, correlation_length_m=200e-6, hurst=0.7, mu_static=1.0,
                mu_kinetic=0.8, seed=11)


@pytest.mark.unit
def test_the_random_track_at_the_reference_spacing_has_the_textures_rms_and_zero_mean():
    """Derived (the scaling rule): at 0.5 µm the whole band is resolved, so the RMS is ``rms_height_m`` to 1e-9
    relative; the mean is 0 to 1e-12 of it."""
    h = random_profile(ROUGH, 0.5e-6)
    assert np.sqrt(np.mean(h**2)) == pytest.approx(ROUGH.rms_height_m, rel=1e-9)
    assert abs(np.mean(h)) < 1e-12 * ROUGH.rms_height_m


@pytest.mark.unit
def test_a_coarser_random_track_is_the_same_surface_without_its_finest_components():
    """Consistency: the 10 µm track has less RMS than the 0.5 µm one (components below 20 µm absent) and equals the
    fine track low-passed to the coarse track's band, to 1e-5 of the RMS height (each track is scaled by its own
    RMS, in which the coarse track's Nyquist cosine weighs differently: ~1e-6 here)."""
    fine, coarse = random_profile(ROUGH, 0.5e-6), random_profile(ROUGH, 10e-6)
    assert np.std(coarse) < np.std(fine)
    spectrum = np.fft.rfft(fine)[:coarse.size // 2 + 1]
    spectrum[-1] = 0.0  # (the coarse track's Nyquist bin holds the fine track's cosine only in part)
    low_passed = np.fft.irfft(spectrum, coarse.size) * coarse.size / fine.size
    c = np.fft.rfft(coarse)
    c[-1] = 0.0
    np.testing.assert_allclose(np.fft.irfft(c, coarse.size), low_passed, atol=1e-5 * ROUGH.rms_height_m)


GRATED = Texture(907, "grated", "test", rms_height_m=0.0, correlation_length_m=200e-6, hurst=0.7, mu_static=1.0,
                 mu_kinetic=0.8, periodic=(PeriodicComponent(3e-3, 100e-6, (0.0, -0.333, 0.0, 0.2)),
                                           PeriodicComponent(0.7e-3, 20e-6, (0.5,), orientation_deg=40.0)))


@pytest.mark.unit
@pytest.mark.parametrize("x0_m, dx_m, n", [(0.0739, 10e-6, 11300), (0.99, 2.5e-6, 45000), (1.02, 10e-6, 70000),
                                           (-0.006, 10e-6, 3)])
def test_the_periodic_relief_on_a_grid_is_the_sum_of_its_cosines(x0_m, dx_m, n):
    """Consistency: the angle-addition evaluation on ``x0 + i·dx`` equals :func:`periodic_profile` at those positions
    to the rounding of the positions themselves: |Δ| ≤ Σ A·(k·16 ulp(x) + 16 ε) (here ~1e-12 of the amplitude;
    a wrong sign or harmonic is off by the amplitude)."""
    x = np.arange(n) * dx_m + x0_m
    expected = periodic_profile(GRATED, x)
    got = periodic_on_grid(GRATED, x0_m, dx_m, n)
    bound = 0.0
    for c in GRATED.periodic:
        k = 2 * np.pi / c.track_period_m
        for j, rel in enumerate((1.0, *c.harmonics), start=1):
            bound += abs(rel * c.amplitude_m) * (j * k * 16 * np.spacing(np.abs(x).max()) + 16 * np.finfo(float).eps)
    assert got.shape == (n,) and np.abs(got - expected).max() <= bound
    assert np.array_equal(periodic_on_grid(ROUGH, x0_m, dx_m, n), np.zeros(n))  # no relief: zeros


@pytest.mark.unit
def test_a_periodic_component_is_its_fundamental_plus_its_harmonics_at_their_orders():
    """Derived (the definition of ``harmonics``: amplitudes of the 2nd, 3rd, … harmonic relative to the
    fundamental): a 3 mm grating with harmonics (0, −1/3, 0, 0.2) is A·[cos(wx) − cos(3wx)/3 + 0.2·cos(5wx)],
    w = 2π/3 mm, to 1e-12 of A; a harmonic one order off is off by ~A/3."""
    c = GRATED.periodic[0]
    one = Texture(908, "grating", "test", rms_height_m=0.0, correlation_length_m=200e-6, hurst=0.7, mu_static=1.0,
                  mu_kinetic=0.8, periodic=(c,))
    x = np.linspace(0.0, 0.01, 2001)
    w = 2 * np.pi / c.track_period_m
    expected = c.amplitude_m * (np.cos(w * x) - 0.333 * np.cos(3 * w * x) + 0.2 * np.cos(5 * w * x))
    assert c.track_period_m == pytest.approx(3e-3)
    np.testing.assert_allclose(periodic_profile(one, x), expected, rtol=0, atol=1e-12 * c.amplitude_m)


@pytest.mark.unit
@pytest.mark.parametrize("hurst", [0.3, 0.7, 1.0])
def test_the_random_track_is_self_affine_with_the_textures_hurst_exponent(hurst):
    """Derived (the definition of a self-affine surface, model.md): the track's power spectrum is flat below
    q0 = 2π / correlation length and falls as q^-(1 + 2H) above it; the log-log slope of its periodogram from 3·q0
    to a tenth of the Nyquist wavenumber is −(1 + 2H) within 0.05 (a mutation pass found that a slope of −(1 + H)
    was caught only by a saved-samples regression)."""
    t = Texture(906, "rough", "test", rms_height_m=3e-6, correlation_length_m=200e-6, hurst=hurst, mu_static=1.0,
                mu_kinetic=0.8, seed=11)
    dx = 2e-6
    h = random_profile(t, dx)
    power = np.abs(np.fft.rfft(h)) ** 2
    q = 2 * np.pi * np.fft.rfftfreq(h.size, dx)
    q0 = 2 * np.pi / t.correlation_length_m
    band = (q > 3 * q0) & (q < 0.1 * q.max())
    slope = np.polyfit(np.log(q[band]), np.log(power[band]), 1)[0]
    assert slope == pytest.approx(-(1 + 2 * hurst), abs=0.05)
    flat = (q > 0) & (q < 0.8 * q0)
    assert np.ptp(np.log(power[flat])) < 0.05  # flat below q0


@pytest.mark.unit
@pytest.mark.parametrize("angle_deg, along_mm", [(0.0, 1.0), (45.0, 2 ** 0.5), (60.0, 2.0), (80.0, 5.7588)])
def test_an_oblique_component_is_met_less_often_along_the_track(angle_deg, along_mm):
    """Derived (geometry: ridges of pitch p crossed at θ from their normal are met every p / cos θ): a 1 mm
    grating at 60° repeats every 2 mm along the track, and its profile does (a mutation pass found p·cos θ went
    unnoticed: the only oblique test compared the surface with itself)."""
    c = PeriodicComponent(1e-3, 10e-6, orientation_deg=angle_deg)
    assert c.track_period_m == pytest.approx(along_mm * 1e-3, rel=1e-4)
    one = Texture(908, "oblique", "test", rms_height_m=0.0, correlation_length_m=200e-6, hurst=0.7, mu_static=1.0,
                  mu_kinetic=0.8, periodic=(c,))
    x = np.linspace(0.0, 0.02, 4001)
    period = c.track_period_m
    np.testing.assert_allclose(periodic_profile(one, x + period), periodic_profile(one, x), atol=1e-6 * c.amplitude_m)
    assert np.max(np.abs(periodic_profile(one, x + 0.5 * period) + periodic_profile(one, x))) < \
        1e-6 * c.amplitude_m  # half a track period: the opposite phase


@pytest.mark.unit
def test_a_track_starting_further_on_is_the_same_surface_shifted_and_reads_between_samples_linearly():
    """surface_track(texture, dx, start): its first height is the whole surface's at ``start`` (not at −start), and
    SurfaceTrack.at a quarter step past a sample is the linear value there (not read backwards)."""
    from emulator.texture import surface_track

    tex = Texture(950, "t", "test", 20e-6, 300e-6, 0.8, 0.6, 0.5, seed=4,
                  periodic=(PeriodicComponent(1e-3, 10e-6),))
    dx = 10e-6
    whole = surface_track(tex, dx)
    shifted = surface_track(tex, dx, start_m=250 * dx)
    assert shifted.heights_m[0] == whole.heights_m[250] and shifted.heights_m[7] == whole.heights_m[257]
    h = whole.heights_m
    assert whole.at(10.25 * dx) == pytest.approx(0.75 * h[10] + 0.25 * h[11], rel=1e-12, abs=1e-18)
