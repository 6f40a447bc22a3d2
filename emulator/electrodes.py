"""The impedance electrodes (19 on the BioTac, 24 on the SP) behind the multiplexer (SENSOR.md §5, D ch. 4).

Contact -> skin and fluid deformation -> fluid gap over every electrode -> impedance -> voltage.

* Resting gaps: electrode i rests under a gap g_i = g₀ + ``electrode_gap_spread_mm``·z_i, z_i a standard
  normal truncated to ±2 and drawn from ``electrode_gap_seed`` (:func:`resting_gaps_mm`; spread 0: all g₀).
  The units' 0.7 mm spread (:mod:`emulator.units`) puts resting codes over about 1900–3150 (2nd–98th
  percentiles over 20 units, each unit spanning ~1000 codes): a low gap moves the code far more than a high one
  (the code saturates toward 3545 as the gap grows).
* A contact at a point of the skin (``x_mm`` along the finger, ``angle_deg`` around it from the ventral
  midline toward +y) with normal force F moves the skin toward the core by δ₀·exp(−d²/2w²) at distance d from
  its centre, δ₀ = (g₀ − g_min)·a, w² = r_indenter² + spread², a = 1 − e^(−F/F₀): the same displacement over any
  resting gap g_i, stopped on the core at g_min (a thin-gap electrode bottoms under a lighter press).  The force passes through the skin's creep (the
  standard linear solid of emulator/mechanics.py and emulator/viscoelastic.py, state carried across chunks)
  before the depth law, so a held force creeps the pattern (~10 % more force-equivalent over ~1.1 s) and a
  release recovers over the same time.  Tangential force shifts the whole pattern toward the shear.
* Where the displaced liquid goes: the fluid is incompressible and the skin is tethered at the nail (only
  skin within ``free_skin_half_angle_deg`` of the ventral midline, and ahead of the base clamp, may move), so
  the volume reappears as a ring bulge around the contact rim, κ·δ₀·(d²/2s²)·exp(−d²/2s²) with
  s = ``bulge_width_ratio``·w (default 1/√2: ring peak at w) and δ₀ = (g₀ − g_min)·a; κ (≈2, more near the
  nail or the base) makes the net volume over the free skin zero (:func:`bulge_balance`).
  Locality (the gap change per mm of central depth, κ = 2): −1 at the centre, −0.55 at 0.5 w, 0 at 0.85 w
  (the dimple ends), +0.2 at 1.24 w (the rim bulge), 0 again at 2.07 w, then a faint −0.01…−0.02 tail that
  is gone (< 0.003) beyond 3.5 w.  For a 1 N fingertip contact (3 mm indenter, w = 4.2 mm): −380 codes on
  the pressed electrode, −170 at 2 mm, +35 to +40 codes at 5–6 mm, under 6 codes beyond 8 mm; the
  pressed electrode and its 3 nearest neighbours carry 77 % (median; 65 % at least) of Σ|Δcode| over the
  19 electrodes, where the former uniform bulge moved every electrode by 20–30 codes (62 %).
  Sources: D ch. 4 says only that the skin and fluid deform over electrodes distributed on the core;
  SynTouch and Lin et al. 2013 describe a distributed pattern from which the point of contact is estimated;
  no published figure gives the fall-off, so the profile's shape is a model choice (claims: locality is
  calibrated on ``bulge_width_ratio``, localisation within 2 mm is a prediction).
* The fluid over an electrode is a thin conducting sheet: Z = Z_series + ρ_sheet / gap, so thinning the
  fluid raises the impedance.
* The multiplexer connects the selected electrode into a 10 kΩ load driven by the 4 kHz, 3.3 V
  excitation; the peak detector holds V = 3.3·R_load/(Z + R_load), so impedance = (3.3/V − 1)·10 kΩ
  (D eq. 4.1).  The electrode path has a 100 Hz bandwidth.
* Between conversions the hold node keeps the last electrode's value; switching to another electrode
  injects charge and the node settles with ``mux_settling_s`` during the firmware's acquisition delay,
  so each sample keeps exp(−t_acq/τ) of the previous electrode's value: cross-talk when channels switch
  faster than the node settles.

Geometry and deformation are evaluated at the fidelity profile's electrode rate (250 Hz to 2 kHz, above
twice the 100 Hz bandwidth) in chunks aligned to absolute time, filtered per electrode, and interpolated
to conversion instants.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from numba import njit
from scipy import special

from emulator import filters
from emulator.channels import DEFAULT_VARIANT, ELECTRODE_FIRST
from emulator.channels import variant as variant_of
from emulator.mechanics import skin_fluid
from emulator.params import SensorParams
from emulator.viscoelastic import Creep

CHUNK_S = 1.0  # the model advances in 1 s chunks aligned to absolute time (per-chunk overhead dominates)
CORE_RADIUS_MM = 5.0
FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
#: each variant's electrode table: the BioTac's 19 (Ruppel et al. 2018, via SENSOR.md) and the BioTac SP's 24
#: (derived from its documented layout grid; see that file's header)
ELECTRODE_TABLES = {"biotac": FIXTURES / "electrodes.csv", "biotac-sp": FIXTURES / "electrodes_sp.csv"}
ELECTRODES_CSV = ELECTRODE_TABLES["biotac"]


def electrode_positions_mm(variant: str = DEFAULT_VARIANT) -> np.ndarray:
    """(N, 3) electrode positions on the core in the sensor frame (mm) of a sensor variant (a new array; the table
    is read once)."""
    return _electrode_table(variant_of(variant).name).copy()  # ValueError naming the known variants


@lru_cache(maxsize=None)
def _electrode_table(name: str) -> np.ndarray:
    v = variant_of(name)
    path = ELECTRODE_TABLES[v.name]
    rows = [r for r in csv.reader(line for line in path.read_text().splitlines()
                                  if line and not line.startswith("#"))]
    table = np.array([[float(x) for x in r[1:4]] for r in rows if r[0].startswith("E")])
    if table.shape != (v.n_electrodes, 3):
        raise ValueError(f"{path}: {table.shape[0]} electrode rows, a {v.name!r} sensor has {v.n_electrodes}")
    return table


def surface_point_mm(x_mm: float, angle_deg: float) -> np.ndarray:
    """A point of the core surface (the wetted skin's shape, :func:`free_skin_grid`), mm: ``x_mm`` along the finger
    — on the cylinder of radius CORE_RADIUS_MM for x ≤ 0, on the hemispherical tip for 0 < x ≤ CORE_RADIUS_MM (its
    apex) — and ``angle_deg`` from the ventral midline (−z) to +y.  Beyond the apex there is no finger: ValueError."""
    if not x_mm <= CORE_RADIUS_MM:
        raise ValueError(f"x_mm = {x_mm!r}: the finger ends at its tip's apex, x = {CORE_RADIUS_MM:g} mm")
    a = np.radians(angle_deg)
    r = CORE_RADIUS_MM if x_mm <= 0.0 else np.sqrt(CORE_RADIUS_MM**2 - x_mm**2)
    return np.array([x_mm, r * np.sin(a), -r * np.cos(a)])


def shear_direction(center_mm, shear_angle_deg: float, angle_deg: float | None = None) -> np.ndarray:
    """Unit vector (3,) of a shear at the core-surface point ``center_mm`` (mm), in the surface's tangent plane:
    cos φ·m + sin φ·c, φ = ``shear_angle_deg``, c = (0, cos a, sin a) the tangent around the finger (toward +angle
    a) and m the tangent along it toward the tip — +x on the cylinder (x ≤ 0); on the hemispherical tip (x > 0)
    n × c with n its outward normal, along the meridian toward the apex (at the apex, over it toward the back).
    a is the point's angle around the finger; at the apex, where the point has none (y = z = 0), the place's
    ``angle_deg`` (°) names its meridian, as a point just below the apex on it would (None: 0°, ventral)."""
    center = np.asarray(center_mm, float)
    if center[1] == 0.0 and center[2] == 0.0:  # the apex: arctan2 of two zeros gave 0 or π by their signs
        a = np.radians(0.0 if angle_deg is None else angle_deg)
    else:
        a = np.arctan2(center[1], -center[2])
    phi = np.radians(shear_angle_deg)
    around = np.array([0, np.cos(a), np.sin(a)])
    along = np.array([1.0, 0, 0]) if center[0] <= 0.0 else np.cross(center / np.linalg.norm(center), around)
    return np.cos(phi) * along + np.sin(phi) * around


def nail_touch_problem(angle_deg, p: SensorParams) -> str | None:
    """Why a contact centred ``angle_deg`` from the ventral midline cannot be modelled (None if it can): beyond
    ``free_skin_half_angle_deg`` the skin is tethered at the nail, and the model has no contact there — its force
    would reach the fluid as a touch on the pad does (a 1 N touch at 180° raised PDC 84 codes, as at 0°)."""
    if angle_deg is None:
        return None
    half = p.free_skin_half_angle_deg
    if abs((float(angle_deg) + 180.0) % 360.0 - 180.0) <= half:
        return None
    return (f"beyond {half:g}° from the ventral midline the skin is tethered at the nail (free_skin_half_angle_deg), "
            f"where the model has no contact (its force would load the fluid as on the pad); allowed -{half:g} to "
            f"{half:g}°")


def surface_point_over_mm(position_mm) -> np.ndarray:
    """The core-surface point over ``position_mm``, mm: radially from the finger's axis on the cylinder (x ≤ 0),
    from the tip's centre on the hemispherical tip (x > 0), so an electrode near the tip is not passed by."""
    p = np.asarray(position_mm, float)
    if p[0] > 0.0:
        return CORE_RADIUS_MM * p / np.linalg.norm(p)
    return surface_point_mm(p[0], np.degrees(np.arctan2(p[1], -p[2])))


@dataclass
class Contact:
    """A contact on the skin: where, how hard (normal and tangential force profiles), with what.

    ``normal_N(t)`` gives the normal force in N and the tangential force is ``tangential_per_normal`` times it; the
    tangential force acts along ``shear_direction`` (unit vector in the sensor frame, default along +x toward the
    tip).  ``planned``: the force profile is known in advance (a scripted stimulus); a contact driven by commands
    given while the run goes (a rig) is not, and the model then computes no instant beyond those asked for.

    ``forces``: the forces come from a model that runs on the sensor's grid (a sliding contact's
    :class:`emulator.sliding.ForceFeed`): ``forces(t)`` gives (normal, tangential) N at the model's instants and
    replaces ``normal_N`` and the ratio (``normal_N`` then only gives the load held before t = 0), and
    ``forces.last_grid_index(t)`` says how far the grid must have run first (see :meth:`ElectrodeModel.grid_needed`).
    Such a contact is not planned: its forces exist only as far as the grid has run.
    """

    center_mm: np.ndarray
    indenter_radius_mm: float
    normal_N: object
    tangential_per_normal: float = 0.0  # tangential force as a fraction of the normal force
    shear_direction: tuple = (1.0, 0.0, 0.0)
    start_s: float = -np.inf  # the contact exerts no force outside [start_s, end_s]
    end_s: float = np.inf
    planned: bool = True
    forces: object = None

    def state(self, t: np.ndarray):
        """(normal, tangential) force (N) at instants ``t`` (s); none outside [start_s, end_s], whatever the
        profile gives there (so the result does not depend on how the model cuts time)."""
        t = np.asarray(t, float)
        if self.forces is not None:
            normal, tangential = self.forces(t)
            normal, tangential = np.maximum(normal, 0.0), np.asarray(tangential, float)
        else:
            normal = np.maximum(np.asarray(self.normal_N(t), float), 0.0)
            tangential = self.tangential_per_normal * normal
        if np.isfinite(self.start_s) or np.isfinite(self.end_s):
            inside = (t >= self.start_s) & (t <= self.end_s)
            normal, tangential = np.where(inside, normal, 0.0), np.where(inside, tangential, 0.0)
        return normal, tangential

    def resting_load_N(self) -> float:
        """The normal force (N) held before t = 0 (a contact loaded at t = 0 has been forever); none for a contact
        whose window does not hold t = 0."""
        if not self.start_s <= 0.0 <= self.end_s:
            return 0.0
        return float(np.maximum(np.asarray(self.normal_N(np.array([0.0])), float), 0.0)[0])


SKIN_BASE_X_MM = -20.0  # the skin is clamped to the core this far behind the tip's centre (wetted length ~25 mm)
GAP_TRUNCATION = 2.0  # resting-gap offsets are drawn from a normal truncated at ±2 spreads (see resting_gaps_mm)


def resting_gaps_mm(p: SensorParams, n: int) -> np.ndarray:
    """(n,) resting fluid gap over each electrode, mm.

    gap_i = resting_gap_mm + electrode_gap_spread_mm · z_i, z_i a standard normal truncated to ±2 (a skin or core
    moulded further off is rejected: its skin would rest on an electrode), drawn from ``electrode_gap_seed`` in
    electrode order (the first 19 of a 24-electrode draw are the 19-electrode draw), and clipped physically to at
    least twice ``minimum_gap_mm`` (a resting skin stays clear of where it bottoms).  Spread 0: all nominal.
    """
    seed = p.electrode_gap_seed
    if isinstance(seed, bool) or not float(seed).is_integer() or not 0 <= seed <= 2**31 - 1:
        raise ValueError(f"sensor.electrode_gap_seed = {seed!r}: must be a whole number (0 to {2**31 - 1})")
    g = np.full(n, float(p.resting_gap_mm))
    if p.electrode_gap_spread_mm == 0.0:
        return g
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0x6A9]))  # the gap stream of this seed
    lo, hi = special.ndtr(-GAP_TRUNCATION), special.ndtr(GAP_TRUNCATION)
    z = special.ndtri(lo + (hi - lo) * rng.random(n))  # inverse CDF: a truncated normal, one draw per electrode
    return np.maximum(g + p.electrode_gap_spread_mm * z, 2.0 * p.minimum_gap_mm)


@lru_cache(maxsize=8)
def free_skin_grid(half_angle_deg: float, step_mm: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Points (M, 3) and areas (M,) of the free (untethered) skin, mm and mm².

    The wetted skin covers the cylinder x ∈ [SKIN_BASE_X_MM, 0] and the hemispherical tip x > 0 (radius
    CORE_RADIUS_MM); it is tethered at the nail on the dorsal side, so only points within ``half_angle_deg`` of
    the ventral midline (angle from −z toward ±y) are free to move.
    """
    r, half = CORE_RADIUS_MM, np.radians(half_angle_deg)
    nth = max(4, int(np.ceil(2 * half * r / step_mm)))
    th = -half + (np.arange(nth) + 0.5) * (2 * half / nth)
    nx = int(np.ceil(-SKIN_BASE_X_MM / step_mm))
    x = SKIN_BASE_X_MM + (np.arange(nx) + 0.5) * (-SKIN_BASE_X_MM / nx)
    X, T = np.meshgrid(x, th, indexing="ij")
    cyl = np.column_stack([X.ravel(), r * np.sin(T.ravel()), -r * np.cos(T.ravel())])
    cyl_a = np.full(cyl.shape[0], (-SKIN_BASE_X_MM / nx) * r * (2 * half / nth))
    nphi = max(2, int(np.ceil(0.5 * np.pi * r / step_mm)))
    phi = (np.arange(nphi) + 0.5) * (0.5 * np.pi / nphi)  # polar angle from the +x axis
    P, T = np.meshgrid(phi, th, indexing="ij")
    tip = np.column_stack([r * np.cos(P.ravel()), r * np.sin(P.ravel()) * np.sin(T.ravel()),
                           -r * np.sin(P.ravel()) * np.cos(T.ravel())])
    tip_a = r * r * np.sin(P.ravel()) * (0.5 * np.pi / nphi) * (2 * half / nth)
    return np.vstack([cyl, tip]), np.concatenate([cyl_a, tip_a])


def indentation_profile(d2_mm2, w_mm: float, ratio: float, kappa: float = 1.0):
    """Gap change per mm of indentation depth at squared distance ``d2_mm2`` (mm²) from a contact's centre, 1.

    −exp(−d²/2w²) (the indentation, width w) + κ·(d²/2s²)·exp(−d²/2s²) (the rim bulge, a ring of width
    s = ratio·w peaking at d = √2·s); κ makes the two volumes equal on the free skin (κ = 1 on a plane).
    """
    u = d2_mm2 / (2.0 * w_mm * w_mm)
    us = u / (ratio * ratio)
    return -np.exp(-u) + kappa * us * np.exp(-us)


def bulge_balance(p: SensorParams, center_mm, w_mm: float) -> float:
    """κ: the rim bulge's amplitude that puts back on the free skin the volume the indentation displaced, 1
    (remembered per parameters, centre and width: a rig builds a sensor per trial)."""
    return _bulge_balance(p, tuple(float(c) for c in np.asarray(center_mm, float)), float(w_mm))


@lru_cache(maxsize=256)
def _bulge_balance(p: SensorParams, center_mm: tuple, w_mm: float) -> float:
    pts, area = free_skin_grid(float(p.free_skin_half_angle_deg))
    d2 = ((pts - np.asarray(center_mm, float)[None, :]) ** 2).sum(axis=1)
    u = d2 / (2.0 * w_mm * w_mm)
    us = u / p.bulge_width_ratio**2
    v_in, v_ring = (area * np.exp(-u)).sum(), (area * us * np.exp(-us)).sum()
    return float(v_in / v_ring) if v_ring > 0 else 0.0


def indentation_fraction(p: SensorParams, force_N) -> np.ndarray:
    """a(F) = 1 − exp(−F/F₀): the static share of the available gap a normal force F (N) squeezes out, 1."""
    return 1.0 - np.exp(-np.asarray(force_N, float) / p.indentation_force_N)


class Footprint:
    """One contact seen from the electrodes: what of :func:`electrode_gaps_mm` does not change while it presses.

    ``d2`` (N,) squared distance from each electrode to the contact's resting centre, mm²; ``along`` (N,) each
    electrode's offset along the shear direction, mm; ``w2`` the indentation's squared width, mm²; ``ring_amp``
    (g₀ − g_min)·κ, mm (κ: ``kappa``, default :func:`bulge_balance`).
    """

    def __init__(self, p: SensorParams, c: Contact, positions: np.ndarray, kappa: float | None = None):
        self.w2 = c.indenter_radius_mm**2 + p.skin_spread_mm**2
        if kappa is None:
            kappa = bulge_balance(p, c.center_mm, np.sqrt(self.w2))
        self.ring_amp = (p.resting_gap_mm - p.minimum_gap_mm) * kappa
        rel = positions - c.center_mm[None, :]
        self.along = rel @ np.asarray(c.shear_direction, float)
        self.d2 = (rel * rel).sum(axis=1)
        self.shift_mm_per_N, self.ratio = p.shear_shift_mm_per_N, p.bulge_width_ratio
        self._unshifted = None
        self._shifted = None  # (shift mm, (dent, ring) (1, N)) of the last steady shear

    def shapes(self, tangential_N: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The dent exp(−u) and the ring u_s·exp(−u_s) over every electrode, (T, N) each (1): u = d²/2w²,
        u_s = u/ratio², the centre shifted along the shear by ``shear_shift_mm_per_N``·F_t (``tangential_N``, N, one
        per sample).  T = 1 (computed once per contact) while the centre does not move, else one row per sample."""
        s_mm = self.shift_mm_per_N * tangential_N
        if not s_mm.any():  # |p − c₀|² exactly: the shifted formula below adds only zeros
            if self._unshifted is None:
                self._unshifted = self._dent_and_ring(self.d2[None, :])
            return self._unshifted
        if s_mm[0] == s_mm[-1] and (s_mm == s_mm[0]).all():  # a steady shear: every row would be the same row
            if self._shifted is None or self._shifted[0] != s_mm[0]:
                self._shifted = (s_mm[0], self._shifted_shapes(s_mm[:1]))
            return self._shifted[1]
        starts = np.flatnonzero(np.concatenate(([True], s_mm[1:] != s_mm[:-1])))  # runs of one shift
        if 4 * starts.size < s_mm.size:  # mostly held (the finger still, the stage cruising): one row per run
            lengths = np.diff(np.append(starts, s_mm.size))
            return tuple(np.repeat(x, lengths, axis=0) for x in self._shifted_shapes(s_mm[starts]))
        return self._shifted_shapes(s_mm)

    def _shifted_shapes(self, s_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # the centre moves along the shear direction u by s(t): |p − c₀ − s·u|² = |p − c₀|² − 2s (p − c₀)·u + s²
        return self._dent_and_ring(self.d2[None, :] - 2 * np.outer(s_mm, self.along) + (s_mm * s_mm)[:, None])

    def _dent_and_ring(self, d2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = d2 / (2 * self.w2)
        us = u / self.ratio**2
        return np.exp(-u), us * np.exp(-us)


def _contact_gaps_mm(p: SensorParams, rest_mm: np.ndarray, terms: list, n: int) -> np.ndarray:
    """(n, N) gaps over the electrodes, mm, from their resting gaps ``rest_mm`` (N,) and the pressing contacts'
    ``terms``: (a (n,), ring_amp mm, dent (T, N), ring (T, N)) each (see :class:`Footprint`), in contact order.

    gap = max(g_i − (g₀ − g_min)·Σ_c a_c·dent_c + Σ_c (ring_amp_c·a_c)·ring_c, g_min): the law of
    :func:`electrode_gaps_mm`, worked in place (the same operations, in the same order, as on fresh arrays)."""
    depth, gmin = p.resting_gap_mm - p.minimum_gap_mm, p.minimum_gap_mm
    if not terms:  # rest − depth·0 + 0: the resting gaps exactly
        return np.maximum(np.broadcast_to(rest_mm, (n, rest_mm.size)), gmin)
    frac = bulge = None
    for a, ring_amp, dent, ring in terms:
        f, b = a[:, None] * dent, (ring_amp * a)[:, None] * ring
        frac = f if frac is None else np.add(frac, f, out=frac)
        bulge = b if bulge is None else np.add(bulge, b, out=bulge)
    g = np.multiply(depth, frac, out=frac)
    g = np.subtract(rest_mm[None, :], g, out=g)  # the skin moves by the same depth over any gap ...
    g = np.add(g, bulge, out=g)
    return np.maximum(g, gmin, out=g)  # ... and stops on the core


def _volts_in_place(p: SensorParams, gaps_mm: np.ndarray, open_idx, short_idx) -> np.ndarray:
    """Overwrite ``gaps_mm`` (..., N), mm, with the peak voltage on the load, V, and return it:
    Z = Z_series + ρ_sheet/gap (∞ on the electrodes ``open_idx``, 0 on ``short_idx``: 0-based indices, the short
    last), V = 3.3·R_load/(Z + R_load)."""
    z = np.divide(p.fluid_sheet_ohm_mm, gaps_mm, out=gaps_mm)
    z = np.add(p.electrode_series_ohm, z, out=z)
    if open_idx:
        z[..., open_idx] = np.inf
    if short_idx:
        z[..., short_idx] = 0.0
    z = np.add(z, p.electrode_load_ohm, out=z)
    if not (open_idx or short_idx):  # every Z finite and > 0: nothing for np.errstate to silence (same numbers)
        return np.divide(3.3 * p.electrode_load_ohm, z, out=z)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.divide(3.3 * p.electrode_load_ohm, z, out=z)


@njit(cache=True)
def _add_term(a, ring_amp, dent, ring, frac, bulge, first):  # pragma: no cover - compiled
    """frac += a·dent and bulge += (ring_amp·a)·ring over (n, N) (``first``: set them), ``dent``/``ring`` of one row
    or n: :func:`_contact_gaps_mm`'s per-contact products and sums, the same operations element by element."""
    n, m = frac.shape
    for i in range(n):
        r = i if dent.shape[0] > 1 else 0
        ai, bi = a[i], ring_amp * a[i]
        for j in range(m):
            f, b = ai * dent[r, j], bi * ring[r, j]
            if first:
                frac[i, j], bulge[i, j] = f, b
            else:
                frac[i, j] += f
                bulge[i, j] += b


@njit(cache=True, error_model="numpy")
def _gaps_to_volts(frac, bulge, rest_mm, lost, depth, gmin, sheet, series, load, is_open, is_short,
                   v33_load):  # pragma: no cover - compiled
    """:func:`_contact_gaps_mm`'s gaps from the summed terms, each resting gap thinned by the share of its fluid a
    leaking finger has lost (``lost`` (n,), 1: 0 without a leak, and g − 0 is g to the bit), then
    :func:`_volts_in_place`, in place in ``frac``: the same operations element by element (max as np.maximum, NaN
    kept; an open electrode's Z infinite, a shorted one's 0, the short last)."""
    n, m = frac.shape
    for i in range(n):
        for j in range(m):
            g = rest_mm[j] - depth * frac[i, j]
            g = g - rest_mm[j] * lost[i]
            g = g + bulge[i, j]
            g = gmin if g < gmin else g
            z = series + sheet / g
            if is_open[j]:
                z = np.inf
            if is_short[j]:
                z = 0.0
            frac[i, j] = v33_load / (z + load)
    return frac


def _contact_volts(p: SensorParams, rest_mm: np.ndarray, terms: list, n: int, open_idx, short_idx,
                   lost: np.ndarray | None = None) -> np.ndarray:
    """``_volts_in_place(p, _contact_gaps_mm(p, rest_mm, terms, n), open_idx, short_idx)`` (n, N), V, in two
    compiled passes (the same bits, tested, with no term too; a third of the time, and no slow broadcasting of a
    one-row dent); a leaking finger's resting gaps thinned by the share of its fluid lost, ``lost`` (n,), each step."""
    m = rest_mm.size
    frac, bulge = (np.empty((n, m)), np.empty((n, m))) if terms else (np.zeros((n, m)), np.zeros((n, m)))
    for k, (a, ring_amp, dent, ring) in enumerate(terms):
        _add_term(np.ascontiguousarray(a, dtype=float), float(ring_amp), np.ascontiguousarray(dent, dtype=float),
                  np.ascontiguousarray(ring, dtype=float), frac, bulge, k == 0)
    is_open, is_short = np.zeros(m, bool), np.zeros(m, bool)
    is_open[list(open_idx)], is_short[list(short_idx)] = True, True
    lost = np.zeros(n) if lost is None else np.ascontiguousarray(lost, dtype=float)
    return _gaps_to_volts(frac, bulge, np.asarray(rest_mm, float), lost, p.resting_gap_mm - p.minimum_gap_mm,
                          p.minimum_gap_mm, p.fluid_sheet_ohm_mm, p.electrode_series_ohm, p.electrode_load_ohm,
                          is_open, is_short, 3.3 * p.electrode_load_ohm)


def _fault_indices(faults: dict | None) -> tuple[list[int], list[int]]:
    """0-based indices of the open and of the shorted electrodes of a fault dict numbering them 1..N."""
    faults = faults or {}
    return ([int(n) - 1 for n in faults.get("electrode_open", ())],
            [int(n) - 1 for n in faults.get("electrode_short", ())])


def electrode_gaps_mm(p: SensorParams, contacts: list[Contact], t: np.ndarray, positions: np.ndarray,
                      rest_mm: np.ndarray | None = None, fractions: list | None = None,
                      kappas: list | None = None) -> np.ndarray:
    """(len(t), N) fluid thickness over every electrode (``positions`` (N, 3), mm), mm.

    ``rest_mm`` : (N,) resting gaps (default :func:`resting_gaps_mm`).  Each contact moves the skin toward the
    core by δ₀·exp(−d²/2w²) over electrode i, δ₀ = (g₀ − g_min)·a(F), a(F) = 1 − exp(−F/F₀), g₀ the nominal resting
    gap — a displacement, the same whatever the fluid under it — and raises it by the rim bulge
    κ·δ₀·(d²/2s²)·exp(−d²/2s²): the displaced liquid, put back near the rim.  Where the fluid is thinner than the
    dent the skin stops on the core (g_min): a thin-gap electrode bottoms under a lighter press.
    ``fractions`` : per contact, a(t) to use instead of the static a(F(t)) (the creeping skin), or None;
    ``kappas`` : per contact, its :func:`bulge_balance` if already known.
    """
    rest = resting_gaps_mm(p, positions.shape[0]) if rest_mm is None else np.asarray(rest_mm, float)
    terms = []
    for i, c in enumerate(contacts):
        a = None if fractions is None else fractions[i]
        if a is None:
            if c.end_s < t[0] or c.start_s > t[-1]:
                continue
            a = indentation_fraction(p, c.state(t)[0])  # bounded: bottoms at g_min
        if not a.any():
            continue
        fp = Footprint(p, c, positions, None if kappas is None else kappas[i])
        terms.append((np.broadcast_to(a, t.shape), fp.ring_amp, *fp.shapes(c.state(t)[1])))
    return _contact_gaps_mm(p, rest, terms, t.size)


def electrode_volts(p: SensorParams, gaps_mm: np.ndarray, faults: dict | None = None) -> np.ndarray:
    """Peak voltage on the load for each gap (mm), with open/shorted electrode faults."""
    v = _volts_in_place(p, np.array(gaps_mm, float), *_fault_indices(faults))
    return np.nan_to_num(v, nan=0.0)


def _whole_in(e, n: int) -> bool:
    return (not isinstance(e, bool) and isinstance(e, (int, float, np.integer, np.floating))
            and float(e).is_integer() and 1 <= e <= n)


def _check_faults(faults: dict, n: int) -> None:
    """Refuse electrode fault numbers outside 1..n, naming the fault and the value."""
    for key in ("electrode_open", "electrode_short"):
        for e in faults.get(key, ()):
            if not _whole_in(e, n):
                raise ValueError(f"faults.{key}: electrode {e!r} is not a whole number in 1..{n}")
    stuck = faults.get("mux_stuck")
    if stuck is not None and not _whole_in(stuck, n):
        raise ValueError(f"faults.mux_stuck: electrode {stuck!r} is not a whole number in 1..{n}")


class ElectrodeModel:
    """Serves E1..EN voltages at conversion instants, the multiplexer's memory included.

    ``positions`` : (N, 3) electrode positions on the core, mm (default: the 19 of fixtures/electrodes.csv;
    the BioTac SP passes its 24).  Fault dicts number electrodes 1..N.  ``leak`` (:class:`emulator.mechanics.
    FluidLeak`): each resting gap thins with the share of the fluid lost, down to the core when the finger is empty.
    """

    def __init__(self, p: SensorParams, contacts: list[Contact], faults: dict | None = None,
                 discretization: str = "prewarped", rate_Hz: float = 500.0, *, positions=None, leak=None):
        self.p, self.contacts, self.faults, self.leak = p, contacts, faults or {}, leak
        self.positions = electrode_positions_mm() if positions is None else np.asarray(positions, float)
        if self.positions.ndim != 2 or self.positions.shape[1] != 3 or self.positions.shape[0] < 1:
            raise ValueError(f"electrode positions: shape {self.positions.shape}, expected (N, 3) in mm with N >= 1")
        if not np.all(np.isfinite(self.positions)):
            raise ValueError("electrode positions: every coordinate must be a finite number of mm")
        self.n = n = self.positions.shape[0]
        _check_faults(self.faults, n)
        self.dt = 1.0 / rate_Hz
        self.chunk = max(1, int(round(CHUNK_S * rate_Hz)))
        z, pz, k = np.array([]), np.array([-2 * np.pi * p.electrode_bandwidth_Hz]), 2 * np.pi * p.electrode_bandwidth_Hz
        sos = filters.discretize(z, pz, k, rate_Hz, discretization)
        # a first-order section (b2 = a2 = 0) runs as 2 taps: the third tap's state stays 0 and adds only zeros,
        # so the output is the same to the last bit, for a third less time (as filters.SosFilter does)
        taps = 2 if sos[0, 2] == 0.0 and sos[0, 5] == 0.0 else 3
        self.b, self.a = sos[0, :taps].copy(), sos[0, 3:3 + taps].copy()
        self.rest_gaps_mm = resting_gaps_mm(p, n)
        rest = electrode_volts(p, self.rest_gaps_mm[None, :], self.faults)[0]
        self.rest = rest
        self.zi = filters.sosfilt_zi(sos[:1])[0, :taps - 1, None] * rest[None, :]
        self.zi_rest = self.zi.copy()
        self.k = 0
        self._hist_t = [np.array([0.0])]
        self._hist = [rest[None, :].copy()]
        a = np.exp(-p.mux_acquisition_s / p.mux_settling_s)
        self.mux_keep = a  # fraction of the previous electrode's value left in a sample
        self.mux_injection = a * p.mux_injection_V
        self.mux_node = float(rest[0])
        self.stuck = self.faults.get("mux_stuck")  # electrode number the multiplexer is stuck on
        # the skin creeps under a held force (standard linear solid with the fluid in parallel, as for PDC): each
        # contact's force goes through its own creep filter (state carried across chunks) before the depth law,
        # so the compliance creeps while the bottoming on the core stays a hard, instantaneous limit
        sf = skin_fluid(p)
        self.creep_time_s, self.creep_ratio = sf.creep_time_s, sf.creep_ratio
        self.creeps = [Creep.standard_linear_solid(sf.creep_time_s, sf.creep_ratio) for _ in contacts]
        for c, cr in zip(contacts, self.creeps):
            cr.settle(c.resting_load_N())
        self.rate_Hz = rate_Hz
        if any(c.forces is not None and c.planned for c in contacts):
            raise ValueError("a contact whose forces come from the grid cannot be planned in advance")
        # compute no further than asked: commands are still coming, or the grid has not run beyond
        self.lazy = not all(c.planned for c in contacts)
        self.kappas = [bulge_balance(p, c.center_mm, float(np.hypot(c.indenter_radius_mm, p.skin_spread_mm)))
                       for c in contacts]
        self.footprints = [Footprint(p, c, self.positions, k) for c, k in zip(contacts, self.kappas)]
        self._open, self._short = _fault_indices(self.faults)
        # a contact loaded before t = 0 has been forever (its creep is settled above): the electrodes, their filter
        # and the hold node start on its pattern, not at rest (no start-up transient, as for the bridge)
        held = [(c, cr.last, fp) for c, cr, fp in zip(contacts, self.creeps, self.footprints) if cr.last > 0.0]
        if held:
            terms = [(indentation_fraction(p, np.array([f0])), fp.ring_amp,
                      *fp.shapes(np.array([0.0 if c.forces is not None else c.tangential_per_normal * f0])))
                     for c, f0, fp in held]
            start = _contact_volts(p, self.rest_gaps_mm, terms, 1, self._open, self._short)[0]
            self.zi = filters.sosfilt_zi(sos[:1])[0, :taps - 1, None] * start[None, :]
            self._hist = [start[None, :].copy()]
            self.mux_node = float(start[0])

    def _advance_chunk(self, n: int | None = None):
        """Advance ``n`` samples (default: a whole chunk); results do not depend on how the time is cut.

        A contact outside [start_s, end_s] exerts no force (see :class:`Contact`): while its skin creeps back
        it has neither normal nor tangential force."""
        n = self.chunk if n is None else n
        t = (self.k + 1 + np.arange(n)) * self.dt
        active = False
        terms = []
        first, last = float(t[0]), float(t[-1])
        for c, cr, fp in zip(self.contacts, self.creeps, self.footprints):
            touching = c.end_s >= first and c.start_s <= last
            if not touching and cr.last == 0.0 and all(abs(x) < 1e-9 for x in cr.state.tolist()):  # N: no trace
                cr.state[:] = 0.0  # released and recovered: nothing left to creep back
                continue
            active = True
            f, ft = c.state(t) if touching else (np.zeros(t.size), np.zeros(t.size))
            a = indentation_fraction(self.p, np.maximum(cr.step(f, self.rate_Hz), 0.0))
            if a.any():  # a contact whose dent is nil moves no electrode
                terms.append((a, fp.ring_amp, *fp.shapes(ft)))
        lost = self._fluid_lost(t)
        if not active and lost is None and np.abs(self.zi - self.zi_rest).max() <= 1e-12:
            y = np.broadcast_to(self.rest, (n, self.n))  # nothing touching and the filter settled: rest
        else:  # (the gaps stay ≥ g_min > 0: the voltages are finite, electrode_volts' NaN guard is not needed)
            v = _contact_volts(self.p, self.rest_gaps_mm, terms, n, self._open, self._short, lost)
            y, self.zi = filters.lfilter(self.b, self.a, v, self.zi, axis=0)
        self.k += n
        self._hist_t.append(t)
        self._hist.append(y)

    def _fluid_lost(self, t: np.ndarray) -> np.ndarray | None:
        """The share (1) of its fluid a leaking finger has lost at instants ``t`` (s): every resting gap thins by it
        (the fluid layer in proportion to the volume, as the mean layer is volume / wetted area); None while nothing
        has leaked."""
        if self.leak is None or t[-1] <= self.leak.start_s:
            return None
        v0 = self.p.inflation_volume_mL
        return 1.0 - self.leak.volume_mL(v0, t) / v0

    def _steps_through(self, t_last: float) -> int:
        """How many steps a lazy model has computed once asked for instants up to ``t_last`` (s): through the first
        step at or after it, not beyond."""
        steps = max(self.k, int(np.ceil(t_last / self.dt - 1e-9)))
        while steps * self.dt < t_last:  # (the step's instant as the history holds it)
            steps += 1
        return steps

    def grid_needed(self, t_last: float) -> int:
        """The last grid sample (index) the contacts fed from the grid (``Contact.forces``) need before the model
        serves instants up to ``t_last`` (s); -1 if none does.  The sensor runs its grid that far first."""
        fed = [c.forces for c in self.contacts if c.forces is not None]
        if not fed:
            return -1
        t_end = self._steps_through(t_last) * self.dt  # (a model with a fed contact is lazy)
        return max(f.last_grid_index(t_end) for f in fed)

    def targets(self, electrode: np.ndarray, times: np.ndarray) -> np.ndarray:
        """Settled voltage of electrode n (1..N) at each instant (no multiplexer memory)."""
        if times.size == 0:
            return np.zeros(0)
        if not self.contacts and self.leak is None:  # nothing ever touches: every electrode rests (the shortcut)
            return self.rest[electrode - 1]
        t_first, t_last = float(times.min()), float(times.max())
        while self._hist_t[-1][-1] < t_last:
            if self.lazy:  # through the first sample at or after the latest instant asked for, not beyond
                self._advance_chunk(max(1, self._steps_through(t_last) - self.k))
            else:
                self._advance_chunk()
        if len(self._hist_t) > 1:
            self._hist_t, self._hist = [np.concatenate(self._hist_t)], [np.vstack(self._hist)]
        ht, hv = self._hist_t[0], self._hist[0]
        if t_first < ht[0] - 1e-12:
            raise ValueError(f"electrode instant {t_first:.6f} s is older than the electrode history")
        idx = np.searchsorted(ht, times, side="right") - 1
        idx = np.minimum(np.maximum(idx, 0), len(ht) - 2)  # np.clip's result, without its overhead
        frac = (times - ht[idx]) / self.dt
        flat, cols = hv.ravel(), electrode - 1  # row idx, column col of hv at idx·N + col of its C-order values
        lo, hi = flat[idx * self.n + cols], flat[(idx + 1) * self.n + cols]
        keep = max(0, int(np.searchsorted(ht, t_last, side="right")) - 2)  # history still needed
        self._hist_t, self._hist = [ht[keep:]], [hv[keep:]]
        return lo + (hi - lo) * frac

    def sample(self, electrode: np.ndarray, times: np.ndarray) -> np.ndarray:
        """Voltages the ADC sees for electrode conversions in the order given (multiplexer memory applied)."""
        electrode = np.asarray(electrode, dtype=np.int64)
        if times.size == 0:
            return np.zeros(0)
        if self.stuck is not None:
            electrode = np.full_like(electrode, int(self.stuck))
        if electrode.min() < 1 or electrode.max() > self.n:
            raise ValueError(f"electrode numbers {electrode.min()}..{electrode.max()}: this sensor has E1..E{self.n}")
        target = self.targets(electrode, np.asarray(times, float))
        # hold node: x_k = (1 − a)·target_k + a·(x_{k−1} + injection), a first-order recursion over conversions,
        # between 0 V and the supply rail
        a = self.mux_keep
        y = _hold_node((1 - a) * target + self.mux_injection, a, self.mux_node, self.p.supply_rail_V)
        self.mux_node = float(y[-1])
        return y


@njit(cache=True)
def _hold_node(u, a, x0, rail):  # pragma: no cover - compiled
    """The multiplexer's hold node over conversions: x_k = a·x_{k−1} + u_k from x_{−1} = ``x0`` (V), as lfilter
    computes it (the same bits), held between 0 V and ``rail`` (V): charge injected at every switch, with too short
    an acquisition to settle (mux_acquisition_s ≪ mux_settling_s), once piled up past 3.3 V at the ADC input."""
    x = np.empty(u.size)
    prev = x0
    for k in range(u.size):
        v = a * prev + u[k]
        v = 0.0 if v < 0.0 else (rail if v > rail else v)
        x[k] = v
        prev = v
    return x


def electrode_number(channel) -> np.ndarray:
    """Electrode number (1 for E1 … 19 for E19) of electrode channel index(es)."""
    return np.asarray(channel) - ELECTRODE_FIRST + 1
