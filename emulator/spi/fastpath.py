"""Fast evaluation of plain sampling/read traffic for one sensor alone on its bus.

The host sampler streams millions of 16-bit transfers that are only sampling commands and reads;
this routine computes exactly what :class:`emulator.spi.model.SensorPort`'s transfer-level path
would, in two compiled passes (numba) around one call to the sensor, and leaves the port in the same state.  A differential test checks
the two against each other; anything else (properties, resend, writes, faults) takes the
transfer-level path.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from emulator import channels as ch
from emulator.spi import protocol as proto
from emulator.spi.model import (CMD_READ_PROPERTY, CMD_RESEND, CMD_RESEND_MANUAL, CMD_WRITE, CONVERSION_TICKS,
                                SAMPLE_DELAY_TICKS, TIMER_HZ, _Prepared, ticks_array)

_ERR = proto.ERROR_WORDS
_ERR_BUSY, _ERR_NOT_RECOGNIZED = _ERR["insufficient_sampling_delay"], _ERR["channel_not_recognized"]
_ERR_NOTHING, _ERR_DELAY = _ERR["nothing_to_resend"], _ERR["insufficient_delay"]
_NO_TICK = -10**12  # the last sampling tick when there was none
_SPECIAL = np.zeros(256, dtype=bool)
_SPECIAL[[CMD_READ_PROPERTY, CMD_RESEND, CMD_RESEND_MANUAL, CMD_WRITE]] = True


def _tables(sampled):
    """Per first byte: the error word a non-sampling byte prepares, whether it samples a channel of ``sampled``,
    and its channel index."""
    byte = np.arange(256)
    parity_ok = proto.ODD_PARITY_OK[byte]
    channel = (byte >> 1) & 0x3F
    recognized = parity_ok & (byte >= 0x80) & np.isin(channel, list(sampled))
    word = np.full(256, _ERR["unknown_command"], dtype=np.int64)
    word[~parity_ok] = _ERR["parity"]
    word[parity_ok & (byte >= 0x80) & ~recognized] = _ERR["channel_not_recognized"]
    return word, recognized, channel


#: The tables of each variant (the SP recognises E20..E24; the 19-electrode sensor answers them EX).
_TABLES = {name: _tables(ch.variant(name).sampled_channels) for name in ch.VARIANTS}
#: The default variant's tables under their former names.
_WORD_OF_BYTE, _RECOGNIZED, _CHANNEL_OF_BYTE = _TABLES[ch.DEFAULT_VARIANT]


def is_plain(port, mosi: np.ndarray) -> bool:
    """True if the batch and the port's state are within what this routine evaluates."""
    if port.faults.any or (port.prepared is not None and port.prepared.kind == "property"):
        return False
    return not _any_special(np.ascontiguousarray(mosi), _SPECIAL)


@njit(cache=True)
def _any_special(mosi, special) -> bool:
    """Whether any word's first byte is marked in ``special`` (per first byte)."""
    for w in mosi:
        if special[w >> 8]:
            return True
    return False


@njit(cache=True)
def _commands(mosi, start, end, next_activity, word_of_byte, recognized_of_byte, channel_of_byte, provided_lut,
              last_sampling_tick, conversion_s, first, cmd_end, prepared, acc_at, acc_channel, acc_time, acc_coupled):
    """The word each command of the transfers (``mosi``, chip select falling at ``start`` and released at ``end``
    s) prepares, in order (commands: transfers whose first byte is not 0; their first bytes to ``first``, release
    instants to ``cmd_end``, words to ``prepared``): an error word, or a conversion (its code comes from the
    sensor) that the bus disturbs if it clocks again within ``conversion_s`` — the bus's next activity after a
    transfer is ``next_activity`` (empty: the next transfer's start, unknown after the last).  The conversions
    accepted go, in order, to ``acc_at`` (command number), ``acc_channel``, ``acc_time`` (s), ``acc_coupled``.
    Returns (commands, sampling commands met, the last one's tick, requests for channels not provided,
    conversions, the command number of the last conversion if nothing is known after it — it is then left to
    convert later — else -1)."""
    sampling, unprovided, c, n_acc = 0, 0, 0, 0
    last_next = 0.0
    for t in range(mosi.size):
        b = mosi[t] >> 8
        if b == 0:
            continue
        first[c], cmd_end[c] = b, end[t]
        prepared[c] = word_of_byte[b]
        c += 1
        if not recognized_of_byte[b]:
            continue
        tick = math.floor(end[t] * TIMER_HZ + 1e-3)  # ticks(): the sensor's 1 MHz timer
        busy = tick - last_sampling_tick < CONVERSION_TICKS
        sampling += 1
        last_sampling_tick = tick
        if busy:
            prepared[c - 1] = _ERR_BUSY
        elif not provided_lut[channel_of_byte[b]]:
            prepared[c - 1] = _ERR_NOT_RECOGNIZED
            unprovided += 1
        else:
            if next_activity.size:
                last_next = next_activity[t]
            else:
                last_next = start[t + 1] if t + 1 < start.size else math.inf
            acc_at[n_acc], acc_channel[n_acc], acc_time[n_acc] = c - 1, channel_of_byte[b], end[t]
            acc_coupled[n_acc] = last_next < end[t] + conversion_s
            n_acc += 1
    deferred = -1
    if n_acc and not math.isfinite(last_next):
        n_acc -= 1
        deferred = acc_at[n_acc]
    return c, sampling, last_sampling_tick, unprovided, n_acc, deferred


@njit(cache=True)
def _transfers(mosi, start, cmd_end, prepared, acc_at, codes, response_word, before_ready, before_word,
               before_consumed, out):
    """MISO of each transfer (``out``) as the port walks through them: at chip-select fall the prepared word if
    it is ready and not consumed, ``E.`` if not ready, ``E_`` if consumed or none; a read that receives the word
    consumes it; a command (first byte not 0) prepares its word (``prepared``, in order; the conversions
    ``acc_at`` their ``codes``' response words).  ``before_ready`` < 0: nothing prepared before the batch.
    Returns (whether the last prepared word was consumed, the index of the last read that consumed one, or -1)."""
    for a in range(codes.size):
        prepared[acc_at[a]] = response_word[codes[a]]
    have = before_ready >= 0
    ready, word, consumed = before_ready, before_word, before_consumed
    c, last_consuming = 0, -1
    for i in range(start.size):
        is_cmd = (mosi[i] >> 8) != 0
        if not have or consumed:
            out[i] = _ERR_NOTHING
        elif math.floor(start[i] * TIMER_HZ + 1e-3) - ready < SAMPLE_DELAY_TICKS:
            out[i] = _ERR_DELAY
        else:
            out[i] = word
            if not is_cmd:
                consumed = True
                last_consuming = i
        if is_cmd:
            have, ready, word, consumed = True, math.floor(cmd_end[c] * TIMER_HZ + 1e-3), prepared[c], False
            c += 1
    return consumed, last_consuming


_NO_NEXT = np.zeros(0)


def exchange_words(port, start: np.ndarray, end: np.ndarray, mosi: np.ndarray,
                   next_activity: np.ndarray | None = None) -> np.ndarray:
    """MISO words for plain 16-bit transfers starting at ``start`` and releasing chip select at ``end`` (s).

    ``next_activity`` (s) is when the bus clocks next after each transfer (another sensor's transfer may come
    first); by default the port's own next transfer, and unknown (deferred) after the last one.  Two compiled
    passes: the commands (what each prepares; the sensor converts the accepted ones in one call), then the
    transfers in order.
    """
    port.resolve_conversion(float(start[0]))
    start = np.ascontiguousarray(start, dtype=float)
    end = np.ascontiguousarray(end, dtype=float)
    nxt = _NO_NEXT if next_activity is None else np.ascontiguousarray(next_activity, dtype=float)
    word_of_byte, recognized_of_byte, channel_of_byte = _TABLES[port.variant.name]
    n = mosi.size
    first, prepared = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    cmd_end, acc_time = np.empty(n), np.empty(n)
    acc_at, acc_channel, acc_coupled = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64), np.empty(n, bool)
    last_tick = port.last_sampling_tick if port.last_sampling_tick is not None else _NO_TICK
    n_cmd, sampling, last_tick, unprovided, n_acc, deferred = _commands(
        mosi, start, end, nxt, word_of_byte, recognized_of_byte, channel_of_byte, port.provided_lut, last_tick,
        float(port.conversion_s), first, cmd_end, prepared, acc_at, acc_channel, acc_time, acc_coupled)
    port.unprovided_requests += unprovided
    if sampling:
        port.last_sampling_tick = int(last_tick)
    codes = np.zeros(0, np.uint16)
    if n_acc:
        coupled = acc_coupled[:n_acc]
        port.coupled_conversions += int(np.count_nonzero(coupled))
        codes = port.sensor.sample(acc_channel[:n_acc], acc_time[:n_acc], bus_active=coupled)
    before = port.prepared
    out = np.empty(n, dtype=np.uint16)
    consumed, last_consuming = _transfers(
        mosi, start, cmd_end, prepared, acc_at, codes, proto.RESPONSE_WORD,
        before.ready_tick if before is not None else -1, before.word if before is not None else 0,
        before.consumed if before is not None else True, out)
    if last_consuming >= 0:
        port.last_sent = int(out[last_consuming])
    # the port's state after the batch
    if n_cmd:
        tick = int(ticks_array(cmd_end[n_cmd - 1:n_cmd])[0])
        if deferred >= 0:
            port.prepared = _Prepared("pending", tick, sample=True)
            port._deferred = (int(channel_of_byte[first[deferred]]), float(cmd_end[deferred]))
        else:
            port.prepared = _Prepared("word", tick, word=int(prepared[n_cmd - 1]), consumed=bool(consumed),
                                      sample=bool(n_acc and acc_at[n_acc - 1] == n_cmd - 1))
    elif before is not None and consumed:
        before.consumed = True
    return out
