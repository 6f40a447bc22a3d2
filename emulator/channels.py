"""Channel indices of the SPI sampling command and the default sample frame (SENSOR.md §6)."""

from __future__ import annotations

import numpy as np

PAC, PDC, TAC, TDC, HAL = 0, 1, 2, 3, 15
ELECTRODE_FIRST = 17  # E1; E19 = 35

CHANNEL_INDEX: dict[str, int] = {"PAC": PAC, "PDC": PDC, "TAC": TAC, "TDC": TDC, "HAL": HAL}
CHANNEL_INDEX.update({f"E{n}": ELECTRODE_FIRST + n - 1 for n in range(1, 20)})
CHANNEL_NAME: dict[int, str] = {v: k for k, v in CHANNEL_INDEX.items()}

#: Channels this sensor answers (HAL is a valid index on the device but carries no signal here).
SAMPLED_CHANNELS = frozenset(CHANNEL_INDEX.values()) - {HAL}

#: The default 44-slot frame: E1,PAC,E2,PAC,...,E19,PAC,PDC,PAC,TAC,PAC,TDC,PAC.
DEFAULT_FRAME_NAMES: tuple[str, ...] = tuple(
    name
    for other in [f"E{n}" for n in range(1, 20)] + ["PDC", "TAC", "TDC"]
    for name in (other, "PAC")
)
DEFAULT_SLOT_RATE_HZ = 4400.0


def channel_index(name: str) -> int:
    """SPI channel index for a channel name such as ``"PAC"`` or ``"E7"``."""
    try:
        return CHANNEL_INDEX[name.upper()]
    except KeyError:
        raise ValueError(
            f"unknown channel {name!r}; known: PAC, PDC, TAC, TDC, E1..E19"
        ) from None


def parse_sequence(sequence) -> np.ndarray:
    """Channel indices from ``"default"`` or a list of names/indices."""
    if isinstance(sequence, str):
        if sequence != "default":
            raise ValueError(f"sequence {sequence!r}: use \"default\" or a list of channel names")
        sequence = DEFAULT_FRAME_NAMES
    if len(sequence) == 0:
        raise ValueError("sequence is empty")
    return np.array([c if isinstance(c, int) else channel_index(c) for c in sequence], dtype=np.int64)
