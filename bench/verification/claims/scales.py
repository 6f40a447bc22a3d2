"""Scale claims: 0.0365 kPa per PDC bit and 0.37 Pa per PAC bit (± 2 %); the ranges of D Table 4-1."""

from __future__ import annotations

import numpy as np

from bench.verification import analysis
from bench.verification.claims.core import Bench, Claim, claim_group
from emulator import conversions as conv
from emulator.stimuli import PressureCalibrator


@claim_group("scales")
def scale_claims(b: Bench) -> list[Claim]:
    """0.0365 kPa per PDC bit and 0.37 Pa per PAC bit (± 2 %); ranges of Table 4-1."""
    levels_kPa = np.arange(0.0, 60.0, 10.0)
    steps = [PressureCalibrator(0.5 + 1.0 * i, 1.0, offset_Pa=lv * 1e3, fade_s=0.0) for i, lv in enumerate(levels_kPa)]
    rec = b.acquire(steps, 0.5 + len(levels_kPa), sequence=("PDC",), slot_rate_Hz=100.0)
    t, pdc = rec["PDC"]
    means = [pdc[(t > 0.5 + i + 0.2) & (t < 0.5 + i + 0.9)].mean() for i in range(len(levels_kPa))]
    fit = analysis.fit_line(means, levels_kPa)
    amp_Pa, f = 300.0, 200.0
    rec = b.acquire([PressureCalibrator(0.0, 4.0, amplitude_Pa=amp_Pa, frequency_Hz=f, fade_s=0.0)], 4.0,
                    sequence=("PAC",), slot_rate_Hz=2200.0)
    pac = rec["PAC"][1][2200:]
    amp_bits = np.sqrt(2 * analysis.band_power_2hz(pac, 2200.0, f))
    pa_per_bit = amp_Pa / amp_bits
    rest = float(np.mean(pdc[t < 0.4]))
    p = b.params
    p0_code = p.stage1_bias_V / conv.ADC_LSB_V  # zero gauge pressure
    top_code = p0_code + 103.4 / fit.slope if fit.slope else np.nan
    return [
        Claim("PDC scale", "0.0365 kPa/bit ± 2 %", fit.slope, 0.0365 * 0.98, 0.0365 * 1.02, "kPa/bit",
              "D Table 4-1", {"r_squared": fit.r_squared, "resting_code": rest}, kind="derived",
              note="bridge sensitivity × excitation × stage-1 gain ÷ LSB, all published, against the published "
                   "scale; a wrong bridge, gain or ADC reference fails it"),
        Claim("PAC scale", "0.37 Pa/bit ± 2 %", float(pa_per_bit), 0.37 * 0.98, 0.37 * 1.02, "Pa/bit",
              "D Table 4-1", kind="derived", note="as the PDC scale, times the stage-2 gain 99.1"),
        Claim("PAC range (half-span)", "±0.76 kPa ± 2 %", float(2048 * pa_per_bit / 1e3), 0.76 * 0.98, 0.76 * 1.02,
              "kPa", "D Table 4-1", kind="derived", note="2048 × the PAC scale row: the same number"),
        Claim("PDC code at full transducer range 103.4 kPa", "inside 0..4095", float(top_code), 0.0, 4095.0,
              "code", "D ch. 5", kind="consistency",
              note="the accepted range is the whole ADC: it cannot fail unless the PDC scale is off by ~20 %"),
    ]
