"""The analog front end (SENSOR.md §3, D Fig. 5-2B).

Stage 1: gain 10, 2nd-order Butterworth anti-aliasing low-pass at 1040 Hz, positive bias -> PDC.
Stage 2: 1st-order high-pass at 10 Hz on the PDC node, gain 99.1, biased to 1.65 V -> PAC.
Together PAC sees the 10–1040 Hz band.  Outputs swing between the supply rails (0–3.3 V).
The first-stage amplifier's input voltage and current noise are referred to its input; the
second stage's own noise (negligible after the gain of 10) runs only in the reference profile.
"""

from __future__ import annotations

import numpy as np

from emulator import filters
from emulator.effects import Block, Effect
from emulator.params import SensorParams
from emulator.transducer import WhiteNoise


class Stage1(Effect):
    """Stage 1: gain 10 and 1040 Hz anti-alias low-pass with positive bias -> PDC (V)."""

    name = "stage1"
    consumes = ("stage1_input_V",)
    produces = ("pdc_V",)

    def __init__(self, params: SensorParams, fs: float, discretization: str):
        self.gain, self.bias, self.rail = params.stage1_gain, params.stage1_bias_V, params.supply_rail_V
        z, p, k = filters.lowpass_butter2(params.stage1_lowpass_Hz)
        self.filter = filters.SosFilter(filters.discretize(z, p, k * self.gain, fs, discretization))  # gain folded in

    def settle(self, inputs):
        v = inputs["stage1_input_V"]
        self.filter.settle(v)
        return {"pdc_V": float(np.clip(self.bias + self.gain * v, 0.0, self.rail))}

    def process(self, block: Block, inputs):
        return {"pdc_V": _bias_and_limit(self.filter(inputs["stage1_input_V"]), self.bias, self.rail)}


class Stage2(Effect):
    """Stage 2: 10 Hz high-pass and gain 99.1 on the PDC node, biased to 1.65 V -> PAC (V)."""

    name = "stage2"
    produces = ("pac_V",)

    def __init__(self, params: SensorParams, fs: float, discretization: str, own_noise: bool = False):
        self.consumes = ("pdc_V", "stage2_noise_V") if own_noise else ("pdc_V",)
        self.gain, self.bias, self.rail = params.stage2_gain, params.stage2_bias_V, params.supply_rail_V
        z, p, k = filters.highpass_1st(params.stage2_highpass_Hz)
        self.filter = filters.SosFilter(filters.discretize(z, p, k * self.gain, fs, discretization, gain_at_hz=1000.0))

    def settle(self, inputs):
        self.filter.settle(inputs["pdc_V"])
        return {"pac_V": self.bias}

    def process(self, block: Block, inputs):
        x = inputs["pdc_V"]
        if "stage2_noise_V" in inputs:
            x = x + inputs["stage2_noise_V"]
        return {"pac_V": _bias_and_limit(self.filter(x), self.bias, self.rail)}


def _bias_and_limit(y: np.ndarray, bias: float, rail: float) -> np.ndarray:
    """bias + y limited to the output swing 0..rail, in place on ``y``."""
    y += bias
    return np.clip(y, 0.0, rail, out=y)


def amplifier_noise(params: SensorParams, fs: float, seed: int) -> WhiteNoise:
    """First-stage input noise: voltage noise and current noise through the 5 kΩ bridge, combined."""
    density = float(np.hypot(params.amp_voltage_noise_V_per_rtHz,
                             params.amp_current_noise_A_per_rtHz * params.bridge_resistance_ohm))
    return WhiteNoise("amplifier_noise", "stage1_input_V", density, fs, seed,
                      "first-stage amplifier input voltage and current noise")


def stage2_noise(params: SensorParams, fs: float, seed: int) -> WhiteNoise:
    return WhiteNoise("stage2_noise", "stage2_noise_V", params.stage2_voltage_noise_V_per_rtHz, fs, seed,
                      "second-stage amplifier input noise (reference profile)")
