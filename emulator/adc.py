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

import math

import numpy as np
from numba import njit

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
        return self._sigma_times(volts, channels, _NO_DRAWS)

    def _sigma_times(self, volts, channels, z) -> np.ndarray:
        """:meth:`sigma_V` of ``volts`` (V) on ``channels``, or with draws ``z`` (one per value) the noisy values
        volts + σ·z (V): a new array shaped as ``volts``, one compiled pass."""
        v = np.asarray(volts, float)
        pac = self.pac_V and channels is not None
        out = np.empty(v.shape)
        # one channel per value: a scalar or a broadcastable shape is spread over ``volts`` (an incompatible one raises)
        per_value = np.broadcast_to(np.asarray(channels, np.int64), v.shape).reshape(-1) if pac else _NO_CHANNELS
        _sigma_times(v.reshape(-1), per_value, self.noise_V**2, self.reference_rel, self.pac_V**2, z.reshape(-1),
                     out.reshape(-1))
        return out

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
                v = self._sigma_times(v, channels, z)
            else:
                v = v + self.noise_V * z
        if self.coupling_V and bus_active is not None and np.any(bus_active):
            v = v.copy()
            v[bus_active] += self.coupling_V * self.coupling_rng.standard_normal(int(np.count_nonzero(bus_active)))
        return quantize(v)


_NO_DRAWS = np.zeros(0, dtype=np.float32)
_NO_CHANNELS = np.zeros(0, dtype=np.int64)


@njit(cache=True)
def _sigma_times(v, channels, noise_var, reference_rel, pac_var, z, out):
    """Per value of ``v`` (V): σ = √(σ_adc² + (ppm·v)² + σ_PAC²·[channel is PAC]) (V) — ``noise_var`` = σ_adc²,
    ``reference_rel`` = ppm·1e-6, ``pac_var`` = σ_PAC², the PAC term only with ``channels`` (empty: none) — into
    ``out``, or with draws ``z`` (not empty) v + σ·z."""
    for p in range(v.size):
        r = reference_rel * v[p]
        var = noise_var + r * r
        if channels.size and channels[p] == PAC:
            var = var + pac_var
        sigma = math.sqrt(var)
        out[p] = v[p] + sigma * z[p] if z.size else sigma


def quantize(volts: np.ndarray) -> np.ndarray:
    """Codes (uint16) of analog values (V): rounded to the nearest code, clipped to 0..4095 (``volts`` is kept)."""
    c = np.divide(volts, ADC_LSB_V, out=np.empty(np.shape(volts)))
    c += 0.5
    np.floor(c, out=c)
    return np.clip(c, 0, ADC_CODES - 1, out=c).astype(np.uint16)[()]  # [()]: a scalar for a scalar
