"""Extrinsic noise (SENSOR.md §3): mains hum and coupling from SPI traffic.

Mains hum couples capacitively into the un-amplified leads at the first-stage input.  SPI clocking
(up to 10 MHz) disturbs a conversion only if it overlaps it; the firmware samples while the bus is
silent, so a well-behaved host never sees it.  Coupling is applied per conversion by the ADC
(:mod:`emulator.adc`), the hum here on the grid.
"""

from __future__ import annotations

import numpy as np

from emulator.effects import Block, Effect, effect_rng
from emulator.params import SensorParams


class MainsHum(Effect):
    """Mains hum at the first-stage input: a sinusoid at the mains frequency with a seeded phase."""

    name = "mains_hum"
    produces = ("stage1_input_V",)

    def __init__(self, params: SensorParams, seed: int):
        self.amplitude = params.mains_amplitude_V
        self.w = 2 * np.pi * params.mains_frequency_Hz
        self.phase = effect_rng(seed, self.name).uniform(0, 2 * np.pi)
        self._table = None  # (n, fs, A·cos(w·k/fs), A·sin(w·k/fs)) for k in a block

    def process(self, block: Block, inputs):
        # sin(φ0 + w·k/fs) = sin φ0·cos(w·k/fs) + cos φ0·sin(w·k/fs); φ0 exact at each block start
        if self._table is None or self._table[:2] != (block.n, block.fs):
            wk = self.w * np.arange(block.n) / block.fs
            self._table = (block.n, block.fs, self.amplitude * np.cos(wk), self.amplitude * np.sin(wk))
        _, _, cos_k, sin_k = self._table
        phi0 = np.fmod(self.w * (block.n0 / block.fs), 2 * np.pi) + self.phase
        return {"stage1_input_V": np.sin(phi0) * cos_k + np.cos(phi0) * sin_k}
