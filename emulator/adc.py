"""The 12-bit ADC (0–3.3 V): the one place where volts become codes.

Each conversion takes the analog value at the commanded instant, adds the ADC's own input noise,
adds SPI coupling if the bus was clocking during the conversion, then quantizes to the nearest
code and clips to 0..4095.  A non-finite input is a modelling error and is reported, never coded.
"""

from __future__ import annotations

import numpy as np

from emulator.conversions import ADC_CODES, ADC_LSB_V
from emulator.effects import effect_rng
from emulator.params import SensorParams


class NumericalError(FloatingPointError):
    """A NaN or Inf reached the ADC input."""


class Adc:
    """12-bit ADC with input noise, SPI-coupling disturbance, quantization and clipping."""

    def __init__(self, params: SensorParams, seed: int, noise: bool = True, spi_coupling: bool = True):
        self.noise_V = params.adc_noise_rms_bits * ADC_LSB_V if noise else 0.0
        self.coupling_V = params.spi_coupling_rms_V if spi_coupling else 0.0
        self.noise_rng = effect_rng(seed, "adc_noise")
        self.coupling_rng = effect_rng(seed, "spi_coupling")

    def convert(self, volts: np.ndarray, bus_active: np.ndarray | None = None, where: str = "ADC input",
                channels: np.ndarray | None = None):
        """Codes (uint16) for analog values in V; ``bus_active`` marks conversions that overlapped SPI clocking;
        ``channels`` (SPI channel index per conversion) lets each channel's path carry its own noise."""
        v = np.asarray(volts, float)
        if not np.isfinite(v.sum()):  # one reduction: any NaN or ±Inf makes the sum non-finite
            bad = int(np.flatnonzero(~np.isfinite(v))[0])
            raise NumericalError(f"non-finite value {v[bad]} at {where} (conversion #{bad})")
        if self.noise_V:
            v = v + self.noise_V * self.noise_rng.standard_normal(v.shape, dtype=np.float32)
        if self.coupling_V and bus_active is not None and np.any(bus_active):
            v = v.copy()
            v[bus_active] += self.coupling_V * self.coupling_rng.standard_normal(int(np.count_nonzero(bus_active)))
        return np.clip(np.floor(v / ADC_LSB_V + 0.5), 0, ADC_CODES - 1).astype(np.uint16)
