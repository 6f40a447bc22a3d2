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


class MainsHum(Effect):
    """Mains hum at the first-stage input: fundamental + 2nd + 3rd harmonic, each with a seeded phase.

    The phase at a block's first sample is computed from the absolute grid index (cycles = k·f·n0/fs reduced
    modulo 1 before it becomes an angle), never accumulated, so it is exact however long the run and the output
    does not depend on the block size.  A block whose first-sample phases and length equal the previous block's
    (blocks a whole number of mains periods long: the sensor's 2 s blocks) is that block's hum again, copied.
    """

    name = "mains_hum"
    produces = ("stage1_input_V",)

    def __init__(self, params: SensorParams, seed: int):
        rng = effect_rng(seed, self.name)
        phases = rng.uniform(0, 2 * np.pi, 3)  # the first draw is the fundamental's phase
        self.components = [(f, a, float(ph)) for (_, f, a), ph in zip(hum_components(params), phases) if a > 0]
        self._table = None  # (n, fs, [(A·cos(w·k/fs), A·sin(w·k/fs)) per component]) for k < n, the longest block
        self._last = (None, None)  # (n, fs, cycles per component) of the last block, and its hum (V)

    def process(self, block: Block, inputs):
        # each component's phase at the block's first sample, in cycles: f·n0 is exact for whole-hertz f
        cycles = tuple(math.fmod(f * block.n0, block.fs) / block.fs for f, _, _ in self.components)
        key = (block.n, block.fs, cycles)
        if key == self._last[0]:
            return {"stage1_input_V": self._last[1].copy()}
        if self._table is None or self._table[1] != block.fs or self._table[0] < block.n:
            # the longest block so far: shorter blocks (a rig's exact-length reads) use its first samples
            k = np.arange(block.n)
            rows = []
            for f, a, _ in self.components:
                wk = 2 * np.pi * (math.fmod(f, block.fs) / block.fs) * k
                rows.append((a * np.cos(wk), a * np.sin(wk)))
            self._table = (block.n, block.fs, rows)
        out = np.zeros(block.n)
        for (_, _, phase), c, (cos_k, sin_k) in zip(self.components, cycles, self._table[2]):
            # sin(φ0 + w·k/fs) = sin φ0·cos(w·k/fs) + cos φ0·sin(w·k/fs); φ0 from the absolute index n0
            phi0 = 2 * np.pi * c + phase
            out += math.sin(phi0) * cos_k[:block.n] + math.cos(phi0) * sin_k[:block.n]
        self._last = (key, out)
        return {"stage1_input_V": out.copy()}
