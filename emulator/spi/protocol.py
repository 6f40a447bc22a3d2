"""Bit-level facts of the BioTac SPI protocol (SENSOR.md §6), shared by the peripheral and hosts.

* Sampling command, first byte ``1 S S S S S S P``: S = 6-bit channel index, P makes the byte's
  count of ones odd.  The second byte is ignored.
* Response word: bits 15–9 = data[11:5], bit 8 = odd parity of the first byte, bits 7–3 =
  data[4:0], bits 2–1 = 0, bit 0 = odd parity of the second byte.
* Error words start with 0xA5 (deliberately even parity) so a host flags them.
"""

from __future__ import annotations

import numpy as np

SAMPLE_DELAY_S = 50e-6  # minimum time from sampling command to reading the result
#: Timing comparisons allow 1 ns: far below any SPI timing, far above float64 rounding of times
#: (3.6 ps at 2^14 s, 0.1 ns after a year), so long runs never flip a comparison.
TIME_TOLERANCE_S = 1e-9
SPI_CLOCK_RANGE_HZ = (500e3, 10e6)
HOST_DEFAULT_CLOCK_HZ = 4.4e6

ERROR_WORDS: dict[str, int] = {
    "parity": 0xA545,  # "EE"
    "unknown_command": 0xA53F,  # "E?"
    "insufficient_delay": 0xA52E,  # "E."
    "insufficient_sampling_delay": 0xA52D,  # "E-"
    "channel_not_recognized": 0xA558,  # "EX"
    "nothing_to_resend": 0xA55F,  # "E_"
    "read_only": 0xA552,  # "ER"
    "write_error": 0xA557,  # "EW"
}
ERROR_NAME = {v: k for k, v in ERROR_WORDS.items()}
#: First byte of every error word.
ERROR_WORD_PREFIX = 0xA5


def is_error_word(word) -> np.ndarray:
    """True for response word(s) that are error words (first byte 0xA5), whatever their second byte."""
    return (np.asarray(word, dtype=np.uint16) >> 8) == ERROR_WORD_PREFIX

_POPCOUNT = np.array([bin(i).count("1") for i in range(256)], dtype=np.uint8)
#: True where a byte has an odd number of ones.
ODD_PARITY_OK = (_POPCOUNT & 1).astype(bool)


def with_odd_parity(seven_bits) -> np.ndarray:
    """Byte made of 7 data bits (shifted left) and a parity LSB that makes the ones count odd."""
    b = (np.asarray(seven_bits, dtype=np.uint16) & 0x7F) << 1
    return (b | (~_POPCOUNT[b] & 1)).astype(np.uint8)


def sample_command(channel) -> np.ndarray:
    """First byte of the sampling command for channel index/indices (e.g. PAC -> 0x80, PDC -> 0x83); an index that
    is not a whole number 0..63 is a ValueError naming it (1.5 and True had been taken as channel 1, PDC)."""
    c = np.asarray(channel)
    if c.size and c.dtype.kind not in "iu":  # a float, a bool, a name: never truncated into another channel
        raise ValueError(f"channel index {channel!r}: a whole number 0..63 (by name: "
                         f"emulator.channels.channel_index(\"PDC\"))")
    if np.any(c < 0) or np.any(c > 63):
        raise ValueError(f"channel index {int(c[(c < 0) | (c > 63)].flat[0])}: must be 0..63")
    c = c.astype(np.uint16)
    return with_odd_parity(0x40 | c)


def _build_encode_table() -> np.ndarray:
    data = np.arange(4096, dtype=np.uint16)
    hi = with_odd_parity(data >> 5).astype(np.uint16)
    lo_data = ((data & 0x1F) << 3).astype(np.uint16)
    lo = lo_data | (~_POPCOUNT[lo_data] & 1)
    return ((hi << 8) | lo).astype(np.uint16)


#: Response word for each 12-bit code.
RESPONSE_WORD = _build_encode_table()


def encode_response(code) -> np.ndarray:
    """Response word(s) carrying 12-bit code(s)."""
    return RESPONSE_WORD[np.asarray(code, dtype=np.int64)]


def decode_response(word) -> tuple[np.ndarray, np.ndarray]:
    """(value, ok) for response word(s): value = (byte0 >> 1)·32 + (byte1 >> 3); ok = both bytes odd parity."""
    w = np.asarray(word, dtype=np.uint16)
    b0, b1 = w >> 8, w & 0xFF
    value = (b0 >> 1).astype(np.int32) * 32 + (b1 >> 3)
    return value, ODD_PARITY_OK[b0] & ODD_PARITY_OK[b1]
