"""The skin as an object with a history: fingerprint ridges that wear with frictional work (D ch. 4 and 6).

Ridges (pitch and width 0.4 mm, height 0.2 mm when new, D ch. 4) lose height by an Archard-type law: the worn
volume is ``k · (1 + v/v_h) · N · d / H`` (wear coefficient ``k``, normal force ``N``, sliding distance ``d``,
hardness ``H``), spread over the ridge crests in contact.  The factor ``1 + v/v_h`` stands for the faster
abrasion of elastomers at higher sliding speed (frictional heating at the asperities; ``v_h`` = 2.5 cm/s is a
model choice), so over the rig's fixed 5 cm the movements of high force × high speed wear fastest, as D saw.  Worn ridges catch texture features less (the ridge term of the
sliding model scales with ``ridge_height / ridge_height_new``) and less regularly: each trial's ridge gain
varies by a relative spread that grows with the worn fraction (``irregularity``, a model choice standing for
the uneven wear D saw as degraded repeatability).  A skin persists across the trials of a session until it is
replaced; :meth:`Skin.history` lists its ridge height after each trial.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


def contact_patch_radius_m(load_N, contact_radius_at_1N_m: float):
    """Radius (m) of the skin's contact patch under a normal load ``load_N`` (N): a_1N · N^(1/3) (Hertz), with
    ``contact_radius_at_1N_m`` = a_1N (m)."""
    return contact_radius_at_1N_m * load_N ** (1 / 3)


def contact_patch_area_m2(load_N, contact_radius_at_1N_m: float):
    """Area (m²) of the skin's contact patch under a normal load ``load_N`` (N): π (a_1N · N^(1/3))²."""
    return np.pi * contact_patch_radius_m(load_N, contact_radius_at_1N_m) ** 2


@dataclass
class Skin:
    """One silicone skin. Lengths in m, forces in N, hardness in Pa."""

    fingerprints: bool = True
    ridge_pitch_m: float = 0.4e-3
    ridge_width_m: float = 0.4e-3
    ridge_height_new_m: float = 0.2e-3
    ridge_height_m: float = 0.2e-3
    ridge_contact_width_m: float = 0.1e-3  # crest width that touches a surface (model choice)
    wear_coefficient: float = 2.5e-5  # Archard k (1), calibrated: a skin lasts ~600 trials of 1 N × 5 cm at 2.5 cm/s, as D replaced
    # the skin twice over 117 textures × 15 trials
    hardness_Pa: float = 1.5e6  # silicone skin, ~45 Shore A (model choice)
    irregularity: float = 0.5  # relative spread of the ridge gain of a fully worn skin (model choice)
    heating_velocity_m_per_s: float = 0.025  # v_h: abrasion doubles at this sliding speed (model choice)
    serial: int = 1
    trials: int = 0
    sliding_distance_m: float = 0.0
    frictional_work_J: float = 0.0
    _history: list = field(default_factory=list, repr=False)

    @property
    def ridge_factor(self) -> float:
        """Ridge height relative to new (1 = new ridges, 0 = worn flat or a smooth skin)."""
        if not self.fingerprints:
            return 0.0
        return max(self.ridge_height_m, 0.0) / self.ridge_height_new_m

    @property
    def worn_fraction(self) -> float:
        return 1.0 - self.ridge_factor if self.fingerprints else 0.0

    def trial_gain(self, rng: np.random.Generator) -> float:
        """This trial's ridge gain: the ridge factor with a spread that grows as the ridges wear (≥ 0)."""
        if not self.fingerprints:
            return 0.0
        spread = self.irregularity * self.worn_fraction
        return max(0.0, self.ridge_factor * (1.0 + spread * rng.standard_normal()))

    def wear(self, normal_N: float, distance_m: float, contact_area_m2: float, mu: float = 0.0,
             velocity_m_per_s: float = 0.0) -> float:
        """Wear the ridges after sliding ``distance_m`` at ``normal_N`` and ``velocity_m_per_s`` over
        ``contact_area_m2``; returns the height lost (m).  The worn volume k·(1 + v/v_h)·N·d/H is spread over the
        crest area in contact."""
        if normal_N < 0 or distance_m < 0 or contact_area_m2 <= 0 or velocity_m_per_s < 0:
            raise ValueError("wear needs normal_N, distance_m, velocity_m_per_s ≥ 0 and a positive contact area")
        self.trials += 1
        self.sliding_distance_m += distance_m
        self.frictional_work_J += mu * normal_N * distance_m
        lost = 0.0
        if self.fingerprints and self.ridge_height_m > 0:
            crest_area = contact_area_m2 * self.ridge_contact_width_m / self.ridge_pitch_m
            k = self.wear_coefficient * (1.0 + velocity_m_per_s / self.heating_velocity_m_per_s)
            lost = min(self.ridge_height_m, k * normal_N * distance_m / self.hardness_Pa / crest_area)
            self.ridge_height_m -= lost
        self._history.append((self.serial, self.trials, self.ridge_height_m))
        return lost

    def replace(self) -> "Skin":
        """A fresh skin of the same kind (ridges new); the history carries on under the next serial."""
        fresh = Skin(self.fingerprints, self.ridge_pitch_m, self.ridge_width_m, self.ridge_height_new_m,
                     self.ridge_height_new_m, self.ridge_contact_width_m, self.wear_coefficient, self.hardness_Pa,
                     self.irregularity, self.heating_velocity_m_per_s, serial=self.serial + 1)
        fresh._history = list(self._history)
        return fresh

    def history(self) -> list[tuple[int, int, float]]:
        """(skin serial, trials on that skin, ridge height in m) after each trial."""
        return list(self._history)

    def state(self) -> dict:
        """The skin's state for a run's record (SI units)."""
        return {"serial": self.serial, "fingerprints": self.fingerprints, "ridge_height_m": self.ridge_height_m,
                "ridge_height_new_m": self.ridge_height_new_m, "ridge_factor": self.ridge_factor,
                "trials": self.trials, "sliding_distance_m": self.sliding_distance_m,
                "frictional_work_J": self.frictional_work_J}

    def __post_init__(self):
        for name in ("ridge_pitch_m", "ridge_width_m", "ridge_height_new_m", "ridge_contact_width_m", "hardness_Pa"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"skin.{name} = {v!r}: must be a positive number")
        if not (0 <= self.ridge_height_m <= self.ridge_height_new_m):
            raise ValueError(f"skin.ridge_height_m = {self.ridge_height_m!r}: must be within 0 and the new height "
                             f"{self.ridge_height_new_m}")
        if not (math.isfinite(self.wear_coefficient) and self.wear_coefficient >= 0):
            raise ValueError(f"skin.wear_coefficient = {self.wear_coefficient!r}: must be ≥ 0")
