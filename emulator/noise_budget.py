"""The pressure path's noise budget, source by source (D Table 5-1 and ch. 5).

For each source: its RMS referred to the first-stage input over the dissertation's 1040 Hz band,
and its RMS on PAC in bits as the model's own filters shape it (noise-equivalent bandwidth of
the PAC path).  Sources after the first stage are given directly in PAC bits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import signal

from emulator import filters
from emulator.conversions import ADC_LSB_V
from emulator.params import SensorParams

DISSERTATION_BAND_HZ = 1040.0


@dataclass
class BudgetLine:
    source: str
    rti_uV: float | None  # RMS referred to the stage-1 input over 1040 Hz (None: not an input-referred source)
    pac_bits: float  # RMS on PAC, in bits, through the model's filters
    note: str


def pac_noise_bandwidth_Hz(params: SensorParams) -> float:
    """Noise-equivalent bandwidth of the analog PAC path (stage-1 low-pass × stage-2 high-pass)."""
    z1, p1, k1 = filters.lowpass_butter2(params.stage1_lowpass_Hz)
    z2, p2, k2 = filters.highpass_1st(params.stage2_highpass_Hz)
    z, p, k = np.concatenate([z1, z2]), np.concatenate([p1, p2]), k1 * k2
    f = np.geomspace(1e-2, 1e6, 400000)
    _, h = signal.freqs_zpk(z, p, k, worN=2 * np.pi * f)
    return float(np.trapezoid(np.abs(h) ** 2, f))


def budget(params: SensorParams | None = None) -> list[BudgetLine]:
    p = params or SensorParams()
    enbw = pac_noise_bandwidth_Hz(p)
    to_pac_bits = p.stage1_gain * p.stage2_gain / ADC_LSB_V

    def input_line(name, density, note):
        return BudgetLine(name, density * math.sqrt(DISSERTATION_BAND_HZ) * 1e6, density * math.sqrt(enbw) * to_pac_bits,
                          note)

    current = p.amp_current_noise_A_per_rtHz * p.bridge_resistance_ohm
    lines = [
        input_line("bridge Johnson noise", p.johnson_noise_V_per_rtHz,
                   f"√(4kTR), R = {p.bridge_resistance_ohm / 1e3:.0f} kΩ at {p.bridge_temperature_C:.0f} °C"),
        input_line("amplifier voltage noise", p.amp_voltage_noise_V_per_rtHz, "first stage"),
        input_line("amplifier current noise × R", current, "negligible"),
        input_line("second-stage noise (referred to input)", p.stage2_voltage_noise_V_per_rtHz / p.stage1_gain,
                   "negligible after the gain of 10; reference profile only"),
    ]
    intrinsic = math.sqrt(sum(x.rti_uV**2 for x in lines[:3]))
    intrinsic_bits = math.sqrt(sum(x.pac_bits**2 for x in lines[:3]))
    lines.append(BudgetLine("intrinsic total (Table 5-1)", intrinsic, intrinsic_bits, "published 0.49 µV ≈ 0.6 bits"))
    hum_bits = p.mains_amplitude_V / math.sqrt(2) * to_pac_bits
    lines += [
        BudgetLine(f"mains hum ({p.mains_frequency_Hz:.0f} Hz)", p.mains_amplitude_V / math.sqrt(2) * 1e6, hum_bits,
                   "power in its 2 Hz band = 0.2 bits²"),
        BudgetLine("ADC quantization", None, 1 / math.sqrt(12), "uniform, 1/√12 LSB"),
        BudgetLine("ADC input noise", None, p.adc_noise_rms_bits, "model choice"),
        BudgetLine("SPI coupling", None, 0.0, "zero while the bus is silent during conversions"),
    ]
    total = math.sqrt(intrinsic_bits**2 + hum_bits**2 + 1 / 12 + p.adc_noise_rms_bits**2)
    lines.append(BudgetLine("total at the ADC output", None, total, "published 1.4 ± 0.1 bits RMS"))
    return lines


def format_budget(lines: list[BudgetLine], params: SensorParams | None = None) -> str:
    p = params or SensorParams()
    pa_per_bit = ADC_LSB_V / p.pac_V_per_Pa
    out = [f"PAC noise budget (PAC path noise bandwidth {pac_noise_bandwidth_Hz(p):.0f} Hz; "
           f"1 bit = {pa_per_bit:.3f} Pa)",
           f"{'source':42s} {'µV RTI/1040 Hz':>15s} {'Pa':>8s} {'PAC bits':>9s}  note"]
    for x in lines:
        rti = f"{x.rti_uV:.3f}" if x.rti_uV is not None else "—"
        pa = f"{x.pac_bits * pa_per_bit:.3f}"
        out.append(f"{x.source:42s} {rti:>15s} {pa:>8s} {x.pac_bits:9.3f}  {x.note}")
    return "\n".join(out)
