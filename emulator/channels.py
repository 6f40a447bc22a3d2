"""Channel indices of the SPI sampling command and the default sample frame (SENSOR.md §6), per sensor variant.

Two variants exist:

* ``"biotac"`` — the dissertation's sensor (D): 19 electrodes E1..E19 at channel indices 17..35 and a
  44-slot frame.  The module-level names (``CHANNEL_INDEX``, ``SAMPLED_CHANNELS``, ``DEFAULT_FRAME_NAMES`` …)
  describe this default variant, as they always have.
* ``"biotac-sp"`` — the BioTac SP: 24 electrodes E1..E24 at channel indices 17..40 (E20..E24 = 36..40,
  sampling commands 0xC8..0xD0) and the 54-slot frame E1,PAC,…,E24,PAC,PDC,PAC,TAC,PAC,TDC,PAC.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PAC, PDC, TAC, TDC, HAL = 0, 1, 2, 3, 15
ELECTRODE_FIRST = 17  # E1; E19 = 35 (E24 = 40 on the SP)

DEFAULT_VARIANT = "biotac"
#: Electrode count of each variant.
ELECTRODE_COUNT: dict[str, int] = {"biotac": 19, "biotac-sp": 24}
VARIANTS: tuple[str, ...] = tuple(ELECTRODE_COUNT)
DEFAULT_SLOT_RATE_HZ = 4400.0


@dataclass(frozen=True)
class Variant:
    """Channel map of one sensor variant."""

    name: str
    n_electrodes: int
    channel_index: dict  # name -> SPI channel index
    channel_name: dict  # SPI channel index -> name
    sampled_channels: frozenset  # indices the sensor answers with data (HAL carries no signal here)
    frame_names: tuple  # the default frame: E1,PAC,…,En,PAC,PDC,PAC,TAC,PAC,TDC,PAC

    @property
    def electrode_channels(self) -> range:
        return range(ELECTRODE_FIRST, ELECTRODE_FIRST + self.n_electrodes)

    @property
    def frame_length(self) -> int:
        return len(self.frame_names)


def _build(name: str) -> Variant:
    n = ELECTRODE_COUNT[name]
    index = {"PAC": PAC, "PDC": PDC, "TAC": TAC, "TDC": TDC, "HAL": HAL}
    index.update({f"E{k}": ELECTRODE_FIRST + k - 1 for k in range(1, n + 1)})
    frame = tuple(slot for other in [f"E{k}" for k in range(1, n + 1)] + ["PDC", "TAC", "TDC"]
                  for slot in (other, "PAC"))
    return Variant(name, n, index, {v: k for k, v in index.items()}, frozenset(index.values()) - {HAL}, frame)


_VARIANTS = {name: _build(name) for name in VARIANTS}


def variant(name: str | Variant = DEFAULT_VARIANT) -> Variant:
    """The channel map of variant ``name`` (``"biotac"`` or ``"biotac-sp"``); ValueError names the allowed ones."""
    if isinstance(name, Variant):
        return name
    try:
        return _VARIANTS[name]
    except (KeyError, TypeError):
        raise ValueError(f"sensor variant {name!r} is not known; allowed: {', '.join(VARIANTS)}") from None


_DEFAULT = _VARIANTS[DEFAULT_VARIANT]
CHANNEL_INDEX: dict[str, int] = dict(_DEFAULT.channel_index)
CHANNEL_NAME: dict[int, str] = dict(_DEFAULT.channel_name)
#: Channels the default sensor answers (HAL is a valid index on the device but carries no signal here).
SAMPLED_CHANNELS = _DEFAULT.sampled_channels
#: The default 44-slot frame: E1,PAC,E2,PAC,...,E19,PAC,PDC,PAC,TAC,PAC,TDC,PAC.
DEFAULT_FRAME_NAMES: tuple[str, ...] = _DEFAULT.frame_names
#: Every channel index any variant answers (E1..E24): a name is parsed against this, a sensor then checks its own.
ALL_CHANNEL_INDEX: dict[str, int] = dict(_VARIANTS["biotac-sp"].channel_index)


def channel_index(name: str, variant_name: str | None = None) -> int:
    """SPI channel index for a channel name such as ``"PAC"`` or ``"E7"``.

    With ``variant_name`` the name must exist on that variant; without it any variant's channel
    (E1..E24) is accepted, so a 19-electrode sensor can be asked for E20 and answer ``EX``.
    """
    table = ALL_CHANNEL_INDEX if variant_name is None else variant(variant_name).channel_index
    try:
        return table[name.upper()]
    except (KeyError, AttributeError):
        n = 24 if variant_name is None else variant(variant_name).n_electrodes
        raise ValueError(f"unknown channel {name!r}; known: PAC, PDC, TAC, TDC, E1..E{n}") from None


def parse_sequence(sequence, variant_name: str = DEFAULT_VARIANT) -> np.ndarray:
    """Channel indices from ``"default"`` (the variant's frame) or a list of names/indices."""
    if isinstance(sequence, str):
        if sequence != "default":
            raise ValueError(f"sequence {sequence!r}: use \"default\" or a list of channel names")
        sequence = variant(variant_name).frame_names
    if len(sequence) == 0:
        raise ValueError("sequence is empty")
    return np.array([c if isinstance(c, int) else channel_index(c) for c in sequence], dtype=np.int64)
