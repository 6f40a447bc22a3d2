"""D ch. 6's definitions of roughness and fineness, pinned on synthetic trials where a different reading of D's text
would give a different number (audit of bench/textures/properties.py against D eqs 6.14–6.19).

* fineness is taken of the *unfiltered* PAC (D Fig. 6-4 C): content outside the roughness filter's 20–700 Hz band
  counts in the spectral centroid;
* the sliding-window spectra are averaged and the centroid is taken of the average (D: the transforms "were averaged
  and used for the spectral centroid estimation"), not an average of per-window centroids;
* roughness's background is the power measured *prior to sliding* with the stepper locked (the hold), so noise that
  lasts from the hold through the slide is removed, and noise before contact is not counted at all;
* roughness is band-limited (20–700 Hz FIR): a tone far outside the band hardly adds to it.
"""

import math

import numpy as np
import pytest

from bench.textures import properties as tp

pytestmark = pytest.mark.unit

FS = 2200.0
CONTACT, START, END, STOP = 0.5, 1.5, 3.5, 4.0  # s


def trial(pac_fn, seed=0) -> tp.TrialRecording:
    """A 4 s trial at 2.2 kS/s with PAC = mid-scale + ``pac_fn(t, rng)`` over the whole record."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(STOP * FS)) / FS
    pac = 2048.0 + pac_fn(t, rng)
    tc = np.arange(0.0, STOP, 0.1)
    return tp.TrialRecording(pac_t=t, pac=pac, pdc_t=t[::22], pdc=np.full(t[::22].size, 2000.0), current_t=tc,
                             current_A=np.full(tc.size, 0.05), contact_s=CONTACT, slide_start_s=START,
                             slide_end_s=END)


def sliding(t):
    return (t >= START) & (t <= END)


def test_centroid_counts_content_outside_the_roughness_band():
    # D Fig. 6-4 C: the FFT is of the unfiltered PAC. Equal tones at 300 and 1000 Hz: centroid 650 Hz; through the
    # 20–700 Hz FIR (gain < 0.01 at 1000 Hz) it would be ≈ 300 Hz
    rec = trial(lambda t, rng: np.where(sliding(t), 30.0 * (np.sin(2 * np.pi * 300 * t) + np.sin(2 * np.pi * 1000 * t)),
                                        0.0) + 0.01 * rng.standard_normal(t.size))
    assert tp.spectral_centroid(rec) == pytest.approx(650.0, rel=0.02)


def test_centroid_of_the_averaged_spectrum_not_the_average_of_centroids():
    # first half of the measurement window: loud 100 Hz; second half: quiet 500 Hz (amplitudes 30 and 3 -> power
    # 900 vs 9). The centroid of the averaged spectrum is power-weighted (≈ 104 Hz); the mean of per-window
    # centroids would be ≈ 300 Hz.
    w0, w1 = START + tp.MEASURE_LEAD * (END - START), END - tp.MEASURE_TAIL * (END - START)
    mid = 0.5 * (w0 + w1)

    def sig(t, rng):
        return np.where(t < mid, 30.0 * np.sin(2 * np.pi * 100 * t), 3.0 * np.sin(2 * np.pi * 500 * t))

    sc = tp.spectral_centroid(trial(sig))
    expected = (900 * 100 + 9 * 500) / 909
    assert sc == pytest.approx(expected, rel=0.05)
    assert sc < 150.0


def test_background_is_the_hold_before_sliding():
    # stepper noise (white, σ 6 bits) from contact through the end: D subtracts it, measured "prior to sliding";
    # a loud burst before contact (σ 50 bits, the finger still lowering) must not enter the background
    sigma_x, sigma_stepper = 8.0, 6.0

    def sig(t, rng):
        n = rng.standard_normal(t.size)
        return (np.where(t < CONTACT - 0.05, 50.0, 0.0) * n
                + np.where(t >= CONTACT, sigma_stepper, 0.0) * rng.standard_normal(t.size)
                + np.where(sliding(t), sigma_x, 0.0) * rng.standard_normal(t.size))

    rec = trial(sig, seed=5)
    g = float(np.sum(tp.roughness_filter(FS) ** 2))  # white-noise power gain of the FIR
    p, bg = tp.band_powers(rec)
    assert bg == pytest.approx(sigma_stepper**2 * g, rel=0.12)
    assert tp.roughness(rec) == pytest.approx(math.log(sigma_x**2 * g), abs=0.12)


def test_roughness_is_band_limited_but_centroid_is_not():
    # a 1000 Hz tone while sliding: outside the 20–700 Hz band, so roughness stays at the small in-band
    # noise's level; the centroid (unfiltered) goes to ~1000 Hz
    def sig(t, rng):
        return 2.0 * rng.standard_normal(t.size) + np.where(sliding(t), 40.0 * np.sin(2 * np.pi * 1000 * t), 0.0)

    rec = trial(sig, seed=2)
    p, bg = tp.band_powers(rec)
    tone_power = 40.0**2 / 2
    assert p - bg < 0.01 * tone_power  # FIR gain < 0.01 beyond 750 Hz: the tone's power is attenuated > 40 dB
    assert tp.spectral_centroid(rec) > 950.0


def test_the_centroids_spectrum_is_welchs_with_256_sample_hann_segments_at_half_overlap():
    """Derived, against scipy.signal.welch: the averaged spectrum the centroid is taken of (README: "256 samples
    (116 ms at 2.2 kS/s, 8.6 Hz bins), 50 % overlap, each segment mean-removed and Hann-tapered") is Welch's
    estimate with those settings, up to Welch's constant scale and its doubling of the bins between DC and Nyquist
    (to 1e-12); the centroid of a trial is the same spectrum's."""
    from scipy import signal as sps

    rng = np.random.default_rng(4)
    x = 2048.0 + np.cumsum(rng.standard_normal(3001)) * 0.3 + 20 * np.sin(2 * np.pi * 140 * np.arange(3001) / FS)
    f, p = tp.averaged_spectrum(x, FS)
    fw, pw = sps.welch(x, FS, window="hann", nperseg=256, noverlap=128, detrend="constant", scaling="spectrum")
    assert np.array_equal(f, fw) and f[1] == pytest.approx(FS / 256)
    pw = pw / np.where((fw > 0) & (fw < FS / 2), 2.0, 1.0)
    np.testing.assert_allclose(p / p.sum(), pw / pw.sum(), rtol=1e-12, atol=0)

    rec = trial(lambda t, rng: 20 * np.sin(2 * np.pi * 140 * t) * sliding(t) + 5 * rng.standard_normal(t.size))
    w = tp.measurement_window(rec)
    fw, pw = sps.welch(rec.pac[(rec.pac_t >= w[0]) & (rec.pac_t <= w[1])], FS, window="hann", nperseg=256,
                       noverlap=128, detrend="constant", scaling="spectrum")
    pw = pw / np.where((fw > 0) & (fw < FS / 2), 2.0, 1.0)
    assert tp.spectral_centroid(rec) == pytest.approx((pw * fw).sum() / pw.sum(), rel=1e-12)
