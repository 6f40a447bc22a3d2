"""Impact claims: a decaying sinusoid of about 330 Hz and 20 ms after a sphere hits; amplitude linear in the
impulse."""

from __future__ import annotations

import numpy as np

from bench.verification import analysis
from bench.verification.claims.core import Bench, Claim, claim_group
from emulator.stimuli import SPHERES, SphereDrop


@claim_group("impact")
def impact_ring_claims(b: Bench) -> list[Claim]:
    """Decaying sinusoid of ~330 Hz and ~20 ms; amplitude linear in the impulse below clipping."""
    mass = SPHERES["5/64 in aluminum bearing"][0]
    impact = {"restitution": b.params.impact_restitution, "contact_s": b.params.impact_contact_s}  # as scenes do
    rec = b.acquire([SphereDrop(0.5, mass, **impact)], 1.0, sequence=("PAC",), slot_rate_Hz=4400.0)
    t, pac = rec["PAC"]
    sel = (t > 0.5 + 1e-3) & (t < 0.62)
    ring = analysis.fit_decaying_sinusoid(t[sel] - 0.5, pac[sel] - np.mean(pac[t < 0.45]))
    # linearity: peak amplitude vs impulse for all six spheres (noise-free analog PAC)
    impulses, peaks = [], []
    for name, (m, _) in SPHERES.items():
        drop = SphereDrop(0.2, m, **impact)
        tt, x = b.analog_pac_bits([drop], 0.5, rate_Hz=22000.0)
        x = x - x[tt < 0.19].mean()
        impulses.append(drop.impulse_Ns)
        peaks.append(float(np.max(np.abs(x))))
    lin = analysis.fit_proportional(impulses, peaks)
    return [
        Claim("impact ringing frequency", "330 ± 30 Hz", ring.frequency_Hz, 300.0, 360.0, "Hz", "D ch. 5; §1",
              kind="consistency", note="reads back resonance_Hz = 330 Hz through the SPI path"),
        Claim("impact ringing decay time constant", "20 ± 4 ms", ring.decay_s * 1e3, 16.0, 24.0, "ms", "D ch. 5; §1",
              kind="consistency", note="reads back resonance_decay_s = 20 ms through the SPI path"),
        Claim("impact amplitude linear in impulse", "R² ≥ 0.999", lin.r_squared, 0.999, 1.0, "R²", "issue 1",
              {"impulse_Ns": impulses, "peak_bits": peaks}, kind="consistency",
              note="the model is a linear system below clipping; not a published figure"),
    ]
