"""Vectorized evaluation of plain sampling/read traffic for one sensor alone on its bus.

The host sampler streams millions of 16-bit transfers that are only sampling commands and reads;
this routine computes exactly what :class:`emulator.spi.model.SensorPort`'s transfer-level path
would, with array operations, and leaves the port in the same state.  A differential test checks
the two against each other; anything else (properties, resend, writes, faults) takes the
transfer-level path.
"""

from __future__ import annotations

import numpy as np

from emulator import channels as ch
from emulator.spi import protocol as proto
from emulator.spi.model import (CMD_READ_PROPERTY, CMD_RESEND, CMD_RESEND_MANUAL, CMD_WRITE, CONVERSION_TICKS,
                                SAMPLE_DELAY_TICKS, _Prepared, ticks_array)

_ERR = proto.ERROR_WORDS
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
    return not _SPECIAL[mosi >> 8].any()


def exchange_words(port, start: np.ndarray, end: np.ndarray, mosi: np.ndarray,
                   next_activity: np.ndarray | None = None) -> np.ndarray:
    """MISO words for plain 16-bit transfers starting at ``start`` and releasing chip select at ``end`` (s).

    ``next_activity`` (s) is when the bus clocks next after each transfer (another sensor's transfer may come
    first); by default the port's own next transfer, and unknown (deferred) after the last one.
    """
    n = start.size
    port.resolve_conversion(float(start[0]))
    b0 = (mosi >> 8).astype(np.int64)
    is_cmd = b0 != 0
    cmd = np.flatnonzero(is_cmd)
    reads = np.flatnonzero(~is_cmd)
    first = b0[cmd]
    cmd_end = end[cmd]
    cmd_tick = ticks_array(cmd_end)
    word_of_byte, recognized_of_byte, channel_of_byte = _TABLES[port.variant.name]
    prepared = word_of_byte[first].copy()

    # sampling commands for recognised channels: ADC busy (E-), not provided (EX), or converted
    rs = np.flatnonzero(recognized_of_byte[first])
    deferred = None
    if rs.size:
        rticks = cmd_tick[rs]
        prev = np.concatenate([[port.last_sampling_tick if port.last_sampling_tick is not None else -10**12],
                               rticks[:-1]])
        busy = rticks - prev < CONVERSION_TICKS
        channels = channel_of_byte[first[rs]]
        provided = port.provided_lut[channels]
        prepared[rs[busy]] = _ERR["insufficient_sampling_delay"]
        unprovided = ~busy & ~provided
        prepared[rs[unprovided]] = _ERR["channel_not_recognized"]
        port.unprovided_requests += int(np.count_nonzero(unprovided))
        acc = rs[~busy & provided]
        acc_ch = channels[~busy & provided]
        nxt = np.append(start[1:], np.inf) if next_activity is None else np.asarray(next_activity, float)
        if acc.size and not np.isfinite(nxt[cmd[acc[-1]]]):  # nothing known after it: convert when something is
            deferred = (int(acc_ch[-1]), float(cmd_end[acc[-1]]))
            acc, acc_ch = acc[:-1], acc_ch[:-1]
        if acc.size:
            next_start = nxt[cmd[acc]]
            coupled = next_start < cmd_end[acc] + port.conversion_s
            port.coupled_conversions += int(np.count_nonzero(coupled))
            codes = port.sensor.sample(acc_ch, cmd_end[acc], bus_active=coupled)
            words = proto.RESPONSE_WORD[codes].astype(np.int64)
            prepared[acc] = words
        port.last_sampling_tick = int(rticks[-1])

    # what each transfer shifts out, and which read consumes each prepared word
    before = port.prepared
    idx = np.arange(n)
    c = np.cumsum(is_cmd) - is_cmd - 1  # latest command before each transfer; -1: from before the batch
    # per-command tables with the state from before the batch in front (index c + 1)
    ready_of = np.concatenate([[before.ready_tick if before else 0], cmd_tick])
    word_of = np.concatenate([[before.word if before else 0], prepared])
    ready = ready_of[c + 1]
    word = word_of[c + 1]
    consumed_init = before.consumed if before is not None else True
    delay_ok = ticks_array(start) - ready >= SAMPLE_DELAY_TICKS
    nothing = consumed_init & (c == -1) if before is not None else c < 0  # no result to shift out
    delay_ok &= ~nothing
    can_consume = delay_ok[reads] & ~((c[reads] == -1) & consumed_init)
    first_consume = np.full(cmd.size + 1, n)
    if can_consume.any():
        g = c[reads][can_consume]  # non-decreasing along the reads: the first of each run consumes
        head = np.concatenate([[True], g[1:] != g[:-1]])
        first_consume[g[head] + 1] = reads[can_consume][head]
    consumed_before = (first_consume[c + 1] < idx) | nothing
    out = np.where(delay_ok, word, _ERR["insufficient_delay"])
    out[consumed_before] = _ERR["nothing_to_resend"]
    consuming = first_consume[first_consume < n]
    if consuming.size:
        port.last_sent = int(out[consuming.max()])

    # the port's state after the batch
    if cmd.size:
        last = cmd.size - 1
        done = bool(first_consume[last + 1] < n)
        if deferred is not None:
            port.prepared = _Prepared("pending", int(cmd_tick[last]))
            port._deferred = deferred
        else:
            port.prepared = _Prepared("word", int(cmd_tick[last]), word=int(prepared[last]), consumed=done)
    elif before is not None and first_consume[0] < n:
        before.consumed = True
    return out.astype(np.uint16)
