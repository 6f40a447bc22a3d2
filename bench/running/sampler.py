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
from numba import njit

from emulator import channels as ch
from emulator.spi import protocol as proto
from emulator.spi.peripheral import TRANSFER_PERIODS, TransferBatch

STATUS_OK, STATUS_PARITY, STATUS_ERROR_WORD = 0, 1, 2
STATUS_NAMES = {STATUS_OK: "ok", STATUS_PARITY: "parity error", STATUS_ERROR_WORD: "error word"}

#: :func:`~emulator.spi.protocol.decode_response` of every 16-bit word (value, status before error words are told
#: apart): a read decodes by two look-ups
def _decode_tables() -> tuple[np.ndarray, np.ndarray]:
    """The code and the status of every 16-bit response word (a bad word's status: parity error, or error word)."""
    words = np.arange(1 << 16, dtype=np.uint16)
    value, parity_ok = proto.decode_response(words)
    status = np.where(parity_ok, STATUS_OK, STATUS_PARITY).astype(np.uint8)
    status[proto.is_error_word(words)] = STATUS_ERROR_WORD
    return value.astype(np.uint16), status


#: :func:`~emulator.spi.protocol.decode_response` of every 16-bit word, and its status: a read decodes by two look-ups
_VALUE_OF_WORD, _STATUS_OF_WORD = _decode_tables()


@njit(cache=True)
def _slot_transfers(k0, n, slot_rate_Hz, word_s, sample_delay_s, sequence, command_words, start, mosi, t_sampled,
                    channels):
    """Slots ``k0`` .. ``k0 + n - 1`` as transfers: each slot's sampling command at k/``slot_rate_Hz`` (s) and its
    read ``word_s`` + ``sample_delay_s`` later (``start``, ``mosi``: 2 per slot), the instant sampled (the command's
    chip-select release, ``t_sampled``) and the channel (``channels``) — :meth:`Sampler.slots`, one pass."""
    m = sequence.size
    for i in range(n):
        k = k0 + i
        t_cmd = k / slot_rate_Hz
        t = t_cmd + word_s
        start[2 * i], start[2 * i + 1] = t_cmd, t + sample_delay_s
        mosi[2 * i], mosi[2 * i + 1] = command_words[k % m], 0
        t_sampled[i], channels[i] = t, sequence[k % m]


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


@njit(cache=True)
def _decode(miso, value_of_word, status_of_word, codes, status):
    """The code and status of each slot's read (the second of its two transfers' MISO words), by look-up."""
    for i in range(codes.size):
        w = miso[2 * i + 1]
        codes[i], status[i] = value_of_word[w], status_of_word[w]


def _checked_reply(peripheral, miso, n_words: int) -> np.ndarray:
    """The peripheral's MISO words as uint16, after checking there is one 16-bit word per transfer (a malformed
    reply is refused naming the peripheral, never decoded past its end or folded into a status)."""
    words = np.asarray(miso)
    name = type(peripheral).__name__
    if words.shape != (n_words,):
        raise ValueError(f"{name}.exchange returned {words.shape} words for {n_words} transfers: one 16-bit MISO "
                         f"word per transfer expected")
    if words.dtype == np.uint16:
        return words
    if words.dtype.kind not in "iu" or (words.size and (words.min() < 0 or words.max() > 0xFFFF)):
        raise ValueError(f"{name}.exchange returned {words.dtype} words outside 0..0xFFFF: 16-bit MISO words "
                         f"expected")
    return words.astype(np.uint16)


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
        start, mosi = np.empty(2 * n_slots), np.empty(2 * n_slots, dtype=np.uint16)
        t_sampled, channels = np.empty(n_slots), np.empty(n_slots, dtype=self.sequence.dtype)
        _slot_transfers(self.next_slot, n_slots, self.slot_rate_Hz, self.word_s, self.sample_delay_s, self.sequence,
                        self.command_words, start, mosi, t_sampled, channels)
        self.next_slot += n_slots
        miso = _checked_reply(self.peripheral, self.peripheral.exchange(TransferBatch(start, mosi, self.clock_hz)),
                              2 * n_slots)
        codes, status = np.empty(n_slots, dtype=np.uint16), np.empty(n_slots, dtype=np.uint8)
        _decode(miso, _VALUE_OF_WORD, _STATUS_OF_WORD, codes, status)
        return Samples(t_sampled, channels, codes, miso[1::2], status)

    def chunks(self, n_slots: int, chunk_slots: int):
        """Read the next ``n_slots`` slots in reads of at most ``chunk_slots``, yielding each :class:`Samples`."""
        if chunk_slots < 1:
            raise ValueError(f"chunk_slots = {chunk_slots}: must be at least 1")
        for done in range(0, n_slots, chunk_slots):
            yield self.read(min(chunk_slots, n_slots - done))
