"""The mean friction of a slide on 60-grit sandpaper against the texture's own µ (docs/experiment/texture_fidelity.md,
"Mean friction on 60-grit").

On the effective comb (the fast and default profiles) a steady fast slide keeps µ(v)·N: the Stribeck term has
vanished, the stiff paper leaves the whole indentation to the skin, the ridges' slope force averages out along
the track and the skin hardly sticks.  The ridge-resolved fingerprint (the reference profile) adds only its
fluctuation about that mean (emulator/friction.py): its subtracted mean µ_r is the ridges' mean over the track the
slide crosses, and it is subtracted through stick phases too (two defects until 2026-11-24 moved the mean instead:
µ_r over the track's first 20 mm, subtracted only in substeps where the ridges moved)."""

import dataclasses

import numpy as np
import pytest

from emulator.fidelity import PROFILES
from emulator.sensor import NoiseSources, Sensor
from emulator.sliding import Slide
from emulator.texture import Texture

#: fixtures/textures/library.toml's T901 "60-grit sandpaper", field for field
GRIT60 = Texture(901, "60-grit sandpaper", "test surfaces", rms_height_m=53e-6, correlation_length_m=265e-6,
                 hurst=0.8, mu_static=0.7, mu_kinetic=0.56, modulus_Pa=4e9, material="paper", seed=901)


def _mean_friction_N(fidelity, force_N: float, velocity_m_per_s: float, distance_m: float,
                     start_position_m: float = 0.0) -> tuple[float, float]:
    """(mean tangential force, mean normal force) in N over the slide's cruise (from a tenth of the slide to 20 ms
    before its end), noise off, the finger landing ``start_position_m`` (m) along the track."""
    slide = Slide(0.02, GRIT60, force_N, velocity_m_per_s, distance_m, approach_s=0.1, hold_s=0.1, accel_s=0.01,
                  lift_s=0.05, start_position_m=start_position_m)
    s = Sensor(stimuli=[slide], channels_read=["PAC"], fidelity=fidelity, seed=3, noise=NoiseSources.none(),
               record_signals=("tangential_force_N", "normal_force_N"))
    t = np.arange(int((slide.end_s + 0.01) * s.fs)) / s.fs
    tangential, normal = s.signal("tangential_force_N", t), s.signal("normal_force_N", t)
    cruise = ((t > slide.slide_start_s + 0.1 * (slide.slide_end_s - slide.slide_start_s))
              & (t < slide.slide_end_s - 0.02))
    return float(tangential[cruise].mean()), float(normal[cruise].mean())


@pytest.mark.unit
@pytest.mark.parametrize("name", ["fast", "default"])
def test_a_fast_steady_slide_on_sandpaper_keeps_the_kinetic_friction_on_the_effective_comb(name):
    """Prediction: 20 N at 0.5 m/s over 10 cm. µ(0.5 m/s) = µk to e^(−100²); the texture series factor at 4 GPa
    is 1 − 6e-5; past the first centimetre the skin does not stick; so the mean tangential force is µk·N within 2 %
    (measured: fast 1.002, default 1.005)."""
    tangential, normal = _mean_friction_N(name, 20.0, 0.5, 0.1)
    ratio = tangential / (float(GRIT60.friction_coefficient(0.5)) * normal)
    assert abs(ratio - 1.0) < 0.02, f"{name}: mean friction {tangential:.3f} N at {normal:.3f} N: {ratio:.4f} µk·N"


#: where the finger lands on the track (m) in the ridge-resolved slides: 0.1 m apart, so no two 10 cm slides share
#: a stretch of the 1 m surface
LANDINGS_M = tuple(0.1 * k for k in range(8))


@pytest.mark.unit
@pytest.mark.parametrize("force_N, velocity_m_per_s, distance_m, landings, spread",
                         [(20.0, 0.5, 0.1, 6, 0.010), (2.0, 0.01, 0.01, 8, 0.039), (20.0, 0.05, 0.03, 6, 0.018)],
                         ids=["20N-0.5m_per_s", "2N-1cm_per_s", "20N-5cm_per_s"])
def test_the_ridge_resolved_fingerprint_keeps_the_slides_mean_friction(force_N, velocity_m_per_s, distance_m,
                                                                      landings, spread):
    """Consistency with the model's own contract (emulator/friction.py: the texture's µ holds the ridges' share, so
    they add their fluctuation about their mean): on the reference grid the ridge-resolved fingerprint keeps the
    slide's mean friction against the effective comb (whose skin stick-slips the same way: the ridges' force does
    not act back on the skin), over the first ``landings`` of LANDINGS_M.  Fast steady slides guard µ_r taken over
    the slide's own track (the track's first 20 mm are rougher or smoother than a 10 cm slide's: each landing's
    ratio moves, not their mean); slow stick-slipping ones guard its subtraction while the skin sticks.  One landing
    is one sample of the ridges' force about its mean: resolved over comb scatters from landing to landing with SD
    ``spread``, 1.0 % at 20 N, 0.5 m/s, 3.9 % at 2 N, 1 cm/s (a 10 mm slide: ~40 of the sandpaper's features) and
    1.8 % at 20 N, 5 cm/s (measured 2026-11-24 over the 8 landings).  So the mean of n landings is held within four
    standard errors, 4·SD/√n (1.6 %, 5.5 %, 2.9 %; measured means over 8: 0.995, 1.012, 0.990), and each landing
    within four SD (4 %, 16 %, 7 %; measured 0.978–1.009, 0.952–1.068, 0.962–1.011).  The single landing this test
    used until 2026-11-24, held within 6 %, could fail at 2 N for a model no worse; before the share's mends (one
    landing) −7.2 %, +13 % from 40 mm, +20 % and +59 %."""
    reference = PROFILES["reference"]
    comb = dataclasses.replace(reference, name="reference, effective comb", ridges="effective")
    ratios = np.array([_mean_friction_N(reference, force_N, velocity_m_per_s, distance_m, start_m)[0]
                       / _mean_friction_N(comb, force_N, velocity_m_per_s, distance_m, start_m)[0]
                       for start_m in LANDINGS_M[:landings]])
    assert abs(ratios.mean() - 1.0) < 4 * spread / np.sqrt(landings), (ratios.mean(), ratios.std(ddof=1))
    assert np.max(np.abs(ratios - 1.0)) < 4 * spread, ratios
