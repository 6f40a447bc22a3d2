"""Limits of the texture layer's contact law that hold whatever the model's choices of thickness and Poisson ratio.

``sliding.TEXTURE_LAYER_M`` (3 mm) and ``sliding.POISSON_RATIO`` (0.3) are model choices: D gives neither, so no
test here reads them back.  What contact mechanics does predict, for any layer thicker than the contact patch and
any isotropic material, is checked instead (docs/model.md: δ_t = T·(1 − exp(−N/(k·T))), k = 2·a·E/(1 − ν²)).
"""

import numpy as np
import pytest

from emulator.params import SensorParams
from emulator.sliding import contact_force_from_depth
from emulator.texture import Texture


def _foam(modulus_Pa: float) -> Texture:
    return Texture(907, "foam", "test", 100e-6, 500e-6, 0.5, 1.0, 0.8, modulus_Pa=modulus_Pa, seed=1)


@pytest.mark.unit
def test_a_small_patch_indents_a_soft_texture_as_a_half_space():
    """Prediction (Boussinesq's rigid flat punch on a half-space): while the patch radius a (0.1 mm at ~0.1 mN,
    0.3 mm at ~2 mN) is far below any plausible layer thickness, the texture's own indentation δ_t (the depth less
    the skin's Hertz share (N/K)^(2/3)) is N/(2·a·E*), with E* = E/(1 − ν²) between E (ν = 0) and 4E/3 (ν = 0.5,
    incompressible) — the only values an isotropic material allows — and the same multiple of E for any modulus
    (ν is a material ratio, not a function of stiffness). Loads in N, lengths in m, moduli in Pa."""
    p = SensorParams()
    ratios = []
    for modulus in (20e3, 50e3, 200e3):
        for depth_m in (10e-6, 30e-6):
            load = float(contact_force_from_depth(depth_m, p, _foam(modulus)))
            radius = p.contact_radius_at_1N_m * np.cbrt(load)
            assert radius < 0.35e-3, (modulus, depth_m, radius)  # a patch well below a millimetre
            texture_depth = depth_m - (load / p.contact_stiffness_N_per_m1_5) ** (2 / 3)
            ratios.append(load / (2 * radius * texture_depth) / modulus)  # E*/E
    ratios = np.array(ratios)
    assert np.all((ratios >= 1.0) & (ratios <= 4 / 3 * 1.01)), ratios
    assert ratios.max() / ratios.min() < 1.02, ratios  # one ν for every modulus (the small-load limit to 2 %)
