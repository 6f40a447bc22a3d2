"""Where a texture property's trial-to-trial spread comes from (the σ the texture experiment's classifier learns).

Derived: the rig starts every trial at a random place on the texture, as D's rig did, so the roughness of
one texture and movement scatters by the sampling variance of a stationary vibration over the measurement window:
σ(ln P) ≈ 1/√(T·B), T the window (s) and B = (∫S df)² / ∫S² df the effective bandwidth (Hz) of the band-passed
PAC's spectrum S. A rig that always started at one place would scatter by sensor noise alone, ~0.1 of that.
"""

import numpy as np
import pytest
from scipy import signal

from bench.rigs.texture_rig import Movement, TextureRig
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


def test_roughness_scatters_by_the_sampling_variance_of_a_random_start():
    """Polyester taffeta (T85, a smooth fabric) at D's roughness movement, 0.2 N @ 6.31 cm/s, 20 trials:
    the observed σ over the predicted 1/√(T·B) in 0.6–1.7 (measured 1.29; the sample σ of 20 trials is good to ±16 %,
    and textures whose relief varies along the track reach ~2). A fixed start measures 0.15."""
    rig = TextureRig(skin=Skin(), wear=False)
    rough, predicted = [], []
    for k in range(TRIALS):
        trial = rig.run_trial(texture(85), Movement(0.2, 0.0631), seed=10_000 + k)
        r, s = _roughness_and_sampling_sigma(trial.recording)
        rough.append(r)
        predicted.append(s)
    starts = {round(rig.run_trial(texture(85), Movement(0.2, 0.0631), seed=10_000 + k).start_position_m, 6)
              for k in range(3)}
    ratio = np.std(rough, ddof=1) / np.mean(predicted)
    assert len(starts) == 3, "every trial should start at its own place on the texture"
    assert 0.6 <= ratio <= 1.7, f"roughness σ is {ratio:.2f} × the sampling σ 1/√(T·B)"
