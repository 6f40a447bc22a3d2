"""Where a texture property's trial-to-trial spread comes from (the σ the texture experiment's classifier learns).

Derived: the rig starts every trial at a random place on the texture, as D's rig did. Were the trials' windows
on independent stretches of texture (a long texture), the roughness of one texture and movement would scatter by the
sampling variance of a stationary vibration over the measurement window: σ(ln P) ≈ 1/√(T·B), T the window (s) and
B = (∫S df)² / ∫S² df the effective bandwidth (Hz) of the band-passed PAC's spectrum S. On D's 75 mm square the
5 cm strokes overlap (the starts spread over R ≈ 22 mm, the window covers L ≈ 35 mm of track), so only the stretches
two trials do not share differ: for a vibration whose power fluctuates on scales short against R the scatter falls
to √(R/(3L)) of the independent one (E|Δ1 − Δ2| = R/3 for two uniform starts), above the sensor noise alone, which
a fixed start measures (~0.15 of the sampling σ).
"""

import numpy as np
import pytest
from scipy import signal

from bench.rigs.texture_rig import Movement, RigSettings, TextureRig
from bench.textures.library import texture
from bench.textures.properties import measurement_window, properties, roughness_filter
from emulator.skin import Skin

pytestmark = pytest.mark.unit

TRIALS = 20


def _roughness_and_sampling_sigma(rec) -> tuple[float, float]:
    """The trial's roughness (ln units) and the 1/√(T·B) it should scatter by."""
    y = np.convolve(rec.pac - rec.pac.mean(), roughness_filter(rec.pac_rate_hz), mode="same")
    t0, t1 = measurement_window(rec)
    sel = (rec.pac_t >= t0) & (rec.pac_t <= t1)
    f, s = signal.welch(y[sel], rec.pac_rate_hz, nperseg=512)
    bandwidth = s.sum() ** 2 / (s ** 2).sum() * (f[1] - f[0])
    return properties(rec)["roughness"], 1.0 / np.sqrt((t1 - t0) * bandwidth)


#: the sensor-noise floor of the scatter, in units of the sampling σ: a fixed start (T85, 0.2 N @ 6.31 cm/s)
FIXED_START_RATIO = 0.15
MOVEMENT = Movement(0.2, 0.0631)  # D's roughness movement


def _scatter_over_sampling_sigma(rig: TextureRig) -> float:
    """σ of T85's roughness over ``TRIALS`` trials on ``rig``, in units of the mean predicted 1/√(T·B)."""
    rough, predicted = [], []
    for k in range(TRIALS):
        trial = rig.run_trial(texture(85), MOVEMENT, seed=10_000 + k)
        r, s = _roughness_and_sampling_sigma(trial.recording)
        rough.append(r)
        predicted.append(s)
    return float(np.std(rough, ddof=1) / np.mean(predicted))


def test_roughness_scatters_by_the_sampling_variance_of_independent_stretches():
    """Polyester taffeta (T85, a smooth fabric) at D's roughness movement, 20 trials, starts anywhere on a 1 m
    texture (independent stretches): the observed σ over the predicted 1/√(T·B) in 0.6–1.7 (measured 1.29; the
    sample σ of 20 trials is good to ±16 %, and textures whose relief varies along the track reach ~2)."""
    rig = TextureRig(skin=Skin(), wear=False, settings=RigSettings(texture_side_m=1.0))
    starts = {round(rig.run_trial(texture(85), MOVEMENT, seed=10_000 + k).start_position_m, 6) for k in range(3)}
    assert len(starts) == 3, "every trial should start at its own place on the texture"
    ratio = _scatter_over_sampling_sigma(rig)
    assert 0.6 <= ratio <= 1.7, f"roughness σ is {ratio:.2f} × the sampling σ 1/√(T·B)"


def test_on_ds_square_overlapping_strokes_scatter_less_but_more_than_the_sensor_noise():
    """The same 20 trials on D's 75 mm square: the scatter lies above the sensor-noise floor (0.15; 0.18 asked, so a
    rig that always started in one place fails) and below the overlap bound √(R/(3L) + 0.15²) (R the room for the
    start, L the window's length of track; 0.48 here, 20 % allowed for the sample σ). Measured 0.24: the taffeta's power fluctuates less locally than a Gaussian
    vibration of its bandwidth, whose scatter over independent stretches also holds structure longer than the room."""
    rig = TextureRig(skin=Skin(), wear=False)
    first, last = rig.start_range_m(MOVEMENT)
    trial = rig.run_trial(texture(85), MOVEMENT, seed=10_000)
    t0, t1 = measurement_window(trial.recording)
    window_track_m = (t1 - t0) * MOVEMENT.velocity_m_per_s
    bound = np.sqrt((last - first) / (3 * window_track_m) + FIXED_START_RATIO ** 2)
    ratio = _scatter_over_sampling_sigma(rig)
    assert 1.2 * FIXED_START_RATIO <= ratio <= 1.2 * bound, (ratio, bound)
