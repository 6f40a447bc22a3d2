"""The piezoresistive pressure transducer: a Wheatstone bridge with two fixed and two active arms.

Output (differential, V) = excitation · (offset(T) + sensitivity · (1 + span drift·ΔT) · pressure),
i.e. 2.18 mV/kPa at 10 V.  Its 5 kΩ output resistance makes Johnson noise √(4kTR) at the bridge
temperature.  In the reference profile the 2 cm fluid duct between skin and transducer adds its
closed-tube resonance (18.7 kHz, negligible below 1 kHz).  It matters only far below its peak, where PAC and PDC
look, so it is mapped by the plain bilinear transform, whatever the profile's discretization: that keeps its
response below a few kHz to within (f/fs)² of the analog one (8e-5 over 1 Hz–2 kHz at the nominal resonance on the
reference grid), and leaves its peak warped down, beyond the 1040 Hz anti-aliasing filter (to 15.6 kHz from 18.7;
one at or above Nyquist — the parameter's range reaches 100 kHz — lands below it).  Prewarping it instead would put
the peak where it belongs but give the band the response of a resonance moved up by as much (7e-3 off at nominal).
"""

from __future__ import annotations

import numpy as np

from emulator import filters
from emulator.effects import Block, Effect, effect_rng
from emulator.params import SensorParams


class Bridge(Effect):
    """Piezoresistive bridge: fluid pressure (Pa) -> differential voltage at the stage-1 input."""

    name = "bridge"
    consumes = ("fluid_pressure_Pa",)
    produces = ("stage1_input_V",)

    def __init__(self, params: SensorParams, fs: float, duct_resonance: bool, thermal: bool = False,
                 settled_temperature_C: float | None = None):
        t = params.bridge_temperature_C if settled_temperature_C is None else settled_temperature_C
        self.span = params.bridge_span_at(t)
        self.offset = params.bridge_offset_at(t)
        self.params = params
        #: with a thermal model the bridge follows the core temperature (offset and span drift)
        self.consumes = ("fluid_pressure_Pa", "bridge_temperature_C") if thermal else ("fluid_pressure_Pa",)
        self.duct = None
        if duct_resonance:
            w0 = 2 * np.pi * params.duct_resonance_Hz
            q = params.duct_quality_factor
            poles = np.roots([1.0, w0 / q, w0**2])
            # (plain bilinear: its in-band response, not its peak, is what the channels see; see the module's doc)
            self.duct = filters.SosFilter(filters.discretize([], poles, w0**2, fs, "bilinear"))

    def settle(self, inputs):
        p = inputs["fluid_pressure_Pa"]
        if self.duct is not None:
            self.duct.settle(p)
        if "bridge_temperature_C" in inputs:
            t = inputs["bridge_temperature_C"]
            return {"stage1_input_V": self.params.bridge_offset_at(t) + self.params.bridge_span_at(t) * p}
        return {"stage1_input_V": self.offset + self.span * p}

    def process(self, block: Block, inputs):
        p = inputs["fluid_pressure_Pa"]
        v = self.duct(p) if self.duct is not None else p.copy()
        if "bridge_temperature_C" in inputs:
            t = inputs["bridge_temperature_C"]
            v *= self.params.bridge_span_at(t)
            v += self.params.bridge_offset_at(t)
            return {"stage1_input_V": v}
        v *= self.span
        v += self.offset
        return {"stage1_input_V": v}


class CoreTemperature(Effect):
    """The heated core's temperature (°C) on the grid, from the thermal network (drives the bridge's drift)."""

    name = "core_temperature"
    produces = ("bridge_temperature_C",)

    def __init__(self, thermal):
        self.thermal = thermal

    def settle(self, inputs):
        return {"bridge_temperature_C": float(self.thermal.value_at(np.array([0.0]), 0)[0])}

    def process(self, block: Block, inputs):
        return {"bridge_temperature_C": self.thermal.value_at(block.times, 0)}


class WhiteNoise(Effect):
    """White Gaussian noise of a given one-sided density (V/√Hz) added to a signal on the grid."""

    def __init__(self, name: str, signal_name: str, density: float, fs: float, seed: int, doc: str):
        self.name = name
        self.produces = (signal_name,)
        self.density = density
        self.sigma = density * np.sqrt(fs / 2.0)  # per-sample RMS of white noise band-limited to fs/2
        self.rng = effect_rng(seed, name)
        self._doc = doc

    def describe(self) -> str:
        return self._doc

    def process(self, block: Block, inputs):
        # float32 draws are twice as fast; the noise itself needs no more than 24 bits of precision
        return {self.produces[0]: self.sigma * self.rng.standard_normal(block.n, dtype=np.float32)}


def johnson_noise(params: SensorParams, fs: float, seed: int) -> WhiteNoise:
    """Thermal noise √(4kTR) of the bridge's output resistance at the bridge temperature."""
    return WhiteNoise(
        "bridge_johnson_noise", "stage1_input_V", params.johnson_noise_V_per_rtHz, fs, seed,
        "Johnson noise of the 5 kΩ bridge at its temperature",
    )
