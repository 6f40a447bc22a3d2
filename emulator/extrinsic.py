"""Extrinsic noise (SENSOR.md §3): mains hum and coupling from SPI traffic.

Mains hum couples capacitively into the un-amplified leads at the first-stage input: the fundamental at the mains
frequency (50 or 60 Hz, ``mains_frequency_Hz``) with amplitude ``mains_amplitude_V``, plus its 2nd and 3rd
harmonics (100/150 Hz or 120/180 Hz) at ``mains_harmonic2_ratio`` and ``mains_harmonic3_ratio`` of it.  Each
component has its own seeded phase.  SPI clocking (up to 10 MHz) disturbs a conversion only if it overlaps it; the
firmware samples while the bus is silent, so a well-behaved host never sees it.  Coupling is applied per
conversion by the ADC (:mod:`emulator.adc`), the hum here on the grid.
"""

from __future__ import annotations

import math

import numpy as np

from emulator.effects import Block, Effect, effect_rng
from emulator.params import SensorParams


def hum_components(params: SensorParams) -> list[tuple[int, float, float]]:
    """(harmonic number, frequency in Hz, amplitude in V at the stage-1 input) of each mains component."""
    f, a = params.mains_frequency_Hz, params.mains_amplitude_V
    return [(1, f, a), (2, 2 * f, a * params.mains_harmonic2_ratio), (3, 3 * f, a * params.mains_harmonic3_ratio)]


#: the longest hum period (samples) tabulated; a longer one (or a non-whole-hertz hum) is computed per sample
MAX_TABLE_SAMPLES = 1 << 20


class MainsHum(Effect):
    """Mains hum at the first-stage input: fundamental + 2nd + 3rd harmonic, each with a seeded phase.

    Each sample is a function of its absolute grid index n alone, Σ a·sin(2π·((f·n) mod fs)/fs + φ) (the cycles
    reduced modulo 1 before they become an angle, never accumulated), so it is exact however long the run and the
    same whatever the block size.  With whole-hertz components on a whole-hertz grid the hum repeats every
    P = lcm over the components of fs/gcd(f, fs) samples (440 at 60 Hz on the 8.8 kHz grid): one period is
    tabulated from the formula and a block is read from it (the same numbers: f·n mod fs = f·(n mod P) mod fs,
    exactly, while f·n < 2^53).
    """

    name = "mains_hum"
    produces = ("stage1_input_V",)

    def __init__(self, params: SensorParams, seed: int):
        rng = effect_rng(seed, self.name)
        phases = rng.uniform(0, 2 * np.pi, 3)  # the first draw is the fundamental's phase
        self.components = [(f, a, float(ph)) for (_, f, a), ph in zip(hum_components(params), phases) if a > 0]
        self._tables: dict[float, np.ndarray | None] = {}  # grid rate (Hz) -> one period of hum (V), or None

    def at(self, n: np.ndarray, fs: float) -> np.ndarray:
        """The hum (V) at absolute grid indices ``n`` (whole numbers, as floats) of a grid at ``fs`` Hz."""
        out = np.zeros(np.shape(n))
        for f, a, phase in self.components:
            out += a * np.sin(2 * np.pi * ((f * n) % fs) / fs + phase)
        return out

    def period(self, fs: float) -> int | None:
        """Samples after which the hum on a grid at ``fs`` Hz repeats exactly, or None (not whole hertz)."""
        if not float(fs).is_integer() or not all(float(f).is_integer() for f, _, _ in self.components):
            return None
        p = 1
        for f, _, _ in self.components:
            p = math.lcm(p, int(fs) // math.gcd(int(f), int(fs)))
        return p

    def process(self, block: Block, inputs):
        if block.fs not in self._tables:
            p = self.period(block.fs)
            self._tables[block.fs] = (self.at(np.arange(p, dtype=float), block.fs)
                                      if p is not None and p <= MAX_TABLE_SAMPLES else None)
        table = self._tables[block.fs]
        if table is None:
            return {"stage1_input_V": self.at(block.n0 + np.arange(block.n, dtype=float), block.fs)}
        start = block.n0 % table.size  # the block's first sample in the period, then the period over and over
        return {"stage1_input_V": np.resize(np.concatenate([table[start:], table[:start]]), block.n)}


#: the PAC band (Hz) a mount vibration's ``rms_Pa`` is given in: stage 2's high-pass to stage 1's low-pass (nominal)
PAC_BAND_HZ = (10.0, 1040.0)


class MountNoise(Effect):
    """Fluid pressure (Pa) of :class:`~emulator.stimuli.MountVibration` stimuli: white Gaussian noise whose density
    gives each one's ``rms_Pa`` over :data:`PAC_BAND_HZ`, switched on at its ``start_s``; several are independent
    sources, so their powers add.  One standard normal is drawn per grid sample, switched on or not, so a sample is
    the same whatever the block size."""

    name = "mount_vibration"
    produces = ("fluid_pressure_Pa",)

    def __init__(self, stimuli: list, fs: float, seed: int):
        self.stimuli = list(stimuli)
        per_sample = np.sqrt(fs / 2.0 / (PAC_BAND_HZ[1] - PAC_BAND_HZ[0]))  # σ per sample / RMS in the band
        self.levels = [(s.start_s, s.rms_Pa * per_sample) for s in self.stimuli]
        self.rng = effect_rng(seed, self.name)

    def describe(self) -> str:
        return "random vibration through the finger's mount (a rig's stepper holding), white in fluid pressure"

    def process(self, block: Block, inputs):
        t = block.times
        z = self.rng.standard_normal(block.n)
        variance = np.zeros(block.n)
        for start_s, level in self.levels:
            variance[t >= start_s] += level ** 2
        return {"fluid_pressure_Pa": np.sqrt(variance) * z}
