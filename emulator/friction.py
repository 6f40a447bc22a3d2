"""Skin–texture contact while sliding, sample by sample: LuGre friction against a compliant skin, plus the texture
seen through the contact patch (compiled with numba; one call per block, state carried between calls).

Per grid step of ``dt`` (s), with the stage moving the texture at ``V`` (m/s) and a nominal normal load ``N0`` (N):

* the texture's height under the patch ``h`` (m) and the load-weighted slope under the skin ``s`` (1) are read
  from precomputed spatial tables at the texture position under the finger (the relative slip ``p``), at the
  patch radius of the present load; normal load ``N = max(0, N0 + k·h)`` with the Hertz contact stiffness
  ``k_n = 1.5·K^(2/3)·N0^(1/3)`` in series with the texture's own stiffness;
* LuGre friction per N of load: bristle deflection ``z`` obeys ``dz/dt = v_r − σ0|v_r| z / g(v_r)`` with the
  Stribeck curve ``g``; over one step with ``v_r`` held it is integrated exactly (an exponential), so it is
  stable at any step and ``|z|`` never exceeds ``max(|z|, µs/σ0)``; the friction force is
  ``N·(σ0 z + σ1(v_r) dz/dt + µv v_r)`` with the bristle damping fading as the skin slides, ``σ1(v_r) =
  σ1·exp(−(v_r/v_s)²)`` (:func:`_bristle_damping`);
* the skin is a massless spring–damper (``k_t``, ``c_t``) between the core and the contact, so the skin's
  velocity ``u`` satisfies ``k_t (x + u dt) + c_t u = F_friction(u)`` with ``v_r = V − u``: an implicit step,
  solved for ``u`` by Newton from the last velocity (analytic slope; 2 evaluations a step while sliding), and
  where friction weakens with slip (G may have several roots) or Newton strays, by regula falsi (Illinois) on a
  bracket that always holds a root (unconditionally stable);
* the texture position advances by the slip ``v_r·dt``: while the skin sticks it hardly moves, so the texture
  excites nothing; at slip the features start passing under the patch.

The friction coefficient fluctuates with the slip: µs and µk (so the Stribeck curve ``g``) are scaled by
``1 + ε(p)``, read from a table along the track at the texture position (:func:`emulator.texture.
friction_fluctuation`); the bristles follow a change of ``g`` over their pre-sliding length, and while the skin
sticks ``p`` hardly moves, so neither does ``ε``.

The tangential force on the skin is the friction force plus ``N·s`` (ridges climbing feature slopes while the
skin slips over them).

Ridge-resolved fingerprints (the reference profile, :class:`Ridges`): ``s`` then holds the patch part alone,
``(1 − g)·s_patch``, and each ridge under the patch is a compliant element with its own force ``F_j``.  Its limit
is the comb's own term without the catch factor, ``L_j = N·f·g·w_j·σ_j`` (load share ``w_j`` × crest slope ``σ_j``
under it, with the series factor ``f`` and the ridge gain ``g``; only a slip deflects a ridge, so a finger pressed
without slipping feels no ridge force, and a ridge deflected by a slip keeps pushing when it stops); in the slip's
direction a ridge over a positive limit loads elastically by ``k_j·|v_r|·dt`` (``k_j`` = the ridge's stiffness per
length × its chord across the patch) up to ``L_j`` and, when ``L_j`` falls below ``F_j`` (a feature's crest passes),
releases to it within the step; over a negative limit (a feature's back) it follows it.  The tangential force
gains ``Σ F_j`` less its mean ``µ_r·N`` in the direction of the last slip that moved the ridges, through the stick
phases after it too (a deflected ridge keeps pushing while the skin sticks), nothing before the first such slip
since touchdown (``µ_r``, :func:`ridge_friction_coefficients`, over the track the motion's patch crosses: the
ridges' catch-and-release dissipates, a share of friction the texture's measured µ holds already, so the skin's
stick-slip keeps that µ and the ridges add their fluctuation about their mean); rigid ridges (``k_j`` → ∞,
``µ_r`` = 0) give the comb's ``N·f·c·g·Σ w_j σ_j`` exactly.  A release event is a
drop of ``F_j`` by ``k_j`` × :data:`RIDGE_RELEASE_LENGTH_M` (peak to trough, small reloads ignored); a slip slower
than :data:`RIDGE_SLIP_FLOOR_M_PER_S` moves no ridge by itself, but once a slip has moved them the slow slip is
summed, and the held crests are carried with the texture once the sum passes the bristles' elastic reach µs/σ0
(creep, not the recoverable pre-sliding deflection); a change of chord adds no energy (:func:`_rechord`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

#: ridges catch feature slopes only while the skin slips over them: the slope force is scaled by
#: |v_r| / (|v_r| + this) (model choice: 1 mm/s, so a finger pressed without sliding feels no slope force)
CATCH_VELOCITY_M_PER_S = 1e-3

#: a ridge release event is a drop of a ridge's force by at least its stiffness × this length (its crest running
#: ahead of its base by 20 µm, a fifth of the crest's contact width), not interrupted by a reload as large (model
#: choice: the limit the surface sets on a crest carries the sandpaper's roughness down to the texture step, so
#: smaller drops multiply as the step shrinks — 2 µm gives 851, 1408, 2057, 2860 events/s for dx 10, 5, 2.5,
#: 1.25 µm on 60-grit — while drops of 20 µm converge, 2 % apart between the last two; a near-rigid ridge, whose
#: crest keeps to its base, never releases)
RIDGE_RELEASE_LENGTH_M = 20e-6

#: a ridge's slip slower than this is no motion: its crest stays, nothing releases and the slip's direction stays; once
#: a faster slip has moved the ridges, the slower ones are summed and carried with the next moving slip, or on their own
#: past the bristles' elastic reach µs/σ0 (see _slide_kernel: the surface holds the crests while the skin creeps) (model
#: choice: the catch velocity, the comb's own scale for "the skin slips" — the pre-sliding micro-slip of the stuck skin
#: and its settling after the stage stops move no crest; with a floor of 1 µm/s the stuck skin's micro-slip let crests
#: over back slopes fall to their negative limits at the stage's start, pushing the skin forward while it stuck and
#: taking the reference profile's slip-onset rise from 22.8 to 10.0 dB)
RIDGE_SLIP_FLOOR_M_PER_S = CATCH_VELOCITY_M_PER_S

#: state vector: skin displacement x (m), bristle deflection z (m), texture position p (m), and the patch height
#: (m) and slope (1) where the finger touched down (a position-held finger's load changes with the height from
#: there; the slope is kept for the record but not subtracted: see the slope force below)
#: ... whether the finger is touching (1.0) or not (0.0), the skin's last velocity (m/s), the direction (±1) of
#: the last slip that moved the resolved ridges (0.0 none since the finger touched down: see _slide_kernel), and
#: the slip (m) the texture has crept under the resolved ridges' held crests since they last moved
STATE_SIZE = 9

# (the helpers below are inlined into slide_block at numba's IR level, ``inline="always"``: the same arithmetic,
# about an eighth less time per sample than calls)


@njit(cache=True, inline="always")
def _stribeck(v, mu_s, mu_k, vs):
    """The Stribeck curve ``g`` (1) at slip velocity ``v`` (m/s) and its slope dg/d|v| (s/m)."""
    r = abs(v) / vs
    if r > 30.0:  # the static part has decayed below 1e-390 of itself
        return mu_k, 0.0
    # (one exponential: the compiler merges the two identical calls)
    return mu_k + (mu_s - mu_k) * math.exp(-r * r), -2.0 * r * ((mu_s - mu_k) * math.exp(-r * r)) / vs


@njit(cache=True, inline="always")
def _bristle_after(z, vr, dt, sigma0, mu_s, mu_k, vs):
    """Bristle deflection (m) after ``dt`` with the slip velocity ``vr`` held (exact solution of the linear ODE),
    and its derivative with respect to ``vr`` (s; at ``vr = 0``, where it has a corner, the mean of both sides)."""
    if vr == 0.0:
        return z, dt
    g, dg = _stribeck(vr, mu_s, mu_k, vs)
    a = sigma0 * abs(vr) / g
    z_ss = g / sigma0 if vr > 0 else -g / sigma0
    if a * dt < 1e-12:
        return z + vr * dt, dt
    decay = math.exp(-a * dt)
    # d z_ss/d vr = g'/σ0 on both sides; d a/d vr = σ0·sign(vr)·(g − |vr| g')/g²
    da = sigma0 * (g - abs(vr) * dg) / (g * g)
    if vr < 0:
        da = -da
    return z_ss + (z - z_ss) * decay, dg / sigma0 * (1.0 - decay) - (z - z_ss) * dt * decay * da


@njit(cache=True, inline="always")
def _bristle_damping(vr, sigma1, vs):
    """The bristle damping (s/m) at slip velocity ``vr`` (m/s) and its derivative d/dv_r (s²/m²): ``sigma1`` at rest,
    fading over the Stribeck velocity ``vs`` (m/s) as σ1·exp(−(v_r/v_s)²): the velocity-dependent damping Olsson
    et al. (Eur. J. Control 4(3), 1998) give for LuGre (attributed from the literature's use, not checked against
    the paper's text), with its velocity scale taken as the texture's Stribeck velocity (a model choice: no new
    parameter, and not fitted to any claim).  With a constant σ1 the friction element is not passive when µ
    falls with slip (σ1 > µv·µk/(µs − µk), every texture of the library): where the bristles' deflection exceeds
    the new steady state — a slip's onset, where g falls from µs to µk within a step — the damping term σ1·dz/dt
    outweighs the bristles' force and the friction pushes the skin along the slip (−7.7 N at 20 N, 20 cm/s),
    giving back up to 1.4e-4 J per slip.  With the fading damping the storage N·σ0·z²/2 never grows faster than
    the work put in (derived: the rate of dissipation is N·|v_r|·(g·w² − σ1(v_r)·|v_r|·(w − 1)) + N·µv·v_r² with
    w = σ0·z·sign(v_r)/g, not negative while σ1(v_r)·|v_r| ≤ 4·g; the most σ1·|v|·exp(−(v/v_s)²) reaches is
    σ1·v_s/√(2e), 0.064 at σ1 = 30 s/m and v_s = 5 mm/s, below 4·g for any µ above 0.016)."""
    r = vr / vs
    if abs(r) > 30.0:
        return 0.0, 0.0
    s1 = sigma1 * math.exp(-r * r)
    return s1, -2.0 * r / vs * s1


@njit(cache=True, inline="always")
def _residual(u, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v):
    """G(u) = skin force − friction force (N) for skin velocity ``u`` (m/s) over one step (increasing through its
    root), its slope dG/du (N·s/m), the bristle deflection after the step (m) and the friction force (N) at ``u``
    (the step's outcome if ``u`` is the root)."""
    vr = v_stage - u
    znew, dz = _bristle_after(z, vr, h, sigma0, mu_s, mu_k, vs)
    s1, ds1 = _bristle_damping(vr, sigma1, vs)
    force = normal * (sigma0 * znew + s1 * (znew - z) / h + mu_v * vr)
    slope = k_t * h + c_t + normal * ((sigma0 + s1 / h) * dz + ds1 * (znew - z) / h + mu_v)
    return k_t * (x + u * h) + c_t * u - force, slope, znew, force


@njit(cache=True, inline="always")
def _radius_weight(radii, r):
    """The table row ``k`` and weight ``w`` toward row ``k + 1`` for patch radius ``r`` (m): linear in between,
    clamped at the ends."""
    if r <= radii[0]:
        return 0, 0.0
    if r >= radii[-1]:
        return radii.size - 1, 0.0
    k = 0
    while radii[k + 1] < r:
        k += 1
    return k, (r - radii[k]) / (radii[k + 1] - radii[k])


@njit(cache=True, inline="always")
def _interp_tables(heights, slopes, fluctuation, k, w, pos, dx):
    """Bilinear reads of ``heights`` and ``slopes`` (radius index × position index) between rows ``k`` and ``k + 1``
    (weight ``w`` toward the latter, from :func:`_radius_weight`) and a linear read of ``fluctuation`` (position
    index) at position ``pos`` (m); the track repeats beyond its ends."""
    n = heights.shape[1]
    u = pos / dx
    i = int(math.floor(u))
    f = u - i
    if i < 0 or i >= n:  # (an integer modulo costs more than the test)
        i = i % n
    j = i + 1 if i + 1 < n else 0
    h = heights[k, i] * (1 - f) + heights[k, j] * f
    s = slopes[k, i] * (1 - f) + slopes[k, j] * f
    e = fluctuation[i] * (1 - f) + fluctuation[j] * f
    if w > 0.0:
        h = h * (1 - w) + (heights[k + 1, i] * (1 - f) + heights[k + 1, j] * f) * w
        s = s * (1 - w) + (slopes[k + 1, i] * (1 - f) + slopes[k + 1, j] * f) * w
    return h, s, e


#: Newton iterations tried per step before the bracketed solver takes over (a warm start needs 1–2)
NEWTON_ITERATIONS = 6


@njit(cache=True, inline="always")
def _step_velocity(u_prev, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v):
    """The skin velocity ``u`` (m/s) that solves one implicit step G(u) = 0, with the bristle deflection (m) and
    friction force (N) at it: Newton from the last velocity ``u_prev`` (m/s), kept inside the bracket its own
    evaluations establish; should a step leave it or the slope not be positive (the Stribeck curve's falling
    part can bend G back), or Newton not settle within :data:`NEWTON_ITERATIONS`, :func:`_solve_bracketed`
    solves the step from scratch (unconditionally stable)."""
    bound = _velocity_bound(x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_v)
    u = min(max(u_prev, -bound), bound)
    lo, hi = -bound, bound  # G(±bound) brackets a root
    tol = 1e-13 * (1.0 + abs(v_stage))
    skin_slope = k_t * h + c_t  # G's slope without friction (N·s/m)
    u_last, slope_last = u, 0.0
    for it in range(NEWTON_ITERATIONS):
        g, slope, znew, force = _residual(u, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs,
                                          mu_v)
        if not slope > 0.5 * skin_slope:  # the friction weakens with slip here: G may bend back to other roots
            break
        # converged: G nil to the bracketed solver's tolerance, or the next Newton correction below the velocity
        # tolerance (quadratic convergence: the one after it is smaller still)
        if abs(g) < 1e-12 * (1.0 + normal) or abs(g) < tol * slope:
            return u, znew, force
        if g > 0.0:
            hi = u
        else:
            lo = u
        du = -g / slope
        u_next = u + du
        if not (lo < u_next < hi):
            break
        # the last correction taken to first order (no evaluation): its error, ½·G''·du²/G' with G'' from the
        # last two slopes, is below a quarter of the tolerance, and the slip keeps its sign (G's corner at v_r = 0)
        if it > 0 and (v_stage - u_next > 0.0) == (v_stage - u > 0.0) and \
                2.0 * abs(slope - slope_last) / abs(u - u_last) * du * du < tol * slope:
            force_slope = slope - skin_slope  # −dF/du (N·s/m)
            s1, ds1 = _bristle_damping(v_stage - u, sigma1, vs)
            dz = (force_slope / normal - mu_v - ds1 * (znew - z) / h) / (sigma0 + s1 / h)  # −dz/du (s)
            return u_next, znew - dz * du, force - force_slope * du
        u_last, slope_last = u, slope
        u = u_next
    return _solve_bracketed(u_prev, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v, bound)


@njit(cache=True, inline="always")
def _velocity_bound(x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_v):
    """A skin velocity (m/s) beyond which G cannot change sign: G(−bound) ≤ 0 ≤ G(bound)."""
    zmax = max(abs(z), mu_s / sigma0)
    fmax = normal * (sigma0 * zmax + sigma1 * 2.0 * zmax / h + mu_v * (abs(v_stage) + 1.0))
    return abs(v_stage) + (k_t * abs(x) + fmax) / (c_t + k_t * h) + 1e-6


@njit(cache=True)
def _solve_bracketed(u_prev, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v, bound):
    """The implicit step solved without derivatives: bracketed around ``u_prev`` (widened until G changes sign;
    G(±``bound``) always brackets a root), then regula falsi with the Illinois modification (superlinear, never
    leaves the bracket). Returns ``u`` (m/s), the bristle deflection (m) and the friction force (N) at it."""
    step = 1e-4 * (1.0 + abs(v_stage))
    u_prev = min(max(u_prev, -bound), bound)  # the bound changes with the load: start inside it
    lo = max(-bound, u_prev - step)
    hi = min(bound, u_prev + step)
    # (the last evaluation's bristle deflection and force are kept: when the root is the last point
    # evaluated, as it mostly is, the step's outcome is already known)
    g_lo, _, z_eval, f_eval = _residual(lo, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v)
    g_hi, _, z_eval, f_eval = _residual(hi, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v)
    u_eval = hi
    while g_lo > 0.0 and lo > -bound:
        lo = max(-bound, lo - 4.0 * (hi - lo))
        g_lo, _, z_eval, f_eval = _residual(lo, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs,
                                            mu_v)
        u_eval = lo
    while g_hi < 0.0 and hi < bound:
        hi = min(bound, hi + 4.0 * (hi - lo))
        g_hi, _, z_eval, f_eval = _residual(hi, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs,
                                            mu_v)
        u_eval = hi
    u = 0.5 * (lo + hi)
    side = 0
    tol = 1e-13 * (1.0 + abs(v_stage))
    for _it in range(100):
        if hi - lo < tol or g_hi == g_lo:
            break
        u = (lo * g_hi - hi * g_lo) / (g_hi - g_lo)
        if not (lo < u < hi):
            u = 0.5 * (lo + hi)
        g, _, z_eval, f_eval = _residual(u, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v)
        u_eval = u
        if g == 0.0:
            break
        if g > 0.0:
            hi, g_hi = u, g
            if side == 1:
                g_lo *= 0.5
            side = 1
        else:
            lo, g_lo = u, g
            if side == -1:
                g_hi *= 0.5
            side = -1
        if abs(g) < 1e-12 * (1.0 + normal):
            break
    if u == u_eval:
        return u, z_eval, f_eval
    _, _, znew, force = _residual(u, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v)
    return u, znew, force


#: the friction's scale 1 + ε never falls below this (a guard for any amplitude; at 3 % RMS it is never reached)
MIN_FLUCTUATION_SCALE = 0.1

#: how deep the friction fluctuation ε dips, in its RMS, for :func:`stribeck_velocity_limit_m_per_s` (a bound with
#: margin: the shipped library's 119 fluctuation tracks at 1.25 µm dip at most 5.2 RMS below their mean, 4.5 on
#: average; 6 × 3 % RMS keeps µ above 0.82 of its value)
FLUCTUATION_DIP_PER_RMS = 6.0


def stribeck_velocity_limit_m_per_s(mu_kinetic: float, sigma1_s_per_m: float, fluctuation_rms: float) -> float:
    """The largest Stribeck velocity v_s (m/s) of a texture of kinetic friction ``mu_kinetic`` (1) with which the
    friction element stays passive under a bristle damping at rest of ``sigma1_s_per_m`` (s/m): the damping fades
    over v_s, so σ1·|v|·exp(−(v/v_s)²) peaks at σ1·v_s/√(2e), which must stay within 4·g (:func:`_bristle_damping`),
    g at its least µk × :func:`fluctuation_floor` (the fluctuation scales µ).  Infinite without bristle damping."""
    if sigma1_s_per_m <= 0.0:
        return math.inf
    return 4.0 * math.sqrt(2.0 * math.e) * mu_kinetic * fluctuation_floor(fluctuation_rms) / sigma1_s_per_m


def fluctuation_floor(fluctuation_rms: float) -> float:
    """The least scale 1 + ε (1) a friction fluctuation of ``fluctuation_rms`` (1) is taken to give µ:
    1 − :data:`FLUCTUATION_DIP_PER_RMS` × ``fluctuation_rms``, not below :data:`MIN_FLUCTUATION_SCALE`."""
    return max(1.0 - FLUCTUATION_DIP_PER_RMS * fluctuation_rms, MIN_FLUCTUATION_SCALE)


class Ridges(NamedTuple):
    """The ridge-resolved fingerprint (one contact): ridge ``j`` sits at ``offsets_m[j]`` (m) from the patch centre
    and reads the crest slope (1) at ``crest[(i + shifts[j]) mod len]`` for the texture position index ``i`` (see
    :func:`emulator.sliding.crest_table`); ``weights`` (radius row × ridge) is its share of the load, the comb's
    line-load weights; ``gain`` the skin's ridge gain (1); ``stiffness_per_length`` (N/m per m of ridge in contact,
    ``inf``: rigid ridges, the comb) from :meth:`emulator.skin.Skin.ridge_stiffness_per_length`; ``state`` (rows ×
    ridges, carried): see :data:`RIDGE_STATE_ROWS`."""

    crest: np.ndarray
    weights: np.ndarray
    shifts: np.ndarray
    offsets_m: np.ndarray
    gain: float
    stiffness_per_length: float
    friction: np.ndarray
    state: np.ndarray


#: rows of :attr:`Ridges.state`: each ridge's deflection (m), its release count's peak or trough (N), whether a
#: release is under way (1.0) and the slip's direction (±1; 0 before the first slip) (see :func:`_count_release`),
#: and the stiffness (N/m) its deflection was reached with (see :func:`_rechord`)
RIDGE_STATE_ROWS = 5


def new_ridge_state(n_ridges: int) -> np.ndarray:
    """:attr:`Ridges.state` of ridges at rest: no force, none releasing."""
    return np.zeros((RIDGE_STATE_ROWS, n_ridges))


# the effective comb passes these in the ridge arguments (the compiled step reads them only when resolved)
_NO_RIDGES = Ridges(np.zeros(1), np.zeros((1, 1)), np.zeros(1, dtype=np.int64), np.zeros(1), 0.0, 0.0,
                    np.zeros(1), new_ridge_state(1))


def slide_block(N0, V, dt, substeps, heights, slopes, radii, fluctuation, dx, state, touchdown_reference,
                K, radius_1N, modulus_eff, layer_m, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v,
                out_normal, out_tangential, out_slip_velocity, out_position, ridges: Ridges | None = None,
                out_releases=None, out_released_N=None):
    """Advance the contact over one block (arrays of the grid's length); fills the four outputs in place (see
    :func:`_slide_kernel`).  With ``ridges`` (:class:`Ridges`) the fingerprint is ridge-resolved: ``slopes`` then
    holds the patch part alone, the ridges' forces are added to the tangential force, and ``out_releases`` /
    ``out_released_N`` (arrays of the grid's length) receive each grid sample's release events (count) and the force
    they released (N)."""
    resolved = ridges is not None
    if not resolved:
        ridges = _NO_RIDGES
        out_releases = out_released_N = _NO_RIDGES.offsets_m
    elif out_releases is None or out_released_N is None:
        raise ValueError("slide_block: ridge-resolved fingerprints need out_releases and out_released_N")
    _slide_kernel(N0, V, dt, substeps, heights, slopes, radii, fluctuation, dx, state, touchdown_reference,
                  K, radius_1N, modulus_eff, layer_m, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v,
                  out_normal, out_tangential, out_slip_velocity, out_position, resolved, ridges.crest,
                  ridges.weights, ridges.shifts, ridges.offsets_m, float(ridges.gain),
                  float(ridges.stiffness_per_length), ridges.friction, ridges.state, out_releases, out_released_N)


@njit(cache=True, inline="always")
def _crest_at(crest, i, f):
    """The crest slope table read at index ``i`` (any integer: the table repeats) and fraction ``f`` toward the
    next (linear)."""
    n = crest.size
    if i < 0 or i >= n:
        i = i % n
    j = i + 1 if i + 1 < n else 0
    return crest[i] * (1.0 - f) + crest[j] * f


@njit(cache=True, inline="always")
def _count_release(ridge_state, j, force_before, force_after, direction, threshold):
    """Ridge ``j``'s release events, counted on its force in the slip's ``direction`` (±1) as it goes from
    ``force_before`` to ``force_after`` (N) in one substep: a release event begins when the force has fallen by
    ``threshold`` (N) from its peak, and lasts, however the force wiggles, until it has risen ``threshold`` above its
    lowest since (a peak-to-trough count with hysteresis; ``ridge_state[1]`` holds that peak or trough, N in the
    slip's direction, ``ridge_state[2]`` whether a release is under way, ``ridge_state[3]`` the slip's direction;
    a new direction starts the count afresh).  Returns the events begun (0 or 1) and the force released (N: from
    the peak down to each new trough, so an event's releases add up to its drop)."""
    if ridge_state[3, j] != direction:
        ridge_state[1, j] = direction * force_before
        ridge_state[2, j] = 0.0
        ridge_state[3, j] = direction
    force = direction * force_after
    extreme = ridge_state[1, j]
    if ridge_state[2, j] == 0.0:  # loading: the extreme is the peak since the last release
        if force > extreme:
            ridge_state[1, j] = force
        elif extreme - force >= threshold:  # a release
            ridge_state[1, j] = force
            ridge_state[2, j] = 1.0
            return 1, extreme - force
        return 0, 0.0
    if force < extreme:  # releasing: the extreme is the trough
        ridge_state[1, j] = force
        return 0, extreme - force
    if force - extreme >= threshold:  # loaded again: the release is over
        ridge_state[1, j] = force
        ridge_state[2, j] = 0.0
    return 0, 0.0


@njit(cache=True, inline="always")
def _rechord(ridge_state, j, stiffness):
    """Ridge ``j``'s state when its chord across the patch, so its stiffness, changes to ``stiffness`` (N/m) from
    ``ridge_state[4, j]``, without energy from nothing: a longer chord keeps the force (the new length enters
    undeflected, so the deflection falls and so does the energy F²/2k); a shorter one keeps the deflection, so the
    force (and the release count's peak or trough with it) falls with the length."""
    before = ridge_state[4, j]
    if before > stiffness:
        ridge_state[1, j] *= stiffness / before
    elif before > 0.0:
        ridge_state[0, j] *= before / stiffness
    ridge_state[4, j] = stiffness


@njit(cache=True, inline="always")
def _ridges_step(ridge_state, crest, shifts, shares, stiffness, pos, dx, limit_scale, catching, slip, slip_floor):
    """One substep of the ridge-resolved fingerprint.  Ridge ``j``'s base sits at texture position ``pos`` (m) plus
    its offset; its crest lags the base by its deflection ``δ_j`` (m, ``ridge_state[0]``), and the surface holds the
    crest with the limit ``L_j(x) = limit_scale · shares[j]`` × the crest slope at the crest's position ``x``.  The
    texture slips by ``slip`` (m) under the base: a held crest moves with the texture, so ``δ_j`` grows by the slip
    and the ridge loads elastically, ``F_j = stiffness[j]·δ_j``.  When ``F_j`` exceeds the limit where its crest is
    (in the slip's direction: a feature's crest has passed under it, or the load fell) the crest is released: it
    slides on with the slip to the first position where the spring force no longer exceeds the limit (the
    piecewise-linear crossing), so the force drops to the limit within the step — a snap, where the limit falls
    along the track faster than the ridge's stiffness.  A slip smaller than ``slip_floor`` (m) is no motion: no
    crest moves or releases and the slip's direction stays.  The ridges' force on the skin is ``Σ F_j``: a deflected
    ridge pushes whether the skin slips or not, and only a slip deflects it (so a finger pressed without slipping
    feels none).  Rigid ridges (``stiffness`` inf) have no deflection to remember: their force is the limit at the
    base times ``catching`` (the comb's catch factor, so they give the comb's force).  A ridge with no limit
    (outside the patch, no load, a smooth skin) or no stiffness carries nothing.  Returns the ridges' force (N), the
    release events begun (a drop of :data:`RIDGE_RELEASE_LENGTH_M` × ``stiffness[j]``, :func:`_count_release`) and
    the force they released (N)."""
    u = pos / dx
    i0 = int(math.floor(u))
    f0 = u - i0
    moving = abs(slip) >= slip_floor
    direction = 1.0 if slip > 0.0 else -1.0
    total, events, released = 0.0, 0, 0.0
    for j in range(shares.size):
        k = stiffness[j]
        scale = limit_scale * shares[j]
        if scale == 0.0 or k == 0.0:  # (no share, no load or gain, or no stiffness)
            for row in range(RIDGE_STATE_ROWS):  # (a slice's assignment costs more, every substep)
                ridge_state[row, j] = 0.0
            continue
        if math.isinf(k):  # rigid: the crest at the base, its force the limit there
            total += catching * scale * _crest_at(crest, i0 + shifts[j], f0)
            continue
        if k != ridge_state[4, j]:  # the chord changed with the load (the state holds the last stiffness)
            _rechord(ridge_state, j, k)
        held = ridge_state[0, j]
        deflection = held
        if moving:
            base = u + shifts[j]  # the base's position in table indices
            deflection = held + slip
            x = base - deflection / dx  # the crest's position, held by the surface
            xi = int(math.floor(x))
            excess = direction * (k * deflection - scale * _crest_at(crest, xi, x - xi))
            if excess > 0.0:  # released: the crest slides on to where the spring force meets the limit
                grid = xi + 1 if direction > 0.0 else (xi if x > xi else xi - 1)
                for _ in range(crest.size):  # (ends well within: the spring force falls by k·dx a position)
                    at_grid = direction * (k * (base - grid) * dx - scale * _crest_at(crest, grid, 0.0))
                    if at_grid <= 0.0:  # the crossing, on the straight piece between x and this position
                        x = x + (grid - x) * excess / (excess - at_grid)
                        break
                    x, excess = float(grid), at_grid
                    grid += 1 if direction > 0.0 else -1
                deflection = (base - x) * dx
            ridge_state[0, j] = deflection
            began, drop = _count_release(ridge_state, j, k * held, k * deflection, direction,
                                         k * RIDGE_RELEASE_LENGTH_M)
            events += began
            released += drop
        total += k * deflection
    return total, events, released


@njit(cache=True, inline="always")
def hertz_stiffness_per_cbrt_N(K):
    """The skin's contact stiffness dN/dδ at load N, over N^(1/3) (N/m per N^(1/3)): N = K·δ^1.5 gives
    1.5·K^(2/3)·N^(1/3)."""
    return 1.5 * K ** (2.0 / 3.0)


@njit(cache=True, inline="always")
def _texture_series(n0, r, kn, modulus_eff, layer_m):
    """The share (1) of the skin's indentation a texture leaves to the skin at load ``n0`` (N), patch radius ``r``
    (m) and skin contact stiffness ``kn`` (N/m): a soft texture layer (``modulus_eff`` Pa, ``layer_m`` m thick) yields
    in series with the skin, a flat-punch stiffness stiffening as the layer densifies toward its thickness (the
    derivative of δ_t = T(1 − exp(−N/(kT))))."""
    k_flat = 2.0 * r * modulus_eff
    k_tex = k_flat * math.exp(min(n0 / (k_flat * layer_m), 50.0))
    return k_tex / (kn + k_tex)


#: :func:`ridge_friction_coefficients`' ridges load from rest over this stretch of the track (m) before the stretch
#: their mean is taken over (model choice: a quarter of the 20 mm the estimate first slid over, the settling it
#: allowed then; the ridges start undeflected and reach their steady catch and release within a few features)
RIDGE_FRICTION_SETTLE_M = 5e-3


@njit(cache=True)
def ridge_friction_coefficients(crest, weights, shifts, offsets_m, gain, stiffness_per_length, radii, radius_1N, K,
                                modulus_eff, layer_m, dx, settle_n, track_n):
    """The ridge-resolved ridges' share of the friction coefficient (1), per patch radius of ``radii`` (m): what
    their catch and release dissipates per N of load over a slow forward slide from rest at the crest table's index
    0 (:func:`_ridges_step` in slips of half a table step ``dx`` (m), at the load N = (r / ``radius_1N``)³ that
    makes radius r and its texture series factor): their mean force over the ``track_n`` table positions after the
    first ``settle_n`` (over which they load from rest) less the rigid ridges' (the comb's slope force, whose mean
    over a stretch is the climb between its ends: conservative, and the comb keeps it).  The caller makes the
    table's positions from ``settle_n`` on the track the motion's patch crosses, so the share is the one the ridges
    take there (their mean over 20 mm stretches of 60-grit differs by ±12 % between stretches).  A texture's
    measured friction coefficient is a fingertip's, ridges included, so the step adds the ridges' force less this
    share times the load once a slip has loaded them.  Compliant ridges dissipate what they store at each release
    (Prandtl–Tomlinson), so this is positive on rough tracks and ~0 on smooth ones (a numerically tiny negative
    share is taken as 0); rigid ridges (``stiffness_per_length`` inf, the comb) or no gain store nothing: 0.  The
    ridges move only with the slip, not with time, so the slide's speed does not enter."""
    out = np.zeros(radii.size)
    if gain == 0.0 or math.isinf(stiffness_per_length) or stiffness_per_length == 0.0:
        return out
    shares, stiffness = np.zeros(offsets_m.size), np.zeros(offsets_m.size)
    rigid = np.full(offsets_m.size, math.inf)
    slip = 0.5 * dx
    settle = 2 * settle_n  # (two slips a position)
    steps = settle + max(2 * track_n, 1)
    kn_per_cbrt_n = hertz_stiffness_per_cbrt_N(K)
    for k in range(radii.size):
        r = radii[k]
        load = (r / radius_1N) ** 3
        kn = kn_per_cbrt_n * load ** (1.0 / 3.0)
        scale = load * _texture_series(load, r, kn, modulus_eff, layer_m) * gain
        _ridge_elements(weights, k, 0.0, offsets_m, r, stiffness_per_length, shares, stiffness)
        state = np.zeros((RIDGE_STATE_ROWS, offsets_m.size))
        total = 0.0
        for n in range(settle, steps):  # the rigid ridges' force at their bases: no state, no settling
            force, _, _ = _ridges_step(state, crest, shifts, shares, rigid, n * slip, dx, scale, 1.0, slip, 0.0)
            total -= force
        for n in range(steps):
            force, _, _ = _ridges_step(state, crest, shifts, shares, stiffness, n * slip, dx, scale, 1.0, slip, 0.0)
            if n >= settle:
                total += force
        out[k] = max(total / (steps - settle) / load, 0.0)  # (dissipation: ≥ 0; ~1e-5 below on smooth tracks)
    return out


@njit(cache=True, inline="always")
def _ridge_elements(weights, row, row_w, offsets_m, radius_m, stiffness_per_length, shares, stiffness):
    """Each ridge's load share (1: ``weights`` between rows ``row`` and ``row + 1`` by ``row_w``, as the comb's
    slopes are read) and tangential stiffness (N/m: ``stiffness_per_length`` × its chord across a patch of radius
    ``radius_m``, m; inf for rigid ridges), written to ``shares`` and ``stiffness``."""
    for j in range(offsets_m.size):
        share = weights[row, j]
        if row_w > 0.0:
            share = share * (1 - row_w) + weights[row + 1, j] * row_w
        shares[j] = share
        if math.isinf(stiffness_per_length):
            stiffness[j] = math.inf
        else:
            half_chord_sq = radius_m * radius_m - offsets_m[j] * offsets_m[j]
            stiffness[j] = stiffness_per_length * 2.0 * math.sqrt(half_chord_sq) if half_chord_sq > 0.0 else 0.0


@njit(cache=True)
def _slide_kernel(N0, V, dt, substeps, heights, slopes, radii, fluctuation, dx, state, touchdown_reference,
                  K, radius_1N, modulus_eff, layer_m, k_t, c_t, sigma0, sigma1, mu_s, mu_k, vs, mu_v,
                  out_normal, out_tangential, out_slip_velocity, out_position, resolved, crest, ridge_weights,
                  ridge_shifts, ridge_offsets, ridge_gain, ridge_stiffness_per_length, ridge_friction, ridge_state,
                  out_releases, out_released):
    """Advance the contact over one block (arrays of the grid's length); fills the four outputs in place.

    ``N0``, ``V``: nominal normal load (N) and stage velocity (m/s) per grid sample; ``heights``/``slopes``:
    spatial tables (radius × position) of the patch-averaged height (m) and the ridge-sampled slope (1);
    ``fluctuation``: the friction coefficient's relative fluctuation ε (1) along the same positions;
    ``modulus_eff``: the texture's E/(1 − ν²) (Pa) and ``layer_m`` its layer thickness (m): soft textures yield
    in series with the skin, so their features reach the fluid attenuated by k_tex/(k_n + k_tex);
    ``state``: x, z, p, touchdown height and slope, touching, the skin's last velocity and the ridges' last slip
    direction (updated in place); ``touchdown_reference``: a
    position-held finger (a rig) takes the touchdown spot as its reference, so its load changes with the height
    from there; a force-controlled finger (scripted slides) holds the commanded force on average, so heights are
    taken from the track's mean (zero).

    ``resolved``: the fingerprint is ridge-resolved (:class:`Ridges`' fields, passed one by one: ``crest``,
    ``ridge_weights``, ``ridge_shifts``, ``ridge_offsets`` m, ``ridge_gain``, ``ridge_stiffness_per_length`` N/m per
    m, ``ridge_state`` updated in place), with each grid sample's release events (count) and released force (N)
    written to ``out_releases`` and ``out_released``; otherwise those arguments are not read.
    """
    x, z, p, h_ref, s_ref = state[0], state[1], state[2], state[3], state[4]
    h = dt / substeps
    touching = 1 if state[5] > 0.5 else 0
    u_prev = state[6]
    # the direction (±1) of the last slip that moved the ridges, 0.0 before any since touchdown: their mean force
    # µ_r·N is taken off in it from then on, stuck or slipping, since a ridge a slip deflected keeps pushing
    ridge_direction = state[7]
    # the slip (m) the texture has crept under the held crests since the ridges last moved: each slip below the floor
    # moves none, but the crests are held by the surface, so once a slip has moved them (ridge_direction ≠ 0) the
    # slow slips are summed and carried with the next moving slip, or on their own once the sum passes the bristles'
    # elastic reach µs/σ0 (beyond it the skin creeps over the surface: the texture passes under the crests; within
    # it the bristles' pre-sliding deflection recovers, as when the skin settles after a stop)
    ridge_creep = state[8]
    creep_reach = mu_s / sigma0
    kn_per_cbrt_n = hertz_stiffness_per_cbrt_N(K)
    n0_last, kn, series, row, row_w = 0.0, 0.0, 0.0, 0, 0.0
    mu_ridges = 0.0
    ridge_shares, ridge_stiffness = np.zeros(ridge_offsets.size), np.zeros(ridge_offsets.size)
    slip_floor = RIDGE_SLIP_FLOOR_M_PER_S * h  # (m per substep)
    for n in range(N0.size):
        n0 = N0[n]
        v_stage = V[n]
        f_sum = 0.0
        vr_sum = 0.0
        normal = 0.0
        slope = 0.0
        ridge_force, ridge_mean, releases, released = 0.0, 0.0, 0, 0.0
        if n0 > 0.0 and n0 != n0_last:  # what depends on the load alone (kept while the load holds still)
            cbrt_n = n0 ** (1.0 / 3.0)
            r = radius_1N * cbrt_n  # the patch radius
            kn = kn_per_cbrt_n * cbrt_n
            series = _texture_series(n0, r, kn, modulus_eff, layer_m)
            row, row_w = _radius_weight(radii, r)
            if resolved:  # each ridge's load share (the comb's weights, between the same rows) and stiffness
                _ridge_elements(ridge_weights, row, row_w, ridge_offsets, r, ridge_stiffness_per_length,
                                ridge_shares, ridge_stiffness)
                # the ridges' mean share of the texture's friction coefficient (already in its measured µ)
                mu_ridges = ridge_friction[row]
                if row_w > 0.0:
                    mu_ridges = mu_ridges * (1 - row_w) + ridge_friction[row + 1] * row_w
            n0_last = n0
        for _ in range(substeps):
            ms, mk = mu_s, mu_k  # (no load: the fluctuation is not read, friction is nil anyway)
            if n0 > 0.0:
                height, slope_here, eps = _interp_tables(heights, slopes, fluctuation, row, row_w, p, dx)
                scale = max(1.0 + eps, MIN_FLUCTUATION_SCALE)
                ms, mk = mu_s * scale, mu_k * scale
                if touching == 0 and touchdown_reference:  # touchdown: the skin settles onto this spot
                    h_ref, s_ref = height, slope_here
                    touching = 1
                vr_last = v_stage - u_prev
                catching = abs(vr_last) / (abs(vr_last) + CATCH_VELOCITY_M_PER_S)
                # (no reference for the slope: ridges catch only while slipping, so a pressed finger feels no slope
                # force anyway, and while sliding up- and down-slopes average out)
                slope = series * catching * slope_here
                normal = max(0.0, n0 + kn * series * (height - h_ref))
            else:
                touching = 0
                normal = 0.0
                slope = 0.0
            if normal == 0.0:  # no load, no friction: the skin relaxes on its own, G(u) is linear
                if resolved:  # the ridges leave the surface: unloaded, no release events, no slip remembered
                    ridge_state[:, :] = 0.0
                    ridge_force, ridge_mean = 0.0, 0.0
                    ridge_direction = 0.0
                    ridge_creep = 0.0
                u = -k_t * x / (k_t * h + c_t)
                u_prev = u
                z = _bristle_after(z, v_stage - u, h, sigma0, ms, mk, vs)[0]
                x += u * h
                p += (v_stage - u) * h
                vr_sum += v_stage - u
                continue
            if v_stage == 0.0 and x == 0.0 and z == 0.0 and u_prev == 0.0:
                # nothing moves (the stage still, the skin unstrained, the bristles relaxed: a finger lowering or
                # held before the slide): G is odd about u = 0, so the step below would return u = 0 exactly,
                # after three evaluations; the same outcome, written out (x and p take the + 0.0 it would add)
                u_prev = 0.0
                if resolved:  # (no slip, no catching: the same ridge step as below with v_r = 0)
                    ridge_force, events, drop = _ridges_step(ridge_state, crest, ridge_shifts, ridge_shares,
                                                             ridge_stiffness, p, dx, normal * series * ridge_gain,
                                                             0.0, 0.0, slip_floor)
                    ridge_mean = ridge_direction * mu_ridges * normal
                    releases += events
                    released += drop
                x += 0.0
                p += 0.0
                f_sum += 0.0
                vr_sum += 0.0
                continue
            # implicit step for the skin velocity u: G(u) = k_t(x + u h) + c_t u - F(u) = 0
            u, znew, force = _step_velocity(u_prev, x, z, v_stage, h, normal, k_t, c_t, sigma0, sigma1, ms, mk, vs,
                                            mu_v)
            u_prev = u
            vr = v_stage - u
            if resolved:  # the ridges under the patch catch and release, read where the tables were
                ridge_slip = vr * h
                if ridge_direction != 0.0:  # (the crept slip joins this one; see ridge_creep above)
                    ridge_slip += ridge_creep
                    ridge_creep = 0.0
                    slow = abs(vr * h) < slip_floor and abs(ridge_slip) < creep_reach
                    if slow or abs(ridge_slip) < slip_floor:
                        ridge_creep, ridge_slip = ridge_slip, 0.0
                ridge_force, events, drop = _ridges_step(ridge_state, crest, ridge_shifts, ridge_shares,
                                                         ridge_stiffness, p, dx, normal * series * ridge_gain,
                                                         catching, ridge_slip, slip_floor)
                # (their mean in the last moving slip's direction: a slip below the floor moves no ridge and keeps
                # the direction; before the first, no ridge is deflected and nothing is taken off)
                if abs(ridge_slip) >= slip_floor:
                    ridge_direction = 1.0 if ridge_slip > 0.0 else -1.0
                ridge_mean = ridge_direction * mu_ridges * normal
                releases += events
                released += drop
            x += u * h
            z = znew
            p += vr * h
            f_sum += force
            vr_sum += vr
        out_normal[n] = normal
        out_tangential[n] = f_sum / substeps + normal * slope
        if resolved:  # the ridges' force about its mean, which the texture's µ holds already
            out_tangential[n] += ridge_force - ridge_mean
            out_releases[n] = releases
            out_released[n] = released
        out_slip_velocity[n] = vr_sum / substeps
        out_position[n] = p
    state[0], state[1], state[2], state[3], state[4], state[5], state[6] = x, z, p, h_ref, s_ref, float(touching), u_prev
    state[7] = ridge_direction
    state[8] = ridge_creep


def new_state(position_m: float = 0.0) -> np.ndarray:
    """A contact at rest at ``position_m`` on the texture (m)."""
    s = np.zeros(STATE_SIZE)
    s[2] = position_m
    return s
