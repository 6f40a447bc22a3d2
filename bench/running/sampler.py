"""Host-side sampler: reads channels through the SPI protocol the way the vendor host library does.

Each slot of the sequence is one sample: the sampling command (chip select, 2 bytes), chip select
released, a wait of at least 50 µs, then a read clocking out the response word while sending
zeros.  Slots are paced at ``slot_rate_Hz`` (4.4 kHz: the default 44-slot frame gives PAC at
2.2 kS/s and every other channel at 100 S/s).  Words are decoded and parity-checked here, as a
host would: a bad word is kept, flagged in ``status``, never silently turned into a value.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emulator import channels as ch
from emulator.spi import protocol as proto
from emulator.spi.peripheral import TRANSFER_PERIODS, TransferBatch

STATUS_OK, STATUS_PARITY, STATUS_ERROR_WORD = 0, 1, 2
STATUS_NAMES = {STATUS_OK: "ok", STATUS_PARITY: "parity error", STATUS_ERROR_WORD: "error word"}

#: :func:`~emulator.spi.protocol.decode_response` of every 16-bit word (value, status before error words are told
#: apart): a read decodes by two look-ups
_VALUE_OF_WORD, _PARITY_OK_OF_WORD = proto.decode_response(np.arange(1 << 16, dtype=np.uint16))
_VALUE_OF_WORD = _VALUE_OF_WORD.astype(np.uint16)
_STATUS_OF_WORD = np.where(_PARITY_OK_OF_WORD, STATUS_OK, STATUS_PARITY).astype(np.uint8)


@dataclass
class Samples:
    """Decoded samples of consecutive slots: instant sampled (s), channel index, code, word, status."""

    times: np.ndarray
    channels: np.ndarray
    codes: np.ndarray
    words: np.ndarray
    status: np.ndarray


def variant_of(peripheral) -> str:
    """The variant of the sensor behind ``peripheral`` (a :class:`~emulator.spi.model.SensorPort` has ``variant``,
    the RTL harness peripheral a ``sensor``); the default variant when it cannot tell (None, a recorder)."""
    for obj in (peripheral, getattr(peripheral, "sensor", None)):
        v = getattr(obj, "variant", None)
        if v is not None:
            return ch.variant(v).name
    return ch.DEFAULT_VARIANT


class Sampler:
    """Reads a repeating channel sequence through any peripheral with an ``exchange(TransferBatch)`` method."""

    def __init__(self, peripheral, sequence="default", slot_rate_Hz: float = ch.DEFAULT_SLOT_RATE_HZ,
                 clock_hz: float = proto.HOST_DEFAULT_CLOCK_HZ, sample_delay_s: float = proto.SAMPLE_DELAY_S,
                 variant: str | None = None):
        """``sequence = "default"`` is the variant's frame (54 slots on a BioTac SP): ``variant`` names it, or else
        the peripheral's sensor's variant is used (the default variant without a peripheral)."""
        self.peripheral = peripheral
        self.variant = ch.variant(variant if variant is not None else variant_of(peripheral))
        self.sequence = ch.parse_sequence(sequence, self.variant.name)
        self.slot_rate_Hz = float(slot_rate_Hz)
        self.clock_hz = float(clock_hz)
        self.sample_delay_s = float(sample_delay_s)
        self.word_s = TRANSFER_PERIODS / self.clock_hz  # chip select held for 16.5 SCK periods
        if 2 * self.word_s + self.sample_delay_s > 1.0 / self.slot_rate_Hz:
            raise ValueError(
                f"a slot of {1e6 / self.slot_rate_Hz:.1f} µs cannot hold command + {self.sample_delay_s * 1e6:.0f} µs "
                f"+ read at {self.clock_hz / 1e6:.2f} MHz; lower slot_rate_Hz or raise the clock")
        self.command_words = (proto.sample_command(self.sequence).astype(np.uint16) << 8)
        self.next_slot = 0

    def slots(self, k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For slot numbers ``k``: when the sampling command starts (s), when the channel is sampled (the
        command's chip-select release, s), and the channel index."""
        t_cmd = k / self.slot_rate_Hz
        return t_cmd, t_cmd + self.word_s, self.sequence[k % len(self.sequence)]

    def read(self, n_slots: int) -> Samples:
        """Sample the next ``n_slots`` slots."""
        k = self.next_slot + np.arange(n_slots)
        self.next_slot += n_slots
        t_cmd, t_sampled, channels = self.slots(k)
        t_read = t_sampled + self.sample_delay_s
        start = np.empty(2 * n_slots)
        start[0::2], start[1::2] = t_cmd, t_read
        mosi = np.zeros(2 * n_slots, dtype=np.uint16)
        mosi[0::2] = self.command_words[k % len(self.sequence)]
        miso = self.peripheral.exchange(TransferBatch(start, mosi, self.clock_hz))
        words = miso[1::2]
        status = _STATUS_OF_WORD[words]
        status[proto.is_error_word(words)] = STATUS_ERROR_WORD
        return Samples(t_sampled, channels, _VALUE_OF_WORD[words], words, status)

    def chunks(self, n_slots: int, chunk_slots: int):
        """Read the next ``n_slots`` slots in reads of at most ``chunk_slots``, yielding each :class:`Samples`."""
        if chunk_slots < 1:
            raise ValueError(f"chunk_slots = {chunk_slots}: must be at least 1")
        for done in range(0, n_slots, chunk_slots):
            yield self.read(min(chunk_slots, n_slots - done))
