"""Texture tracks (emulator.texture): the random component has the texture's RMS height over the band resolved at
the reference spacing and zero mean, and coarser tracks are the same surface with the fine components absent."""

import numpy as np
import pytest

from emulator.texture import Texture, random_profile

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
