"""Batches of 16-bit transfers for a sensor alone on its bus (what the host sampler sends).

The protocol itself lives in :mod:`emulator.spi.model`; this module only names the batch format.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emulator.spi import protocol as proto
from emulator.spi.model import SensorPort

BITS_PER_TRANSFER = 16
#: A transfer of n bits holds chip select for (n + 1/2) SCK periods (see emulator.spi.model).
TRANSFER_PERIODS = BITS_PER_TRANSFER + 0.5


@dataclass
class TransferBatch:
    """Transfers in time order: ``start_s`` (s), ``mosi`` (uint16 words), ``clock_hz`` (Hz, scalar or array)."""

    start_s: np.ndarray
    mosi: np.ndarray
    clock_hz: float | np.ndarray = proto.HOST_DEFAULT_CLOCK_HZ

    @property
    def end_s(self) -> np.ndarray:
        return self.start_s + TRANSFER_PERIODS / np.asarray(self.clock_hz, float)


def SoftwarePeripheral(sensor, index: int = 1) -> SensorPort:
    """The software model of one sensor's SPI side (a :class:`SensorPort`)."""
    return SensorPort(sensor, index)
