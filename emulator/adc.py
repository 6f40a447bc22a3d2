"""The 12-bit ADC (0–3.3 V): the one place where volts become codes.

Each conversion takes the analog value at the commanded instant and adds the noise that arises per conversion:

* the ADC's own input (transition) noise, the same for every channel (``adc_noise_rms_bits``);
* the reference's noise, proportional to the code (``adc_reference_noise_ppm``: code k moves by k·ppm·1e-6 LSB);
* the PAC path's own extra noise, on PAC conversions only (``pac_path_noise_rms_bits``: the second gain stage
  and the ADC driver of the AC node; the grid noise before it — bridge, amplifier, hum — is in the analog value).

The three are independent Gaussians, so one standard-normal draw per conversion scaled by the conversion's
own σ = √(σ_adc² + (ppm·v)² + σ_PAC²) carries them all: switching one source off leaves every other conversion's code
unchanged.  Then SPI coupling if the bus was clocking during the conversion, rounding to the nearest code and
clipping to 0..4095.  A non-finite input is a modelling error and is reported, never coded.
"""

from __future__ import annotations

import numpy as np

from emulator.channels import PAC
from emulator.conversions import ADC_CODES, ADC_LSB_V
from emulator.effects import effect_rng
from emulator.params import SensorParams


class NumericalError(FloatingPointError):
    """A NaN or Inf reached the ADC input."""


class Adc:
    """12-bit ADC with per-channel conversion noise, SPI-coupling disturbance, quantization and clipping.

    ``noise`` switches all the per-conversion noise (input, reference, PAC path) together.
    """

    def __init__(self, params: SensorParams, seed: int, noise: bool = True, spi_coupling: bool = True):
        self.noise_V = params.adc_noise_rms_bits * ADC_LSB_V if noise else 0.0
        self.reference_rel = params.adc_reference_noise_ppm * 1e-6 if noise else 0.0  # relative RMS of V_ref
        self.pac_V = params.pac_path_noise_rms_bits * ADC_LSB_V if noise else 0.0
        self.coupling_V = params.spi_coupling_rms_V if spi_coupling else 0.0
        self.noise_rng = effect_rng(seed, "adc_noise")
        self.coupling_rng = effect_rng(seed, "spi_coupling")

    def sigma_V(self, volts: np.ndarray, channels: np.ndarray | None = None) -> np.ndarray:
        """RMS per-conversion noise (V) for analog values ``volts`` (V) on SPI channel indices ``channels``
        (None: no channel-specific path noise): √(σ_adc² + (ppm·v)² + σ_PAC²·[channel is PAC]), a new array shaped as ``volts``."""
        v = np.asarray(volts, float)
        var = np.multiply(self.reference_rel, v, out=np.empty(v.shape))
        var = np.add(self.noise_V**2, np.square(var, out=var), out=var)
        if self.pac_V and channels is not None:
            var = np.add(var, self.pac_V**2 * (np.asarray(channels) == PAC), out=var)
        return np.sqrt(var, out=var)

    def convert(self, volts: np.ndarray, bus_active: np.ndarray | None = None, where: str = "ADC input",
                channels: np.ndarray | None = None):
        """Codes (uint16) for analog values in V; ``bus_active`` marks conversions that overlapped SPI clocking;
        ``channels`` (SPI channel index per conversion, same shape as ``volts``) lets the PAC path carry its own
        noise (without it no conversion is taken as PAC)."""
        v = np.asarray(volts, float)
        if not np.isfinite(v.sum()):  # one reduction: any NaN or ±Inf makes the sum non-finite
            bad = int(np.flatnonzero(~np.isfinite(v))[0])
            raise NumericalError(f"non-finite value {v[bad]} at {where} (conversion #{bad})")
        if channels is not None and np.shape(channels) != v.shape:
            raise ValueError(f"channels has shape {np.shape(channels)}; it must match the {v.shape} conversions")
        if self.noise_V or self.reference_rel or self.pac_V:
            z = self.noise_rng.standard_normal(v.shape, dtype=np.float32)
            if self.reference_rel or (self.pac_V and channels is not None):
                noise = self.sigma_V(v, channels)  # a new array: v + σ·z worked in place on it
                noise *= z
                v = np.add(v, noise, out=noise)
            else:
                v = v + self.noise_V * z
        if self.coupling_V and bus_active is not None and np.any(bus_active):
            v = v.copy()
            v[bus_active] += self.coupling_V * self.coupling_rng.standard_normal(int(np.count_nonzero(bus_active)))
        return quantize(v)


def quantize(volts: np.ndarray) -> np.ndarray:
    """Codes (uint16) of analog values (V): rounded to the nearest code, clipped to 0..4095 (``volts`` is kept)."""
    c = np.divide(volts, ADC_LSB_V, out=np.empty(np.shape(volts)))
    c += 0.5
    np.floor(c, out=c)
    return np.clip(c, 0, ADC_CODES - 1, out=c).astype(np.uint16)[()]  # [()]: a scalar for a scalar
