"""The software model of the sensor's SPI peripheral, vectorized over batches of transfers.

A *transfer* is one chip-select window carrying a 2-byte word, with its start time (s) and SCK
rate (Hz).  The peripheral answers the sampling command and the result read:

* the ADC converts during ``adc_conversion_s`` after the command; if the host starts another transfer
  inside that window the conversion is disturbed by SPI coupling (counted in ``coupled_conversions``).
  A command that ends a batch is converted when the next batch shows what followed it, so results
  never depend on how traffic is split into batches;
* a sampling command for a channel the emulated sensor was not built to provide (see
  ``Sensor(channels_read=...)``) answers ``EX`` and is counted in ``unprovided_requests``;
* a transfer whose first byte is 0x00 (host clocking out with 0x0000 or 0x0001) is a *read*: it
  returns the word prepared by the latest command, or ``E.`` if it starts less than 50 µs after
  that command ended, or ``E_`` if no command came before it;
* any other first byte is a *command*: a byte with even parity prepares ``EE``; a sampling
  command for a channel the sensor has prepares the code sampled at the instant the command
  ended (chip select released); an unknown channel prepares ``EX``; other commands ``E?``;
* MISO carries 0x0000 during a command.

State (the prepared word and when its command ended) carries across batches.  Property reads,
writes and resend belong to the full protocol model built on this one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emulator.channels import SAMPLED_CHANNELS
from emulator.spi import protocol as proto

BITS_PER_TRANSFER = 16


def _command_tables():
    """Per first byte: the word it prepares if not a sample, whether it samples, and its channel."""
    byte = np.arange(256)
    parity_ok = proto.ODD_PARITY_OK[byte]
    is_sampling = parity_ok & (byte >= 0x80)
    channel = (byte >> 1) & 0x3F
    known = is_sampling & np.isin(channel, list(SAMPLED_CHANNELS))
    prepared = np.full(256, proto.ERROR_WORDS["unknown_command"], dtype=np.uint16)
    prepared[~parity_ok] = proto.ERROR_WORDS["parity"]
    prepared[is_sampling & ~known] = proto.ERROR_WORDS["channel_not_recognized"]
    return prepared, known, channel


_PREPARED_BY_FIRST_BYTE, _SAMPLES_CHANNEL, _CHANNEL_OF_BYTE = _command_tables()


@dataclass
class TransferBatch:
    """Transfers in time order: ``start_s`` (s), ``mosi`` (uint16 words), ``clock_hz`` (Hz, scalar or array)."""

    start_s: np.ndarray
    mosi: np.ndarray
    clock_hz: float | np.ndarray = proto.HOST_DEFAULT_CLOCK_HZ

    @property
    def end_s(self) -> np.ndarray:
        return self.start_s + BITS_PER_TRANSFER / np.asarray(self.clock_hz, float)


class SoftwarePeripheral:
    """The sensor's SPI side, in software. ``sensor`` supplies ADC codes via ``sample(channels, times, bus_active)``."""

    def __init__(self, sensor):
        self.sensor = sensor
        # The emulated sensor computes only the channels it was built for; a sampling command for any
        # other channel answers EX (and is counted) rather than stopping the exchange.
        provided = np.zeros(256, dtype=bool)
        provided[:] = np.isin(_CHANNEL_OF_BYTE, list(sensor.channels_read))
        self._samples = _SAMPLES_CHANNEL & provided
        self._prepared_by_byte = _PREPARED_BY_FIRST_BYTE.copy()
        self._prepared_by_byte[_SAMPLES_CHANNEL & ~provided] = proto.ERROR_WORDS["channel_not_recognized"]
        self._not_provided = _SAMPLES_CHANNEL & ~provided
        self.unprovided_requests = 0
        self.conversion_s = sensor.params.adc_conversion_s
        self.coupled_conversions = 0
        self._deferred: tuple[int, float] | None = None  # (channel, command end) awaiting the next transfer
        self._prepared = proto.ERROR_WORDS["nothing_to_resend"]
        self._prepared_at = -np.inf
        self._has_prepared = False
        self._last_end = -np.inf

    def exchange(self, batch: TransferBatch) -> np.ndarray:
        """MISO word for every transfer of ``batch``."""
        start = np.asarray(batch.start_s, float)
        mosi = np.asarray(batch.mosi, dtype=np.uint16)
        clock = np.asarray(batch.clock_hz, float)
        if start.shape != mosi.shape:
            raise ValueError("start_s and mosi must have the same length")
        if start.size == 0:
            return np.zeros(0, np.uint16)
        lo, hi = proto.SPI_CLOCK_RANGE_HZ
        if clock.min() < lo or clock.max() > hi:
            c = np.broadcast_to(clock, start.shape)
            bad = int(np.flatnonzero((c < lo) | (c > hi))[0])
            raise ValueError(f"transfer #{bad}: SCK {c[bad]:.0f} Hz outside {lo:.0f}–{hi:.0f} Hz")
        end = start + BITS_PER_TRANSFER / clock
        eps = proto.TIME_TOLERANCE_S
        if start[0] < self._last_end - eps or (start.size > 1 and (start[1:] - end[:-1]).min() < -eps):
            raise ValueError("transfers must be in time order and must not overlap")
        b0 = mosi >> 8
        cmd = np.flatnonzero(b0 != 0)
        reads = np.flatnonzero(b0 == 0)
        self._convert_deferred(next_start=float(start[0]))

        # the word each command prepares: an error word from the table, or a sampled code
        first = b0[cmd]
        prepared = self._prepared_by_byte[first]
        sampling = self._samples[first]
        self.unprovided_requests += int(np.count_nonzero(self._not_provided[first]))
        cmd_end = end[cmd]
        defer_last = cmd.size > 0 and cmd[-1] == start.size - 1 and bool(sampling[-1])
        now = sampling.copy()
        if defer_last:
            now[-1] = False
        if now.any():
            next_start = np.append(start, np.inf)[cmd[now] + 1]
            coupled = next_start < cmd_end[now] + self.conversion_s
            self.coupled_conversions += int(np.count_nonzero(coupled))
            codes = self.sensor.sample(_CHANNEL_OF_BYTE[first[now]], cmd_end[now], bus_active=coupled)
            prepared[now] = proto.RESPONSE_WORD[codes]

        # each read answers the latest command before it (possibly one from an earlier batch)
        miso = np.zeros(start.shape, dtype=np.uint16)
        if reads.size:
            src = np.searchsorted(cmd, reads) - 1
            from_batch = src >= 0
            srci = np.maximum(src, 0)
            if cmd.size:
                word = np.where(from_batch, prepared[srci], self._prepared).astype(np.uint16)
                ready_at = np.where(from_batch, cmd_end[srci], self._prepared_at)
            else:
                word = np.full(reads.shape, self._prepared, dtype=np.uint16)
                ready_at = np.full(reads.shape, self._prepared_at)
            has = from_batch | self._has_prepared
            word[~has] = proto.ERROR_WORDS["nothing_to_resend"]
            too_soon = has & (start[reads] - ready_at < proto.SAMPLE_DELAY_S - proto.TIME_TOLERANCE_S)
            word[too_soon] = proto.ERROR_WORDS["insufficient_delay"]
            miso[reads] = word

        if cmd.size:
            self._prepared, self._prepared_at, self._has_prepared = int(prepared[-1]), float(cmd_end[-1]), True
        if defer_last:
            self._deferred = (int(_CHANNEL_OF_BYTE[first[-1]]), float(cmd_end[-1]))
        self._last_end = float(end[-1])
        return miso

    def _convert_deferred(self, next_start: float) -> None:
        """Convert the sample of a batch's final command, now that the next transfer's start is known."""
        if self._deferred is None:
            return
        channel, t_end = self._deferred
        self._deferred = None
        coupled = np.array([next_start < t_end + self.conversion_s])
        self.coupled_conversions += int(coupled[0])
        code = self.sensor.sample(np.array([channel]), np.array([t_end]), bus_active=coupled)
        self._prepared = int(proto.RESPONSE_WORD[code[0]])
