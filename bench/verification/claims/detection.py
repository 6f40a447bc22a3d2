"""Detection claims: D Table 5-3 with the dissertation's rule — the 0.25 mm solder ball at most 5 %, the other
five spheres of D Table 5-2 at least 95 %."""

from __future__ import annotations

from bench.verification.claims.core import Bench, Claim, claim_group
from bench.verification.claims.impact import detections
from emulator.stimuli import DROP_HEIGHT_M, SPHERES


@claim_group("detection")
def detection_claims(b: Bench, drops: int = 200) -> list[Claim]:
    """D Table 5-3 with the dissertation's rule: 0.25 mm ≤ 5 %, the other five spheres ≥ 95 %."""
    drops = 30 if b.quick else drops
    rows = []
    for k, name in enumerate(SPHERES):
        hits = detections(b, name, DROP_HEIGHT_M, drops, seed_offset=k)  # Hertz drops on this sensor's skin
        rate = 100.0 * hits / drops
        lo, hi = (0.0, 5.0) if name == "0.25 mm solder ball" else (95.0, 100.0)
        rows.append(Claim(f"detected: {name}", "≤ 5 %" if hi == 5.0 else "≥ 95 %", rate, lo, hi, "%",
                          "D Table 5-3; §7", {"drops": drops, "detected": int(hits)}, kind="prediction",
                          note="from mass and drop height (D Table 5-2), restitution, the force→pressure slope, "
                               "the resonance and the noise; nothing was tuned to these rates"))
    return rows
