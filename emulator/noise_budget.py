"""The noise budget, channel by channel (D Table 5-1 and ch. 5; issue 10.2).

PAC, source by source: each source's RMS referred to the first-stage input over the dissertation's 1040 Hz band,
and its RMS on PAC in bits as the model's own filters shape it (noise-equivalent bandwidth of the PAC path).
Sources after the first stage are given directly in bits.  Then every other channel (PDC, TDC, TAC, E1..E19):
its own path's noise, the reference noise at its resting code, the ADC's input noise and quantization.

Totals add independent sources in quadrature; quantization is taken as 1/√12 LSB, which is what a constant input
dithered by ≳ 0.45 LSB of Gaussian noise shows on average over where the input sits within a code.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import signal

from emulator import channels as ch
from emulator import filters
from emulator.conversions import ADC_LSB_V
from emulator.params import SensorParams

DISSERTATION_BAND_HZ = 1040.0
QUANTIZATION_BITS = 1 / math.sqrt(12)


@dataclass
class BudgetLine:
    source: str
    rti_uV: float | None  # RMS referred to the stage-1 input over 1040 Hz (None: not an input-referred source)
    pac_bits: float  # RMS on the line's channel (PAC for the PAC section), in bits, through the model's filters
    note: str
    channel: str = "PAC"


def _enbw_Hz(z, p, k) -> float:
    f = np.geomspace(1e-2, 1e6, 400000)
    _, h = signal.freqs_zpk(z, p, k, worN=2 * np.pi * f)
    return float(np.trapezoid(np.abs(h) ** 2, f))


def pac_noise_bandwidth_Hz(params: SensorParams) -> float:
    """Noise-equivalent bandwidth of the analog PAC path (stage-1 low-pass × stage-2 high-pass)."""
    z1, p1, k1 = filters.lowpass_butter2(params.stage1_lowpass_Hz)
    z2, p2, k2 = filters.highpass_1st(params.stage2_highpass_Hz)
    return _enbw_Hz(np.concatenate([z1, z2]), np.concatenate([p1, p2]), k1 * k2)


def pdc_noise_bandwidth_Hz(params: SensorParams) -> float:
    """Noise-equivalent bandwidth of the analog PDC path (stage-1 low-pass)."""
    return _enbw_Hz(*filters.lowpass_butter2(params.stage1_lowpass_Hz))


def thermistor_noise_V(params: SensorParams) -> tuple[float, float]:
    """(TDC, TAC) RMS noise in V from the thermistor-node noise ``tdc_noise_V`` through the read-out filters at
    the thermal network's rate — present only while the thermal network runs (the settled-at-rest shortcut has
    none)."""
    from emulator.thermal import TAC_GAIN, THERMAL_RATE_HZ

    fs = THERMAL_RATE_HZ
    lp = filters.discretize(np.array([]), np.array([-2 * np.pi * params.tdc_bandwidth_Hz]),
                            2 * np.pi * params.tdc_bandwidth_Hz, fs, "prewarped")
    zh, ph, kh = filters.highpass_1st(params.tac_highpass_Hz)
    hp = filters.discretize(zh, ph, kh, fs, "prewarped", gain_at_hz=10.0)
    impulse = np.zeros(20000)
    impulse[0] = 1.0
    h_tdc = signal.sosfilt(np.array(lp), impulse)
    h_tac = TAC_GAIN * signal.sosfilt(np.array(hp), h_tdc)
    return (params.tdc_noise_V * float(np.sqrt(np.sum(h_tdc**2))),
            params.tdc_noise_V * float(np.sqrt(np.sum(h_tac**2))))


def resting_volts(params: SensorParams, variant: str = ch.DEFAULT_VARIANT) -> dict[str, float]:
    """Noise-free analog value (V) at the ADC input of every sampled channel of the sensor (``variant``: its
    electrodes) at rest."""
    from emulator.sensor import NoiseSources, Sensor

    names = ["PAC", "PDC", "TDC", "TAC"] + [f"E{n}" for n in range(1, ch.variant(variant).n_electrodes + 1)]
    s = Sensor(params, [], names, seed=0, noise=NoiseSources.none(), variant=variant)
    idx = np.array([ch.channel_index(n) for n in names])
    v = s.analog(idx, np.full(idx.size, 0.5))
    return dict(zip(names, (float(x) for x in v)))


def budget(params: SensorParams | None = None, variant: str = ch.DEFAULT_VARIANT) -> list[BudgetLine]:
    """Every channel's noise at rest, source by source (the PAC section first, as D Table 5-1), for a sensor of
    ``params`` (default: the nominal unit) and ``variant`` (its electrodes: E1..E19, or E1..E24 for an SP)."""
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
    intrinsic_density = math.sqrt(p.johnson_noise_V_per_rtHz**2 + p.amp_voltage_noise_V_per_rtHz**2 + current**2)
    intrinsic = math.sqrt(sum(x.rti_uV**2 for x in lines[:3]))
    intrinsic_bits = math.sqrt(sum(x.pac_bits**2 for x in lines[:3]))
    lines.append(BudgetLine("intrinsic total (Table 5-1)", intrinsic, intrinsic_bits, "published 0.49 µV ≈ 0.6 bits"))
    from emulator.extrinsic import hum_components

    hum = hum_components(p)
    hum_names = ("mains hum", "mains hum, 2nd harmonic", "mains hum, 3rd harmonic")
    hum_notes = ("calibrated: its 2 Hz band = 0.2 bits² (D ch. 5)",
                 f"{p.mains_harmonic2_ratio:g} × the fundamental (2 × IEC 61000-2-2's 2 %)",
                 f"{p.mains_harmonic3_ratio:g} × the fundamental (3 × IEC 61000-2-2's 5 %)")
    hum_lines = [BudgetLine(f"{name} ({f:.0f} Hz)", a / math.sqrt(2) * 1e6, a / math.sqrt(2) * to_pac_bits, note)
                 for name, (_, f, a), note in zip(hum_names, hum, hum_notes)]
    lines += hum_lines
    rest = resting_volts(p, variant)
    codes = {n: v / ADC_LSB_V for n, v in rest.items()}
    ref = {n: p.adc_reference_noise_ppm * 1e-6 * abs(c) for n, c in codes.items()}
    adc_line = BudgetLine("ADC input noise (every channel)", None, p.adc_noise_rms_bits,
                          "dsPIC33FJ 12-bit SAR: ENOB 11.1 typ. less quantization")
    lines += [
        BudgetLine("ADC quantization", None, QUANTIZATION_BITS, "uniform, 1/√12 LSB"),
        adc_line,
        BudgetLine("ADC reference noise at the resting code", None, ref["PAC"],
                   f"{p.adc_reference_noise_ppm:g} ppm × code {codes['PAC']:.0f}"),
        BudgetLine("PAC path extra noise (stage 2 / ADC driver)", None, p.pac_path_noise_rms_bits,
                   "calibrated: the one knob that closes the total to D's 1.4 bits"),
        BudgetLine("SPI coupling", None, 0.0, "zero while the bus is silent during conversions"),
    ]
    hum_bits2 = sum(x.pac_bits**2 for x in hum_lines)
    total = math.sqrt(intrinsic_bits**2 + hum_bits2 + QUANTIZATION_BITS**2 + p.adc_noise_rms_bits**2
                      + ref["PAC"] ** 2 + p.pac_path_noise_rms_bits**2)
    lines.append(BudgetLine("total at the ADC output", None, total, "published 1.4 ± 0.1 bits RMS"))

    # --- every other channel -------------------------------------------------------------------------------
    pdc_band = math.sqrt(pdc_noise_bandwidth_Hz(p))
    to_pdc_bits = p.stage1_gain / ADC_LSB_V
    tdc_V, tac_V = thermistor_noise_V(p)
    for name in ["PDC", "TDC", "TAC"] + [n for n in rest if n.startswith("E")]:
        if name == "PDC":
            path = [("intrinsic noise × stage-1 gain", intrinsic_density * pdc_band * to_pdc_bits,
                     "the Table 5-1 sources before the 99.1 gain"),
                    ("mains hum × stage-1 gain", math.sqrt(sum((a / math.sqrt(2)) ** 2 for _, _, a in hum))
                     * to_pdc_bits, "fundamental and harmonics")]
        elif name in ("TDC", "TAC"):
            v = tdc_V if name == "TDC" else tac_V
            path = [("thermistor noise (thermal network running)", v / ADC_LSB_V,
                     f"tdc_noise_V = {p.tdc_noise_V * 1e6:g} µV per step" + (" × TAC gain" if name == "TAC" else "")
                     + "; none in the settled-at-rest shortcut")]
        else:
            path = [("electrode path", 0.0, "no noise source of its own in the model")]
        rows = [BudgetLine(f"{name}: {src}", None, bits, note, channel=name) for src, bits, note in path]
        rows += [BudgetLine(f"{name}: ADC input noise", None, p.adc_noise_rms_bits, "every channel", channel=name),
                 BudgetLine(f"{name}: ADC reference noise", None, ref[name],
                            f"{p.adc_reference_noise_ppm:g} ppm × code {codes[name]:.0f}", channel=name),
                 BudgetLine(f"{name}: ADC quantization", None, QUANTIZATION_BITS, "1/√12 LSB", channel=name)]
        rms = math.sqrt(sum(x.pac_bits**2 for x in rows))
        lines += rows
        lines.append(BudgetLine(f"{name}: total at the ADC output", None, rms,
                                "at rest; 0.3–0.7 LSB expected of a quiet channel", channel=name))
    return lines


def channel_totals(lines: list[BudgetLine]) -> dict[str, float]:
    """Total RMS at the ADC output (LSB) per channel."""
    return {("PAC" if x.channel == "PAC" else x.channel): x.pac_bits for x in lines
            if x.source.endswith("total at the ADC output")}


def format_budget(lines: list[BudgetLine], params: SensorParams | None = None) -> str:
    p = params or SensorParams()
    pa_per_bit = ADC_LSB_V / p.pac_V_per_Pa
    out = [f"PAC noise budget (PAC path noise bandwidth {pac_noise_bandwidth_Hz(p):.0f} Hz; "
           f"1 bit = {pa_per_bit:.3f} Pa)",
           f"{'source':45s} {'µV RTI/1040 Hz':>15s} {'Pa':>8s} {'PAC bits':>9s}  note"]
    for x in (x for x in lines if x.channel == "PAC"):
        rti = f"{x.rti_uV:.3f}" if x.rti_uV is not None else "—"
        pa = f"{x.pac_bits * pa_per_bit:.3f}"
        out.append(f"{x.source:45s} {rti:>15s} {pa:>8s} {x.pac_bits:9.3f}  {x.note}")
    others = [x for x in lines if x.channel != "PAC"]
    if others:
        out += ["", "Every other channel at rest, LSB RMS at the ADC output (path: the channel's own noise before "
                    "the ADC; ref: reference noise at its resting code)",
                f"{'channel':8s} {'path':>7s} {'ADC in':>7s} {'ref':>7s} {'quant':>7s} {'total':>7s}  path note"]
        for name in dict.fromkeys(x.channel for x in others):
            rows = [x for x in others if x.channel == name]
            path = [x for x in rows[:-4]]
            path_bits = math.sqrt(sum(x.pac_bits**2 for x in path))
            adc_in, ref, quant, total = (x.pac_bits for x in rows[-4:])
            note = "; ".join(f"{x.source.split(': ', 1)[1]}: {x.note}" for x in path)
            out.append(f"{name:8s} {path_bits:7.3f} {adc_in:7.3f} {ref:7.3f} {quant:7.3f} {total:7.3f}  {note}")
    return "\n".join(out)
