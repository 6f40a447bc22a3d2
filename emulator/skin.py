"""The skin as an object with a history: fingerprint ridges that wear with frictional work (D ch. 4 and 6).

Ridges (pitch and width 0.4 mm, height 0.2 mm when new, D ch. 4) lose height by an Archard-type law whose rate
rises steeply with the sliding power: the worn volume is ``k · N · d / H · (N·v / P_ref)^β`` (wear coefficient
``k``, normal force ``N``, sliding distance ``d``, hardness ``H``, sliding speed ``v``), spread over the ridge
crests in contact.  ``N·v`` is D's sliding power (eq. 6.22) without the friction coefficient, which D's power
levels hold constant for a texture (so does the law: a model choice).  Both knobs are calibrated to what D says
about wear, never to an accuracy: ``k`` so that D's three training movements (all of power level 6) wear two
skins to first visible wear over the 1755 training trials (D "replaced two times"); ``β`` so that after a
pilot's worth of use (60 trials of one movement: 10 textures × 6 repetitions) the movements D kept (power level
≤ 7) show no visible wear while those of level 8 do (D Fig. 6-7 excluded levels above 7 "due to the high wear
rate").  :func:`bench.experiments.trials.wear_calibration` re-derives both.

Wear is *visible* once the flat worn on a rounded ridge crest (radius ``r`` = half the ridge width) is
``visible_flat_width_m`` wide: a crest worn down by ``δ`` shows a flat ``2·√(2rδ − δ²)`` wide, so the first
visible wear is ``δ = r − √(r² − (w/2)²)``, 3.2 % of a new ridge's height (:attr:`Skin.first_visible_wear_fraction`).

Worn ridges catch texture features less (the ridge term of the sliding model scales with ``ridge_height /
ridge_height_new``) and less regularly: each trial's ridge gain varies by a relative spread that grows with the
worn fraction (``irregularity``, a model choice standing for the uneven wear D saw as degraded repeatability).
A skin persists across the trials of a session until it is replaced; :meth:`Skin.history` lists its ridge
height after each trial.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

#: Timoshenko shear correction of a rectangular cross-section (κ = 5/6, textbook value for a ridge's section)
SHEAR_CORRECTION = 5.0 / 6.0


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
    ridge_crest_radius_m: float = 0.2e-3  # a rounded crest, half the ridge width (model choice)
    visible_flat_width_m: float = 0.1e-3  # a worn flat this wide is visible (model choice: the naked eye
    # resolves ~1 arcmin, 0.07–0.1 mm at 25–35 cm)
    wear_coefficient: float = 7.7e-6  # Archard k (1) at P_ref, calibrated: D's three training movements wear two
    # skins to first visible wear over 117 textures × 3 movements × 5 trials (D "replaced two times")
    wear_power_exponent: float = 3.4  # β (1), calibrated: after 60 trials of one movement (a pilot's worth)
    # the movements of power level ≤ 7 show no visible wear and those of level 8 do (D Fig. 6-7)
    reference_power_W: float = 0.02  # P_ref: N·v of D's main anti-diagonal, level 7 (model choice)
    hardness_Pa: float = 1.5e6  # silicone skin, ~45 Shore A (model choice)
    irregularity: float = 0.5  # relative spread of the ridge gain of a fully worn skin (model choice)
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

    def ridge_stiffness_per_length(self, youngs_modulus_Pa: float, poisson_ratio: float) -> float:
        """Tangential stiffness (N/m per m of ridge length) of one ridge as a cantilever of its present height ``h``
        and width ``w`` in the skin's modulus: bending ``E·w³/(4h³)`` in series with shear ``κ·G·w/h``
        (``G = E/(2(1 + ν))``, ``κ`` = :data:`SHEAR_CORRECTION`).  Derived from D's geometry, not tuned: 0.42 MPa
        for a new ridge of Silastic (E 0.97 MPa, ν 0.5); a worn (shorter) ridge is stiffer, a ridge worn flat
        (height 0) rigid (infinite)."""
        h, w = max(self.ridge_height_m, 0.0), self.ridge_width_m
        if h == 0.0:
            return math.inf
        shear_modulus = youngs_modulus_Pa / (2.0 * (1.0 + poisson_ratio))
        bending = youngs_modulus_Pa * w**3 / (4.0 * h**3)
        shear = SHEAR_CORRECTION * shear_modulus * w / h
        compliance = 1.0 / bending + 1.0 / shear
        return 1.0 / compliance if compliance > 0.0 else math.inf  # (an infinite modulus: rigid)

    @property
    def first_visible_wear_fraction(self) -> float:
        """Fraction of the new ridge height worn off when the flat on the crest becomes visible (1)."""
        r, half = self.ridge_crest_radius_m, self.visible_flat_width_m / 2
        return (r - math.sqrt(r * r - half * half)) / self.ridge_height_new_m

    def height_lost(self, normal_N: float, distance_m: float, contact_area_m2: float,
                    velocity_m_per_s: float) -> float:
        """Ridge height (m) a new-enough skin loses sliding ``distance_m`` at ``normal_N`` and ``velocity_m_per_s``
        over ``contact_area_m2``: the volume k·N·d/H·(N·v/P_ref)^β spread over the crest area in contact."""
        if not (normal_N >= 0 and distance_m >= 0 and contact_area_m2 > 0 and velocity_m_per_s >= 0):
            raise ValueError("wear needs normal_N, distance_m, velocity_m_per_s ≥ 0 and a positive contact area")
        crest_area = contact_area_m2 * self.ridge_contact_width_m / self.ridge_pitch_m
        power = (normal_N * velocity_m_per_s / self.reference_power_W) ** self.wear_power_exponent
        return self.wear_coefficient * power * normal_N * distance_m / self.hardness_Pa / crest_area

    def wear(self, normal_N: float, distance_m: float, contact_area_m2: float, mu: float = 0.0,
             velocity_m_per_s: float | None = None) -> float:
        """Wear the ridges after sliding ``distance_m`` at ``normal_N`` and ``velocity_m_per_s`` over
        ``contact_area_m2`` (``mu`` only counts the frictional work); returns the height lost (m)."""
        if velocity_m_per_s is None:
            raise ValueError("wear needs the sliding speed (velocity_m_per_s)")
        lost = self.height_lost(normal_N, distance_m, contact_area_m2, velocity_m_per_s)
        self.trials += 1
        self.sliding_distance_m += distance_m
        self.frictional_work_J += mu * normal_N * distance_m
        if self.fingerprints and self.ridge_height_m > 0:
            lost = min(self.ridge_height_m, lost)
            self.ridge_height_m -= lost
        else:
            lost = 0.0
        self._history.append((self.serial, self.trials, self.ridge_height_m))
        return lost

    def replace(self) -> "Skin":
        """A fresh skin of the same kind (ridges new); the history carries on under the next serial."""
        return replace(self, ridge_height_m=self.ridge_height_new_m, serial=self.serial + 1, trials=0,
                       sliding_distance_m=0.0, frictional_work_J=0.0, _history=list(self._history))

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
        for name in ("wear_coefficient", "wear_power_exponent"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"skin.{name} = {v!r}: must be ≥ 0")
        for name in ("reference_power_W", "ridge_crest_radius_m", "visible_flat_width_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"skin.{name} = {v!r}: must be a positive number")
        if self.visible_flat_width_m >= 2 * self.ridge_crest_radius_m:
            raise ValueError(f"skin.visible_flat_width_m = {self.visible_flat_width_m!r}: must be narrower than the "
                             f"crest ({2 * self.ridge_crest_radius_m} m)")
