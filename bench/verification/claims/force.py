"""Force claims: 11.5 mN per PDC bit (± 5 %, R² ≥ 0.99) over 0–2 N, and a clear departure above the 2 N knee."""

from __future__ import annotations

from bench.verification import analysis
from bench.verification.claims.core import Bench, Claim, claim_group
from emulator.stimuli import Press


@claim_group("force")
def force_claims(b: Bench) -> list[Claim]:
    """11.5 mN per PDC bit (± 5 %, R² ≥ 0.99) over 0–2 N; a clear departure above 2 N."""
    press = Press(0.5, 4.0, ramp_s=8.0, hold_s=0.2)
    rec = b.acquire([press], 9.0, sequence=("PDC",), slot_rate_Hz=100.0)
    t, pdc = rec["PDC"]
    force = press.force(t)
    rest = pdc[t < 0.45].mean()
    below = (force > 0.05) & (force <= 2.0) & (t < 8.6)
    above = (force >= 2.5) & (t < 8.6)
    fit = analysis.fit_line(force[below], pdc[below] - rest)
    fit_above = analysis.fit_line(force[above], pdc[above] - rest)
    ratio = fit_above.slope / fit.slope
    return [
        Claim("force per PDC bit, 0–2 N", "11.5 mN/bit ± 5 %", 1e3 / fit.slope, 11.5 * 0.95, 11.5 * 1.05, "mN/bit",
              "D ch. 4; §1", kind="consistency",
              note="reads back force_per_pdc_bit_N: the force→pressure slope is defined as the PDC scale ÷ "
                   "11.5 mN, so a wrong bridge or gain still measures 11.5 mN/bit"),
        Claim("linearity of force -> PDC, 0–2 N", "R² ≥ 0.99", fit.r_squared, 0.99, 1.0, "R²", "D ch. 4 (0.995)",
              kind="consistency", note="the force→pressure map is linear below the knee by construction"),
        Claim("slope above the knee / slope below", "clear departure: < 0.5", ratio, 0.0, 0.5, "ratio",
              "D ch. 4; §1", kind="consistency", note="reads back force_slope_above_knee = 0.25 (a model choice)"),
    ]
