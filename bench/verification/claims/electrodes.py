"""Electrode claims: the pressed electrode's impedance rises with force, pressing over an electrode moves it
most, mirror-image contacts give mirror-image patterns, and the same contact's PDC rise (11.5 mN per bit)."""

from __future__ import annotations

import numpy as np

from bench.verification.claims.core import Bench, Claim, claim_group
from emulator import conversions as conv
from emulator.electrodes import electrode_positions_mm
from emulator.sensor import NoiseSources
from emulator.stimuli import Touch

ELECTRODES = [f"E{n}" for n in range(1, 20)]


@claim_group("electrodes")
def electrode_claims(b: Bench) -> list[Claim]:
    """Monotonic impedance with force, the pressed electrode moves most, mirror symmetry, PDC consistency."""

    def pattern(touch, at_s):
        # each electrode read twice in a row; the second reading has no memory of the previous electrode
        twice = [e for e in ELECTRODES for _ in range(2)]
        rec = b.acquire([touch], at_s + 0.05, sequence=twice, slot_rate_Hz=3800.0, noise=NoiseSources.none())
        z = []
        for e in ELECTRODES:
            t, code = rec[e]
            second = slice(1, None, 2)
            t, code = t[second], code[second]
            z.append(float(conv.impedance_ohm(code[t >= at_s - 0.02]).mean()))
        return np.array(z)

    rest = pattern(Touch(5.0, 1.0), 1.0)
    # monotonic rise of the pressed electrode's impedance with force
    forces = np.array([0.1, 0.3, 0.6, 1.0, 2.0, 3.5, 5.0])
    z17 = [pattern(Touch(0.2, float(f), 0.3, 1.0, electrode="E17", indenter_radius_mm=2.0), 0.6)[16]
           for f in forces]
    monotonic = bool(np.all(np.diff(z17) > 0))
    # pressing over each electrode moves that electrode most
    hits = 0
    for n in range(1, 20):
        z = pattern(Touch(0.2, 1.0, 0.3, 1.0, electrode=f"E{n}", indenter_radius_mm=1.5), 0.6)
        hits += int(np.argmax(z - rest) == n - 1)
    # mirror-image contacts about y = 0 give mirror-image patterns
    pos = electrode_positions_mm()
    mirror_of = [int(np.argmin(np.linalg.norm(pos - pos[i] * np.array([1, -1, 1]), axis=1))) for i in range(19)]
    za = pattern(Touch(0.2, 1.5, 0.3, 1.0, x_mm=-6.0, angle_deg=35.0), 0.6)
    zb = pattern(Touch(0.2, 1.5, 0.3, 1.0, x_mm=-6.0, angle_deg=-35.0), 0.6)
    asym = float(np.max(np.abs(za - zb[mirror_of]) / rest))
    # the same contact's DC pressure: 11.5 mN per PDC bit
    rec = b.acquire([Touch(0.5, 1.0, 0.3, 1.0, electrode="E17")], 1.5, sequence=("PDC",), slot_rate_Hz=200.0)
    t, pdc = rec["PDC"]
    rise = float(pdc[(t > 0.9) & (t < 1.7)].mean() - pdc[t < 0.45].mean())
    return [
        Claim("pressed electrode's impedance rises with force", "monotonic", float(monotonic), 1.0, 1.0,
              "monotonic", "D ch. 4; §5", {"force_N": forces.tolist(), "impedance_ohm": z17}, kind="consistency",
              note="the indentation depth is monotonic in force and Z = Z_series + ρ/gap by construction"),
        Claim("pressing over an electrode moves it most", "19 of 19", float(hits), 19.0, 19.0, "electrodes",
              "issue 4; §5 (G positions)", kind="consistency",
              note="the indentation is centred on the pressed electrode; checks positions and plumbing"),
        Claim("mirror-image contacts give mirror-image patterns", "< 0.1 % apart", 100 * asym, 0.0, 0.1, "%",
              "issue 4; §5 (G positions)", kind="consistency",
              note="the electrode table is mirror-symmetric and the model has no asymmetric term: it cannot fail "
                   "for physics reasons"),
        Claim("a 1 N contact's PDC rise", "87 bits (11.5 mN/bit) ± 5 %", rise, 1.0 / 0.0115 * 0.95,
              1.0 / 0.0115 * 1.05, "bits", "D ch. 4; §1", kind="consistency",
              note="reads back force_per_pdc_bit_N through a touch"),
    ]
