"""Sliding over a texture: the motions that press and slide, and the effect that turns them into forces.

Data flow (per block, state carried): texture + skin → spatial tables along the track (patch-averaged height,
ridge-sampled slope, one row per patch radius) → :func:`emulator.friction.slide_block` (LuGre stick-slip
against the compliant skin, texture position advanced by the slip) → ``contact_force_N`` (normal load with
its fluctuations, plus the tangential force's share of fluid pressure) and ``tangential_force_N`` (for the
stage's motor current and plots) and ``normal_force_N`` (the true normal load, for checking force control).
``contact_force_N`` then takes the existing path: force → fluid pressure → resonance → bridge → front end → codes.
The electrodes read each motion's normal and tangential force through a :class:`ForceFeed` (the mean over each
electrode period), so they feel the friction's shear: none while the stage holds still, its ramp, stick-slip and
fluctuations once it moves.

The tables cover the motion's whole travel when it is short (:data:`TABLE_WHOLE_MAX` positions); a long slide's
are held as a ring of tiles around the finger, computed as the stage reaches them, so memory does not grow with the
travel (:meth:`SlidingContact._centre_ring`).

The friction coefficient fluctuates with the slip distance, µ → µ·(1 + ε(p)) (:func:`emulator.texture.
friction_fluctuation`: 3 % RMS, power ∝ 1/q between 20 µm and 10 mm, on every texture): the micro stick-slip
and junction turnover of skin sliding on any surface, smooth ones included.  It is a table along the track like
the heights, read in the compiled step at the texture position, so it moves only while the skin slips.

The texture under the finger is seen through the contact patch (radius ``a = a_1N·N^(1/3)``): heights are
averaged with the Hertz line load ``∝ 1 − x²/a²`` (a spatial low-pass: coarse features pass, fine ones fade
as force grows); fingerprint ridges sample the surface slope at the ridge pitch under the same load, each ridge
crest seeing the surface through its contact width — a comb that folds fine texture into vibrations at
``v/pitch`` and its harmonics.  A smooth skin sees only the patch-averaged slope.  Worn ridges interpolate
between the two by the skin's ridge gain (:mod:`emulator.skin`).  That comb is the *effective* ridge model (rigid
ridges, a slope table).  The *resolved* one (``ridges="resolved"``, the reference profile) keeps only the patch part
in the table and makes each ridge under the patch a compliant element that catches and releases (its crest slope
read from :func:`crest_table`, its stiffness :meth:`emulator.skin.Skin.ridge_stiffness_per_length` × its chord;
:class:`emulator.friction.Ridges`); :meth:`SlidingContact.ridge_releases` logs its release events.

Two kinds of motion: :class:`Slide` (scripted: force ramp, hold, slide at a velocity over a distance, lift;
force-controlled) and :class:`CommandedMotion` (a rig's stepper and stage commands added while the run goes,
position-controlled: the normal load follows from the finger's indentation through the contact law).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np
from numba import njit
from scipy import fft as scipy_fft

from emulator import filters, friction
from emulator.effects import Block, Effect, effect_rng
from emulator.fidelity import RIDGE_MODELS
from emulator.params import SensorParams
from emulator.skin import Skin
from emulator.texture import SURFACE_LENGTH_M, Texture, friction_fluctuation, periodic_on_grid, random_profile

POISSON_RATIO = 0.3  # of texture materials, for E/(1 − ν²) (model choice; 0.5 for rubbers changes it by 20 %)
#: a commanded motion's load is not known when its contact is built (the rig sends its commands as it goes): its
#: patch-radius table reaches 2.5 × this (N; the rig's targets are at most 2 N)
COMMANDED_FORCE_MAX_N = 5.0
#: textures are layers on the rig's rigid backing: a soft one compresses at most this much (it densifies as it
#: approaches its thickness), so a finger always reaches a force (model choice: the library has no thickness)
TEXTURE_LAYER_M = 3e-3
#: A track's tables (patch-averaged heights and ridge slopes per patch radius, the friction's fluctuation) are
#: computed whole when they hold at most this many positions (1.3 m at the default 10 µm, 0.33 m at the reference
#: 2.5 µm): a slide's whole travel, as they always were.  A longer track (a long slide) is held as a ring of
#: RING_TILES tiles of TABLE_TILE positions centred on the finger, a tile computed as the stage reaches it, so the
#: memory is bounded by the ring (12.6 MB at default, 25 MB at reference), not the travel.
TABLE_WHOLE_MAX = 2**17
TABLE_TILE = 2**15
RING_TILES = 3
#: the finger is kept this far inside the ring's ends (within one grid step the skin moves tens of microns)
RING_MARGIN_M = 0.01


@dataclass
class Slide:
    """A scripted sliding trial, force-controlled: the normal force ramps to ``force_N`` over ``approach_s``,
    holds ``hold_s``, the stage slides the texture at ``velocity_m_per_s`` over ``distance_m`` (accelerating
    over ``accel_s``), then the finger lifts over ``lift_s``.  ``start_position_m`` is where on the texture the
    finger lands."""

    start_s: float
    texture: Texture
    force_N: float
    velocity_m_per_s: float
    distance_m: float
    approach_s: float = 0.3
    hold_s: float = 0.5
    accel_s: float = 0.05
    lift_s: float = 0.2
    start_position_m: float = 0.0
    skin: Skin | None = None

    def __post_init__(self):
        for name in ("force_N", "velocity_m_per_s", "distance_m", "approach_s", "accel_s", "lift_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"slide.{name} = {v!r}: must be a positive number")
        if self.distance_m < self.velocity_m_per_s * self.accel_s:
            raise ValueError(f"slide.distance_m = {self.distance_m!r}: shorter than the acceleration and braking "
                             f"({self.velocity_m_per_s * self.accel_s:.4g} m at this velocity)")

    @property
    def slide_start_s(self) -> float:
        return self.start_s + self.approach_s + self.hold_s

    @property
    def slide_end_s(self) -> float:
        return self.slide_start_s + self.distance_m / self.velocity_m_per_s + self.accel_s

    @property
    def end_s(self) -> float:
        return self.slide_end_s + self.lift_s

    @property
    def max_travel_m(self) -> float:
        return self.distance_m

    def normal_force_N(self, t: np.ndarray) -> np.ndarray:
        """Nominal normal force (N): raised-cosine ramps up and down, held in between."""
        t = np.asarray(t, float)
        up = np.clip((t - self.start_s) / self.approach_s, 0, 1)
        down = np.clip((t - self.slide_end_s) / self.lift_s, 0, 1)
        return self.force_N * (0.5 - 0.5 * np.cos(np.pi * up)) * (0.5 + 0.5 * np.cos(np.pi * down))

    def stage_velocity_m_per_s(self, t: np.ndarray) -> np.ndarray:
        """Stage velocity (m/s): linear ramps of ``accel_s`` at both ends of the slide."""
        t = np.asarray(t, float)
        v, a = self.velocity_m_per_s, self.accel_s
        rise = np.clip((t - self.slide_start_s) / a, 0, 1)
        fall = np.clip((self.slide_end_s - t) / a, 0, 1)
        return v * np.minimum(rise, fall)


@dataclass
class CommandedMotion:
    """Motion commanded while the run goes (a rig's stepper and linear stage), position-controlled.

    The finger's depth below the texture's surface (m, negative above it) and the stage velocity (m/s) are
    piecewise linear in time between commands; a command takes effect ``latency_s`` after it is given (the
    rig's control latency), so the emulator never needs a command it has not yet received.  The normal load is
    the contact law of the indentation: ``N = K·δ^1.5`` for the skin in series with the texture's compliance.
    """

    texture: Texture
    start_position_m: float = 0.0
    max_travel_m: float = 0.2
    latency_s: float = 0.02
    skin: Skin | None = None
    start_s: float = 0.0
    end_s: float = math.inf
    depth_m: float = -1e-3
    _finger: list = field(default_factory=list)  # (t, depth m, depth rate m/s)
    _stage: list = field(default_factory=list)  # (t, velocity m/s, acceleration m/s²)
    _stage_velocity: float = 0.0
    _computed_until_s: float = -math.inf  # latest instant the sensor has already evaluated the motion at
    _column_cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)  # see _columns

    def __post_init__(self):
        self._finger = [(self.start_s, self.depth_m, 0.0)]
        self._stage = [(self.start_s, 0.0, 0.0)]

    def _check_not_past(self, t: float, what: str) -> None:
        """A command must not change the motion at instants the sensor has already computed."""
        if t < self._computed_until_s:
            raise ValueError(f"{what} command takes effect at {t:.6f} s, but the sensor has already computed the "
                             f"motion through {self._computed_until_s:.6f} s: give commands at least the latency "
                             "ahead of what has been read")

    def move_finger(self, t_s: float, rate_m_per_s: float) -> float:
        """From ``t_s`` + latency the finger moves down at ``rate_m_per_s`` (negative: up); returns the instant."""
        t = t_s + self.latency_s
        self._check_not_past(t, "finger")
        t0, d0, r0 = self._finger[-1]
        if t < t0:
            raise ValueError(f"finger command at {t:.6f} s is older than the last one ({t0:.6f} s)")
        self._finger.append((t, d0 + r0 * (t - t0), float(rate_m_per_s)))
        return t

    def move_stage(self, t_s: float, velocity_m_per_s: float, accel_m_per_s2: float = 1.0) -> tuple[float, float]:
        """From ``t_s`` + latency the stage accelerates at ``accel_m_per_s2`` to ``velocity_m_per_s``; returns
        (start, end) of the change."""
        t = t_s + self.latency_s
        self._check_not_past(t, "stage")
        v0 = self._piecewise("stage", np.array([t]))[0]
        dv = float(velocity_m_per_s) - v0
        dur = abs(dv) / accel_m_per_s2
        self._stage.append((t, v0, math.copysign(accel_m_per_s2, dv) if dur > 0 else 0.0))
        self._stage.append((t + dur, float(velocity_m_per_s), 0.0))
        return t, t + dur

    def depth_at(self, t: np.ndarray) -> np.ndarray:
        """Finger depth below the surface (m) at instants ``t`` (s), as the sensor computes them."""
        return self._piecewise("finger", t, computing=True)

    def stage_velocity_m_per_s(self, t: np.ndarray) -> np.ndarray:
        """Stage velocity (m/s) at instants ``t`` (s), as the sensor computes them."""
        return self._piecewise("stage", t, computing=True)

    def planned_depth_at(self, t: np.ndarray) -> np.ndarray:
        """Finger depth (m) the commands given so far plan for instants ``t`` (s): a look ahead that, unlike
        :meth:`depth_at`, does not mark the instants as computed (later commands may still change them)."""
        return self._piecewise("finger", t)

    def _piecewise(self, which: str, t, computing: bool = False) -> np.ndarray:
        """Value of the piecewise-linear segments (start s, value, slope) ``which`` ("finger" or "stage") at ``t``;
        ``computing`` marks instants the sensor has now evaluated (later commands must not reach back before them)."""
        t = np.asarray(t, float)
        out = np.empty(t.shape)
        if t.size == 0:
            return out
        start, value, slope = self._columns(which)
        t_hi = _piecewise_fill(t.reshape(-1), start, value, slope, out.reshape(-1))
        if computing:
            self._computed_until_s = max(self._computed_until_s, t_hi)
        return out

    def _columns(self, which: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The segments ``which`` as three arrays (start s, value, slope), rebuilt only when a command was appended
        (the lists only grow)."""
        segments = self._finger if which == "finger" else self._stage
        cached = self._column_cache.get(which)
        if cached is None or cached[0] != len(segments):
            seg = np.array(segments, dtype=float)
            cached = (len(segments), (seg[:, 0].copy(), seg[:, 1].copy(), seg[:, 2].copy()))
            self._column_cache[which] = cached
        return cached[1]

    def decided_until(self) -> float:
        """Latest instant up to which the motion is fixed by commands already given."""
        return max(self._finger[-1][0], self._stage[-1][0])


@njit(cache=True)
def _piecewise_fill(t, start, value, slope, out):
    """``out[i] = value[k] + slope[k]·(t[i] − start[k])`` with ``k`` the last segment starting at or before ``t[i]``
    (the first for instants before it); returns the latest instant (NaN if any is NaN).  One pass; a time-ordered
    ``t`` (a block) walks the segments forward."""
    n_seg = start.size
    k = 0
    seg_lo, seg_hi = start[0], start[1] if n_seg > 1 else math.inf
    v0, v1 = value[0], slope[0]
    t_hi = -math.inf
    for i in range(t.size):
        ti = t[i]
        if not (seg_lo <= ti < seg_hi):
            if ti != ti:  # NaN: after every segment, as searchsorted puts it
                k = n_seg - 1
            else:  # the last start <= ti (binary search), the first segment before them all
                lo, hi = 0, n_seg
                while lo < hi:
                    mid = (lo + hi) // 2
                    if start[mid] <= ti:
                        lo = mid + 1
                    else:
                        hi = mid
                k = max(lo - 1, 0)
            seg_lo, seg_hi = start[k], start[k + 1] if k + 1 < n_seg else math.inf
            v0, v1 = value[k], slope[k]
            if ti != ti:
                t_hi = ti
        if ti > t_hi:
            t_hi = ti
        out[i] = v0 + v1 * (ti - seg_lo)
    return t_hi

def contact_force_from_depth(depth_m, params: SensorParams, texture: Texture) -> np.ndarray:
    """Normal load (N) at finger depth ``depth_m`` (m): skin (N = K δ_s^1.5) in series with the texture layer,
    δ_t = T·(1 − exp(−N / (k T))) with the flat-punch stiffness k = 2 a E* and the layer thickness T (soft at
    first, densifying toward T), solved on a table and interpolated."""
    table_N, table_depth = _depth_table(params.contact_stiffness_N_per_m1_5, params.contact_radius_at_1N_m,
                                        texture.modulus_Pa)
    d = np.asarray(depth_m, float)
    if d.ndim == 1 and d.size > 1 and d[0] == d[-1] and bool(np.all(d == d[0])):  # a finger held still: one value
        return np.full(d.shape, np.interp(d[0], table_depth, table_N) if d[0] > 0 else 0.0)
    out = np.zeros(d.shape)
    pressed = d > 0
    out[pressed] = np.interp(d[pressed], table_depth, table_N)  # (the finger above the surface: no load)
    return out


def commanded_load_N(motion: CommandedMotion, params: SensorParams, t) -> np.ndarray:
    """Normal load (N) of a commanded finger at instants ``t`` (s) the sensor has reached: the contact law of its
    depth.  Bind it with :func:`functools.partial`, not a closure, so that a copied sensor reads its copied motion.
    (Evaluated piece by piece between the finger's commands, so a piece where the finger holds still costs one
    interpolation; the law is applied element by element, so the values are the same.)"""
    depth = motion.depth_at(t)
    if depth.ndim != 1 or depth.size < 2:
        return contact_force_from_depth(depth, params, motion.texture)
    t = np.asarray(t, float)
    start = motion._columns("finger")[0]
    cuts = np.searchsorted(t, start[(start > t[0]) & (start <= t[-1])], side="left") if t[-1] > t[0] else []
    edges = [0, *(int(c) for c in cuts), depth.size]
    if len(edges) == 2:
        return contact_force_from_depth(depth, params, motion.texture)
    return np.concatenate([contact_force_from_depth(depth[b:e], params, motion.texture)
                           for b, e in zip(edges[:-1], edges[1:])])


@functools.lru_cache(maxsize=64)
def _depth_table(K: float, radius_1N: float, modulus: float):
    N = np.concatenate([[0.0], np.geomspace(1e-5, 50.0, 2000)])
    skin = (N / K) ** (2.0 / 3.0)
    radius = radius_1N * np.cbrt(N)
    k = 2.0 * radius * modulus / (1 - POISSON_RATIO**2)
    texture = TEXTURE_LAYER_M * -np.expm1(-np.divide(N, k * TEXTURE_LAYER_M, out=np.zeros_like(N), where=k > 0))
    return N, skin + texture


@functools.lru_cache(maxsize=32)
def _random_track(texture: Texture, dx_m: float) -> np.ndarray:
    return random_profile(texture, dx_m)


@functools.lru_cache(maxsize=32)
def _fluctuation_track(texture: Texture, dx_m: float) -> np.ndarray:
    return friction_fluctuation(texture, dx_m)


def table_positions(length_m: float, dx_m: float) -> int:
    """How many positions (spacing ``dx_m``) the tables of a track ``length_m`` long hold: ⌈length/dx⌉ + 2."""
    return int(np.ceil(length_m / dx_m)) + 2


def fluctuation_table(texture: Texture, start_m: float, length_m: float, dx_m: float) -> np.ndarray:
    """The friction coefficient's relative fluctuation ε (1) along the track ``[start_m, start_m + length_m)`` at
    the positions of :func:`spatial_tables` (relative to ``start_m``), from the texture's own fluctuation."""
    return fluctuation_stretch(texture, start_m, 0, table_positions(length_m, dx_m), dx_m)


def fluctuation_stretch(texture: Texture, start_m: float, first: int, n: int, dx_m: float) -> np.ndarray:
    """:func:`fluctuation_table`'s positions ``first`` … ``first + n − 1`` (position i at ``start_m + i·dx_m``): the
    same samples, whichever stretch they are asked in."""
    track = _fluctuation_track(texture, dx_m)
    i0 = (int(round(start_m / dx_m)) + first) % track.size
    if i0 + n <= track.size:  # no wrap: a copy of a slice (the same samples)
        return track[i0:i0 + n].copy()
    return np.ascontiguousarray(track[(i0 + np.arange(n)) % track.size])


def spatial_tables(texture: Texture, skin: Skin, ridge_gain: float, start_m: float, length_m: float, dx_m: float,
                   radii_m: np.ndarray, ridge_comb: bool = True):
    """Tables (radius × position) of the patch-averaged height (m) and the slope the skin feels (1) along the
    track ``[start_m, start_m + length_m)``, positions relative to ``start_m``.  ``ridge_comb`` False: the slope
    leaves the ridges out, ``(1 − gain)·s_patch`` (ridge-resolved fingerprints add theirs in the step)."""
    return table_stretch(texture, skin, ridge_gain, start_m, 0, table_positions(length_m, dx_m), dx_m, radii_m,
                         ridge_comb)


def _surface_around(texture: Texture, start_m: float, first: int, n: int, pad: int, dx_m: float) -> np.ndarray:
    """The surface's heights (m) at positions ``first − pad`` … ``first + n + pad − 1`` (position i at ``start_m +
    i·dx_m``): the texture's random track (wrapping past its stored 1 m) plus its periodic components."""
    rough = _random_track(texture, dx_m)
    n_surface = rough.size
    i0 = (int(round(start_m / dx_m)) + first - pad) % n_surface
    if i0 + n + 2 * pad <= n_surface:  # the stretch does not wrap: a slice (the same samples)
        h = rough[i0:i0 + n + 2 * pad]
    else:
        h = rough[(i0 + np.arange(n + 2 * pad)) % n_surface]
    if texture.periodic:  # (positions start_m + i·dx, i from first - pad)
        return h + periodic_on_grid(texture, start_m + (first - pad) * dx_m, dx_m, n + 2 * pad)
    return h + 0.0  # (a fresh array, as the sum with the zero profile made it: -0.0 becomes 0.0 as before)


def _crest_slope(h: np.ndarray, skin: Skin, dx_m: float) -> np.ndarray:
    """The slope (1) a ridge crest feels over heights ``h`` (m, spacing ``dx_m``): the surface seen through the
    crest's contact width (a box average), differentiated (np.gradient)."""
    w_crest = max(1, int(round(skin.ridge_contact_width_m / dx_m)))
    crest = np.convolve(h, np.ones(w_crest) / w_crest, mode="same")
    return np.gradient(crest, dx_m)


def table_stretch(texture: Texture, skin: Skin, ridge_gain: float, start_m: float, first: int, n: int, dx_m: float,
                  radii_m: np.ndarray, ridge_comb: bool = True):
    """:func:`spatial_tables` at positions ``first`` … ``first + n − 1`` (position i at ``start_m + i·dx_m``), computed
    from the surface around them alone (the patch average by one FFT over the stretch and its margins): a whole
    track's tables are the stretch from 0, and a long track is computed stretch by stretch (:data:`TABLE_TILE`)."""
    pad = int(np.ceil((radii_m.max() + skin.ridge_pitch_m) / dx_m)) + 2
    h = _surface_around(texture, start_m, first, n, pad, dx_m)
    # the crest of a ridge sees the surface through its contact width
    crest_slope = _crest_slope(h, skin, dx_m)
    # the patch average at every radius: h convolved with each radius's Hertz line load, at positions
    # pad - 1 .. pad + n (one beyond each end for the slope)
    patch = np.empty((radii_m.size, n + 2))
    for n_fft, rows, spectra in _patch_kernels(tuple(float(a) for a in radii_m), dx_m, h.size):
        full = scipy_fft.irfft(scipy_fft.rfft(h, n_fft) * spectra, n_fft, axis=1)  # the radii of one FFT length
        for row, (k, m) in zip(full, rows):
            patch[k] = row[m + pad - 1:m + pad + n + 1]  # scipy's fftconvolve(h, w, "same") centres by m
    heights = np.ascontiguousarray(patch[:, 1:-1])
    # fingerprint ridges: each radius's ridges under the patch sample the crest slope, weighted by the line load
    weights, shifts = _ridge_weights(tuple(float(a) for a in radii_m), skin.ridge_pitch_m, dx_m)
    if not ridge_comb:  # no ridge enters the sum
        weights = np.zeros_like(weights)
    slopes = np.empty((radii_m.size, n))
    _ridge_slopes(patch, crest_slope, pad, weights, shifts, float(ridge_gain), 2.0 * dx_m, slopes)
    return heights, slopes


@functools.lru_cache(maxsize=8)  # (the movement grid's 6 forces each have their radii; < 1 MB each at default)
def _patch_kernels(radii_m: tuple, dx_m: float, n_signal: int) -> list:
    """Per patch radius ``a`` (m): the half-width m (samples of ``dx_m``) of its Hertz line-load kernel
    ``∝ 1 − x²/a²`` (normalised to sum 1), the FFT length and the kernel's spectrum with which
    :func:`scipy.signal.fftconvolve` convolves it with a signal of ``n_signal`` samples (the same arithmetic, with
    the kernel's spectrum computed once).  Grouped by FFT length: [(length, [(radius index, m), …], spectra
    stacked one row per radius)], in order of first appearance."""
    groups: dict = {}
    for k, a in enumerate(radii_m):
        m = max(1, int(np.floor(a / dx_m)))
        w = np.clip(1.0 - ((np.arange(-m, m + 1) * dx_m) / a) ** 2, 0.0, None)
        w /= w.sum()
        n_fft = scipy_fft.next_fast_len(n_signal + w.size - 1, True)
        groups.setdefault(n_fft, []).append((k, m, scipy_fft.rfftn(w[::-1], [n_fft], axes=[0])))
    return [(n_fft, [(k, m) for k, m, _ in g], np.stack([spectrum for _, _, spectrum in g]))
            for n_fft, g in groups.items()]


@functools.lru_cache(maxsize=16)
def _ridge_weights(radii_m: tuple, pitch_m: float, dx_m: float):
    """Per patch radius, the weights (line load at each ridge under the patch, summing to 1; rows padded with 0) and
    the ridges' offsets (samples of ``dx_m``) for ridges at ``pitch_m``."""
    rows = []
    for a in radii_m:
        j = np.arange(-int(a // pitch_m), int(a // pitch_m) + 1)
        wj = np.clip(1.0 - (j * pitch_m / a) ** 2, 0.0, None)
        wj = wj / wj.sum() if wj.sum() > 0 else np.zeros_like(wj)
        rows.append((wj, [int(round(jj * pitch_m / dx_m)) for jj in j]))
    width = max(len(w) for w, _ in rows)
    weights, shifts = np.zeros((len(rows), width)), np.zeros((len(rows), width), dtype=np.int64)
    for k, (w, sh) in enumerate(rows):
        weights[k, :len(w)], shifts[k, :len(sh)] = w, sh
    return weights, shifts


def ridge_reach(radii_m: np.ndarray, dx_m: float) -> int:
    """How far (positions of ``dx_m``) a ridge under the largest patch (radius, m) lies from its centre, at most."""
    return int(np.ceil(float(np.max(radii_m)) / dx_m)) + 1


def ridge_elements(radii_m: tuple, pitch_m: float, dx_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ridges of the ridge-resolved fingerprint, one column per ridge at ``j·pitch_m`` (j = −J … J, J the most
    the largest patch holds): each patch radius's load shares (radius × ridge, the comb's :func:`_ridge_weights`,
    0 for ridges outside that patch), each ridge's offset in positions of ``dx_m`` and in m."""
    weights, _ = _ridge_weights(radii_m, pitch_m, dx_m)
    most = max(int(a // pitch_m) for a in radii_m)
    aligned = np.zeros((len(radii_m), 2 * most + 1))
    for k, a in enumerate(radii_m):
        held = int(a // pitch_m)  # the row's ridges j = −held … held sit in its first 2·held + 1 columns
        aligned[k, most - held:most + held + 1] = weights[k, :2 * held + 1]
    offsets_m = np.arange(-most, most + 1) * pitch_m
    shifts = np.array([int(round(o / dx_m)) for o in offsets_m], dtype=np.int64)
    return aligned, shifts, offsets_m


def crest_table(texture: Texture, skin: Skin, start_m: float, first: int, n: int, n_track: int, reach: int,
                dx_m: float) -> np.ndarray:
    """The ridge crests' slope (1) for the ridge-resolved step at table indices ``first`` … ``first + n − 1`` of a track
    of ``n_track`` positions (spacing ``dx_m`` from ``start_m``): index q holds position q, except the last
    ``reach`` (:func:`ridge_reach`) indices, which hold the positions just before the track's start (q − n_track),
    where the ridges behind the patch's centre read at first (the step reads the table modulo its length)."""
    out = np.empty(n)
    margin = max(1, int(round(skin.ridge_contact_width_m / dx_m))) + 2  # the box average's and gradient's reach
    ahead = int(np.clip(n_track - reach - first, 0, n))  # indices holding their own position
    for at, position, count in ((0, first, ahead), (ahead, first + ahead - n_track, n - ahead)):
        if count:
            h = _surface_around(texture, start_m, position, count, margin, dx_m)
            out[at:at + count] = _crest_slope(h, skin, dx_m)[margin:margin + count]
    return out


@njit(cache=True)
def _ridge_slopes(patch, crest_slope, pad, weights, shifts, gain, two_dx, out):
    """The slope the skin feels, per radius k and position i: the patch average's central difference
    ``s = (patch[k, i + 2] − patch[k, i]) / two_dx`` (np.gradient's) and the ridges' ``r = Σ_j weights[k, j] ·
    crest_slope[pad + shifts[k, j] + i]`` (in order of j from 0, zero weights skipped) blended as
    ``s + gain·(r − s)``; written to ``out`` (radii × positions)."""
    n = out.shape[1]
    ridged = np.empty(n)
    for k in range(weights.shape[0]):
        ridged[:] = 0.0
        for j in range(weights.shape[1]):
            w = weights[k, j]
            if w == 0.0:
                continue
            shifted = crest_slope[pad + shifts[k, j]:pad + shifts[k, j] + n]  # 1-D views: the loop vectorises
            for i in range(n):
                ridged[i] += w * shifted[i]
        p, row = patch[k], out[k]
        for i in range(n):
            s = (p[i + 2] - p[i]) / two_dx
            row[i] = s + gain * (ridged[i] - s)


@njit(cache=True)
def _period_means(j0, normal, tangential, den, num, carry, first_kept, last_kept, out_k, out_normal, out_tangential):
    """Mean of grid samples ``j0 + i`` (values ``normal``, ``tangential``) over each period k of a slower rate: grid
    sample j belongs to period k = ⌊j·den/num⌋ + 1 (num/den: grid samples per period), i.e. its instant lies in
    [t_{k−1}, t_k).  A period closes with its last grid sample; closed periods in [``first_kept``, ``last_kept``]
    are written to the outputs (k, means), their count returned.  ``carry`` = (open period, sums, count), carried across calls: the
    samples are added one by one in grid order, so the means do not depend on how the grid was cut into blocks."""
    k_open, sum_n, sum_t, count = int(carry[0]), carry[1], carry[2], carry[3]
    m = 0
    for i in range(normal.size):
        j = j0 + i
        k = j * den // num + 1
        if k != k_open:  # (only before the first sample: a period is closed by its own last sample)
            k_open, sum_n, sum_t, count = k, 0.0, 0.0, 0.0
        sum_n += normal[i]
        sum_t += tangential[i]
        count += 1.0
        if (j + 1) * den // num + 1 != k:  # the period's last grid sample
            if first_kept <= k <= last_kept:
                out_k[m], out_normal[m], out_tangential[m] = k, sum_n / count, sum_t / count
                m += 1
            k_open, sum_n, sum_t, count = k + 1, 0.0, 0.0, 0.0
    carry[0], carry[1], carry[2], carry[3] = k_open, sum_n, sum_t, count
    return m


class ForceFeed:
    """One sliding contact's normal and tangential force (N) handed to a slower model (the electrodes, at
    ``rate_Hz``): the mean of the grid samples over each period [t_{k−1}, t_k), t_k = k/``rate_Hz`` (a boxcar
    decimation: the texture's fast vibration is averaged out rather than aliased), filled as
    the grid runs, with the open period carried across blocks (the means do not depend on the block size), and kept
    until read.

    Calling it with instants t_k (s, on the slower model's grid, increasing from call to call) returns the (normal,
    tangential) means of their periods.  The tangential force is the friction model's, signed along the stage's axis
    (+x).  Only periods around the motion's span [``start_s``, ``end_s``] are kept (the others read zero), as are
    periods before the first grid sample the feed saw (a sensor started later); periods read are dropped, so the
    feed holds what the grid has computed since the last read.  :meth:`last_grid_index` says how far the grid must
    have run for an instant."""

    def __init__(self, rate_Hz: float, fs: float, start_s: float, end_s: float):
        per_period = Fraction(fs).limit_denominator(10**6) / Fraction(rate_Hz).limit_denominator(10**6)
        self.rate_Hz, self._num, self._den = float(rate_Hz), per_period.numerator, per_period.denominator
        self._span = (math.floor(start_s * rate_Hz) - 1,  # periods that may hold a sample of the motion
                      math.ceil(end_s * rate_Hz) + 1 if math.isfinite(end_s) else np.iinfo(np.int64).max)
        self._carry = np.array([-1.0, 0.0, 0.0, 0.0])  # open period, its sums and count
        self._first = None  # the first period the grid reached
        self._next = self._span[0]  # the first period not yet read (none before the span is kept)
        self._k, self._normal, self._tangential = [], [], []  # closed periods not yet read

    def last_grid_index(self, t_s: float) -> int:
        """The last grid sample (index) of the period ending at instant ``t_s`` (s)."""
        k = int(round(t_s * self.rate_Hz))
        return -(-k * self._num // self._den) - 1  # ⌈k·num/den⌉ − 1

    def _period(self, j: int) -> int:
        return j * self._den // self._num + 1

    def push(self, n0: int, n: int, normal: np.ndarray | None = None, tangential: np.ndarray | None = None) -> None:
        """Take grid samples ``n0`` … ``n0 + n − 1`` of the contact's forces (N; None: zero), in grid order."""
        if self._first is None:
            self._first = self._period(n0)
        if self._period(n0 + n - 1) < self._span[0] or self._period(n0) > self._span[1]:
            return  # no period kept: nothing to add (the open period restarts at the next sample pushed)
        if normal is None:
            normal = tangential = np.zeros(n)
        size = n * self._den // self._num + 2
        out_k, out_n, out_t = np.empty(size, dtype=np.int64), np.empty(size), np.empty(size)
        m = _period_means(n0, normal, tangential, self._den, self._num, self._carry, self._next, self._span[1], out_k,
                          out_n, out_t)
        if m:
            self._k.append(out_k[:m])
            self._normal.append(out_n[:m])
            self._tangential.append(out_t[:m])

    def __call__(self, t) -> tuple[np.ndarray, np.ndarray]:
        k = np.rint(np.asarray(t, float) * self.rate_Hz).astype(np.int64)
        normal, tangential = np.zeros(k.size), np.zeros(k.size)
        if k.size == 0:
            return normal, tangential
        if self._first is None:
            raise RuntimeError("force feed: read before the grid ran")
        if len(self._k) > 1:
            self._k, self._normal, self._tangential = ([np.concatenate(x)] for x in (self._k, self._normal,
                                                                                     self._tangential))
        have = self._k[0] if self._k else np.zeros(0, dtype=np.int64)
        at = np.minimum(np.searchsorted(have, k), max(have.size - 1, 0))
        found = have[at] == k if have.size else np.zeros(k.size, bool)
        normal[found], tangential[found] = self._normal[0][at[found]], self._tangential[0][at[found]]
        waiting = ~found & (k >= max(self._first, self._next)) & (k >= self._span[0]) & (k <= self._span[1])
        if waiting.any():
            raise RuntimeError(f"force feed: the grid has not reached the period ending at "
                               f"{k[waiting][0] / self.rate_Hz:.6f} s")
        if have.size:
            drop = int(np.searchsorted(have, k.max(), side="right"))
            self._k, self._normal, self._tangential = ([x[0][drop:]] for x in (self._k, self._normal, self._tangential))
        self._next = max(self._next, int(k.max()) + 1)
        return normal, tangential


class SlidingContact(Effect):
    """Skin–texture sliding: stick-slip friction, patch-averaged texture, fingerprint ridges (N)."""

    name = "sliding_contact"
    produces = ("contact_force_N", "tangential_force_N", "normal_force_N", "stage_force_N")
    #: the linear stage drags the texture through its own mechanics: the load its motor feels (and its current
    #: measures) is the tangential force low-passed at this corner (model choice: a stage and motor of tens of
    #: hertz; fast texture fluctuations do not reach the motor current)
    STAGE_CORNER_HZ = 20.0

    #: rate (Hz) of the force log kept for each contact (for a stage's motor current and force plots)
    LOG_RATE_HZ = 100.0

    def __init__(self, motions: list, params: SensorParams, fs: float, dx_m: float, substeps: int, n_radii: int,
                 seed: int, ridges: str = "effective"):
        if ridges not in RIDGE_MODELS:
            raise ValueError(f"sliding contact: ridges = {ridges!r}; choose one of: {', '.join(RIDGE_MODELS)}")
        self.params, self.fs, self.dx_m, self.substeps = params, fs, dx_m, int(substeps)
        self.ridges = ridges
        self.log_every = max(1, int(round(fs / self.LOG_RATE_HZ)))
        a = np.exp(-2 * np.pi * self.STAGE_CORNER_HZ / fs)  # first-order low-pass, exact pole
        # (b padded to a's length: lfilter pads it so anyway, and 2 taps run in filters' compiled loop)
        self._stage_ba = (np.array([1.0 - a, 0.0]), np.array([1.0, -a]))
        self.motions = sorted(motions, key=lambda m: m.start_s)
        rng = effect_rng(seed, self.name)
        self._contacts = []
        for m in self.motions:
            skin = m.skin or Skin()
            gain = skin.trial_gain(rng)
            force_max = getattr(m, "force_N", COMMANDED_FORCE_MAX_N)
            radii = params.contact_radius_at_1N_m * np.cbrt(np.geomspace(0.02, max(2.5 * force_max, 0.1), n_radii))
            length = m.max_travel_m + 4 * radii.max() + 0.01
            c = {"motion": m, "gain": gain, "radii": radii, "skin": skin, "table_n": table_positions(length, dx_m),
                 "ring_first": None, "state": friction.new_state(0.0), "skin_state": skin.state(), "log": [],
                 "stage_zi": np.zeros(1), "feeds": [], "releases": []}
            if ridges == "resolved":  # each ridge under the patch a compliant element (friction.Ridges)
                weights, shifts, offsets = ridge_elements(tuple(float(a) for a in radii), skin.ridge_pitch_m, dx_m)
                stiffness = skin.ridge_stiffness_per_length(params.skin_youngs_modulus_Pa, params.skin_poisson_ratio)
                c["ridge_parts"] = [weights, shifts, offsets, gain, stiffness, None,
                                    friction.new_ridge_state(offsets.size)]
                c["reach"] = ridge_reach(radii, dx_m)
            if c["table_n"] <= TABLE_WHOLE_MAX:  # the whole track's tables, once
                c["heights"], c["slopes"] = spatial_tables(m.texture, skin, gain, m.start_position_m, length, dx_m,
                                                           radii, ridge_comb=ridges == "effective")
                c["fluctuation"] = fluctuation_table(m.texture, m.start_position_m, length, dx_m)
                if ridges == "resolved":
                    c["crest"] = crest_table(m.texture, skin, m.start_position_m, 0, c["table_n"], c["table_n"],
                                             c["reach"], dx_m)
            else:  # a ring around the finger, which starts at position 0
                self._centre_ring(c, 0)
            if ridges == "resolved":  # the ridges' share of the texture's friction over the track crossed
                c["ridge_parts"][5] = self._ridge_friction(c)
            self._contacts.append(c)

    def _ridge_friction(self, c: dict) -> np.ndarray:
        """The ridge-resolved ridges' mean share of contact ``c``'s friction coefficient per patch radius (1:
        :func:`friction.ridge_friction_coefficients`) over the track its patch crosses: from the motion's start
        position over its travel (a slide's distance, a commanded motion's ``max_travel_m``; at most the texture's
        :data:`emulator.texture.SURFACE_LENGTH_M`, over which the surface repeats), the ridges loaded from rest over
        :data:`friction.RIDGE_FRICTION_SETTLE_M` before it, on a crest table of its own (so however the contact
        holds its tables)."""
        weights, shifts, offsets, gain, stiffness = c["ridge_parts"][:5]
        p, m, dx = self.params, c["motion"], self.dx_m
        settle_n = int(np.ceil(friction.RIDGE_FRICTION_SETTLE_M / dx))
        track_n = max(int(np.ceil(min(m.max_travel_m, SURFACE_LENGTH_M) / dx)), 1)
        n = settle_n + track_n + 2 * c["reach"] + 2
        crest = crest_table(m.texture, c["skin"], m.start_position_m - settle_n * dx, 0, n, n, c["reach"], dx)
        return friction.ridge_friction_coefficients(crest, weights, shifts, offsets, float(gain), float(stiffness),
                                                    c["radii"], p.contact_radius_at_1N_m,
                                                    p.contact_stiffness_N_per_m1_5,
                                                    m.texture.modulus_Pa / (1 - POISSON_RATIO**2), TEXTURE_LAYER_M,
                                                    dx, settle_n, track_n)

    # --- the tables of a long track: a ring of tiles around the finger -------------------------------------------
    def _centre_ring(self, c: dict, tile: int) -> None:
        """Hold ``c``'s tables for tiles ``tile − RING_TILES // 2`` … (tile b: positions b·T … b·T + T − 1, T =
        :data:`TABLE_TILE`) in new arrays (the old ones are replaced, never edited: a rig's snapshot shares them).
        Position i sits in column i mod (RING_TILES·T), which is where the compiled step reads it (it reads a table
        modulo its length), so the step reads exactly what the whole table holds there; a position beyond the
        track's end (or before its start) holds what the whole table's wrapped read gives, its position modulo the
        track's length.  Tiles the ring already held are copied, the others computed (:func:`table_stretch`, one
        FFT per tile of the track, so a position's values do not depend on which ring asked for them)."""
        T, n_total, m = TABLE_TILE, c["table_n"], c["motion"]
        first = tile - RING_TILES // 2
        old = c["ring_first"]
        width = RING_TILES * T
        resolved = self.ridges == "resolved"
        if old is None:
            heights, slopes = np.empty((c["radii"].size, width)), np.empty((c["radii"].size, width))
            fluct = np.empty(width)
            crest = np.empty(width) if resolved else None
        else:
            heights, slopes, fluct = c["heights"].copy(), c["slopes"].copy(), c["fluctuation"].copy()
            crest = c["crest"].copy() if resolved else None
        computed = {}  # track tile -> its tables (a ring tile beyond the track's end may need two)
        for b in range(first, first + RING_TILES):
            if old is not None and old <= b < old + RING_TILES:
                continue  # held already, in the same columns
            column = (b % RING_TILES) * T
            v = b * T
            while v < (b + 1) * T:  # positions v …, as their wrapped positions w in the track's tiles
                w = v % n_total
                k = w // T
                if k not in computed:
                    start, n = k * T, min(T, n_total - k * T)
                    computed[k] = (start, *table_stretch(m.texture, c["skin"], c["gain"], m.start_position_m, start,
                                                         n, self.dx_m, c["radii"], not resolved),
                                   fluctuation_stretch(m.texture, m.start_position_m, start, n, self.dx_m),
                                   crest_table(m.texture, c["skin"], m.start_position_m, start, n, n_total,
                                               c["reach"], self.dx_m) if resolved else None)
                start, h, s, e, r = computed[k]
                run = min((b + 1) * T - v, start + h.shape[1] - w)
                at = column + v - b * T
                heights[:, at:at + run], slopes[:, at:at + run] = h[:, w - start:w - start + run], \
                    s[:, w - start:w - start + run]
                fluct[at:at + run] = e[w - start:w - start + run]
                if resolved:
                    crest[at:at + run] = r[w - start:w - start + run]
                v += run
        c["heights"], c["slopes"], c["fluctuation"], c["ring_first"] = heights, slopes, fluct, first
        if resolved:
            c["crest"] = crest

    def _friction(self, c: dict, n0: np.ndarray, v: np.ndarray, dt: float, out: tuple, i: int, j: int) -> None:
        """:func:`friction.slide_block` over samples ``i`` … ``j − 1`` of a block (nominal load ``n0``, N, and stage
        velocity ``v``, m/s, per grid sample of ``dt`` s) into the outputs ``out`` (normal N, tangential N, slip m/s,
        texture position m, and with ridge-resolved fingerprints release events and released force N); the state is
        carried, so a block cut into pieces gives the same samples."""
        m, p, tex = c["motion"], self.params, c["motion"].texture
        ridges, releases = None, {}
        if self.ridges == "resolved":
            ridges = friction.Ridges(c["crest"], *c["ridge_parts"])
            releases = {"out_releases": out[4][i:j], "out_released_N": out[5][i:j]}
        friction.slide_block(n0[i:j], v[i:j], dt, self.substeps,
                             c["heights"], c["slopes"], c["radii"], c["fluctuation"], self.dx_m, c["state"],
                             not isinstance(m, Slide),
                             p.contact_stiffness_N_per_m1_5, p.contact_radius_at_1N_m,
                             tex.modulus_Pa / (1 - POISSON_RATIO**2), TEXTURE_LAYER_M,
                             p.skin_tangential_stiffness_N_per_m, p.skin_tangential_damping_N_s_per_m,
                             p.bristle_stiffness_per_N, p.bristle_damping_per_N,
                             tex.mu_static, tex.mu_kinetic, tex.stribeck_velocity_m_per_s,
                             tex.mu_per_velocity_s_per_m, *(x[i:j] for x in out[:4]), ridges=ridges, **releases)

    def _friction_in_ring(self, c: dict, n0: np.ndarray, v: np.ndarray, dt: float, out: tuple) -> None:
        """:meth:`_friction` over a whole block in pieces over which the stage moves at most half a tile, each with
        the ring centred on the tile the finger is on.  Should the skin leave the ring within a piece after all (it
        cannot at physical speeds), the piece runs again from the state it started from, shorter, so no position is
        ever read outside the ring."""
        half_tile_m = 0.5 * TABLE_TILE * self.dx_m
        fastest = float(np.max(np.abs(v))) if v.size else 0.0
        piece = v.size if fastest == 0.0 else max(1, int(half_tile_m / (fastest * dt)))
        positions_m = out[3]
        done = 0
        while done < v.size:
            start_m = c["state"][2]
            tile = int(np.floor(start_m / self.dx_m)) // TABLE_TILE if np.isfinite(start_m) else c["ring_first"]
            if tile != c["ring_first"] + RING_TILES // 2:
                self._centre_ring(c, tile)
            end = min(v.size, done + piece)
            state = c["state"].copy()
            ridge_state = c["ridge_parts"][-1].copy() if "ridge_parts" in c else None
            self._friction(c, n0, v, dt, out, done, end)
            if self._ring_holds(c, np.append(positions_m[done:end], start_m)):
                done = end
                continue
            c["state"][:] = state  # the piece runs again from where it started: the skin's state and the ridges'
            if ridge_state is not None:
                c["ridge_parts"][-1][:] = ridge_state
            if end - done == 1:
                raise RuntimeError(f"sliding: the skin moved more than {RING_MARGIN_M * 1e3:g} mm along the texture "
                                   f"within one grid step (position {c['state'][2]:.6g} m)")
            piece = max(1, (end - done) // 2)

    def _ring_holds(self, c: dict, positions_m: np.ndarray) -> bool:
        """Whether every position (m) lies in the ring, :data:`RING_MARGIN_M` inside its ends (the step reads a
        position's column and the next; the margin covers the skin's travel within one grid step between the
        positions it records)."""
        margin = min(RING_MARGIN_M / self.dx_m, TABLE_TILE / 4)
        lo, hi = c["ring_first"] * TABLE_TILE + margin, (c["ring_first"] + RING_TILES) * TABLE_TILE - 1 - margin
        u = positions_m / self.dx_m
        return bool(np.all((u >= lo) & (u < hi)))  # (NaN: not held)

    def describe(self) -> str:
        return "sliding contact: stick-slip friction, patch-averaged texture, fingerprint ridges (N)"

    def ridge_gains(self) -> list[float]:
        return [c["gain"] for c in self._contacts]

    def ridge_releases(self, k: int) -> dict[str, np.ndarray]:
        """Contact ``k``'s ridge release events so far (ridge-resolved fingerprints; none with effective ridges; an
        event: :func:`emulator.friction._count_release`), at the grid instants (s) where one began or went on: how
        many began there and the force they released (N) in that grid step (an event lasting several steps counts
        once, where its drop reached the threshold, and adds its force step by step, peak to trough)."""
        log = self._contacts[k]["releases"]
        a = np.concatenate(log, axis=1) if log else np.zeros((3, 0))
        return {"t": a[0], "count": a[1], "released_N": a[2]}

    def force_feed(self, motion, rate_Hz: float) -> ForceFeed:
        """A :class:`ForceFeed` of ``motion``'s (one of :attr:`motions`, by identity) normal and tangential force at
        ``rate_Hz``, filled from now on as the grid runs (the electrode model reads its contact's forces from it)."""
        contact = next((c for c in self._contacts if c["motion"] is motion), None)
        if contact is None:
            raise ValueError(f"force_feed: {motion!r} is not one of this sliding contact's motions")
        feed = ForceFeed(rate_Hz, self.fs, motion.start_s, motion.end_s)
        contact["feeds"].append(feed)
        return feed

    def force_log(self, k: int) -> dict[str, np.ndarray]:
        """Contact ``k``'s forces at :data:`LOG_RATE_HZ` so far: instants (s), normal and tangential force (N),
        slip velocity (m/s), and the stage's load (N: the tangential force through the stage's mechanics)."""
        log = self._contacts[k]["log"]
        a = np.concatenate(log, axis=1) if log else np.zeros((5, 0))
        return {"t": a[0], "normal_N": a[1], "tangential_N": a[2], "slip_m_per_s": a[3], "stage_N": a[4]}

    def process(self, block: Block, inputs):
        t = block.times
        normal_out = np.zeros(block.n)
        tangential_out = np.zeros(block.n)
        load_out = np.zeros(block.n)
        stage_out = np.zeros(block.n)
        p, dt = self.params, 1.0 / block.fs
        for c in self._contacts:
            m = c["motion"]
            if m.end_s < t[0] or m.start_s > t[-1]:
                for feed in c["feeds"]:
                    feed.push(block.n0, block.n)  # no force: the periods still close
                continue
            a = int(np.searchsorted(t, m.start_s, side="left"))
            b = int(np.searchsorted(t, m.end_s, side="right"))
            tt = t[a:b]
            if isinstance(m, Slide):
                n0 = m.normal_force_N(tt)
            else:
                n0 = commanded_load_N(m, p, tt)
            n0, v = np.ascontiguousarray(n0), np.ascontiguousarray(m.stage_velocity_m_per_s(tt))
            resolved = self.ridges == "resolved"
            out = tuple(np.empty(tt.size) for _ in range(6 if resolved else 4))  # (+ releases, released force)
            normal, tang, slip, pos = out[:4]
            if c["ring_first"] is None:
                self._friction(c, n0, v, dt, out, 0, tt.size)
            else:
                self._friction_in_ring(c, n0, v, dt, out)
            for feed in c["feeds"]:  # (the whole block: zero force outside the motion)
                if a == 0 and b == block.n:
                    feed.push(block.n0, block.n, normal, tang)
                else:
                    whole_n, whole_t = np.zeros(block.n), np.zeros(block.n)
                    whole_n[a:b], whole_t[a:b] = normal, tang
                    feed.push(block.n0, block.n, whole_n, whole_t)
            # the tangential load's share of fluid pressure, signed: its fluctuations enter linearly (no
            # rectification); slides run along +x, so the mean friction raises the pressure
            normal_out[a:b] += normal + p.tangential_coupling * tang
            tangential_out[a:b] += tang
            load_out[a:b] += normal
            stage, c["stage_zi"] = filters.lfilter(*self._stage_ba, tang, c["stage_zi"])
            stage_out[a:b] += stage
            if resolved:  # the ridges' release events and released force, where there were any
                at = np.flatnonzero(out[5])
                if at.size:
                    c["releases"].append(np.stack([tt[at], out[4][at], out[5][at]]))
            # the force log: grid samples whose index is a multiple of log_every (independent of block size)
            keep = slice(-(block.n0 + a) % self.log_every, None, self.log_every)
            if tt[keep].size:
                c["log"].append(np.stack([tt[keep], normal[keep], tang[keep], slip[keep], stage[keep]]))
        return {"contact_force_N": normal_out, "tangential_force_N": tangential_out, "normal_force_N": load_out,
                "stage_force_N": stage_out}
