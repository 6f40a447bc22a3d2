"""Which textures form the validation pairs of the texture experiment (D ch. 6: "eight pairs of similar textures").

D's experimenter chose the pairs by hand, for a human discrimination study, taking care that the two textures of a
pair had no property other than texture — compliance or thermal feel — that a person could tell them apart by.
D's eight pairs were a mix, picked partly with the training confusion matrices (D p. 138): pairs people found
similar but the sensor did not, the reverse, and pairs similar to both; D gives neither the counts nor a rule.
``similar-description`` (the default) stands for the human side of that choice with the textures' physical
descriptions in the library, never with a classifier's outcome. Two textures are *admissible* as a pair when they

- belong to one library group (one kind of material, as D's human subjects saw it);
- are of one thermal ``material`` (same conductivity, density, heat capacity: same thermal feel);
- feel equally compliant: both rigid to a fingertip (modulus ≥ :data:`RIGID_MODULUS_PA`, ten times the ~1 MPa
  fingertip or BioTac skin, so the finger, not the surface, deforms) or moduli within a factor
  :data:`COMPLIANCE_RATIO` (about two Weber fractions of compliance discrimination, ~22 %, Tan et al. 1995);
- both have a periodic relief (ridges, weave) or both have none (they look alike).

Among admissible pairs the *description distance* is the Euclidean distance of
:func:`description_features` — log₁₀ RMS height, log₁₀ correlation length, Hurst exponent, static friction μ,
and for ridged textures log₁₀ track period and log₁₀ amplitude of the strongest periodic component — each
divided by its spread (standard deviation) over the library's textures outside the test surfaces — D's 117, and a
library's own groups (:mod:`bench.textures.library`) — so no feature weighs by its units. Logs for lengths (a
ratio of heights or periods is what changes the feel, Weber's law); linear for μ and the Hurst exponent
(dimensionless, narrow ranges). A feature fewer than two of those textures have (a library with one ridged texture),
or that all of them share, has no spread and weighs nothing.

Pairs are taken greedily, nearest first (ties by texture number), disjoint, at most one pair per library group
while groups remain (D's sixteen textures came from different kinds of material), then from any group.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

PAIR_CHOICES = ("similar-description", "random-within-group", "most-confused")
#: a surface at least this stiff (Pa) feels rigid to a fingertip (~1 MPa pulp, BioTac skin alike)
RIGID_MODULUS_PA = 10e6
#: largest modulus ratio of two compliant surfaces that feel equally soft
COMPLIANCE_RATIO = 1.5
FEATURES = ("log10 RMS height", "log10 correlation length", "Hurst", "mu_static", "log10 track period",
            "log10 ridge amplitude")


def description_features(t) -> np.ndarray:
    """The six :data:`FEATURES` of a texture (lengths in m before the log); the two periodic ones NaN without
    a periodic relief."""
    p = max(t.periodic, key=lambda c: c.amplitude_m) if t.periodic else None
    return np.array([math.log10(t.rms_height_m), math.log10(t.correlation_length_m), t.hurst, t.mu_static,
                     math.log10(p.track_period_m) if p else np.nan, math.log10(p.amplitude_m) if p else np.nan])


def feature_scales(lib: dict) -> np.ndarray:
    """Spread (standard deviation) of each feature over the library's textures outside the test surfaces (D's 117
    and the library's own groups; periodic features: over the ridged ones); NaN for a feature fewer than two of
    them have, or that all of them share, which then weighs nothing in :func:`description_distance`."""
    from bench.textures.library import TEST_GROUP

    f = np.array([description_features(t) for n, t in sorted(lib.items()) if t.group != TEST_GROUP[0]])
    f = f.reshape(-1, len(FEATURES))
    with warnings.catch_warnings():  # (a feature no texture has: nanstd's warning; the NaN below says it)
        warnings.simplefilter("ignore", RuntimeWarning)
        spread = np.nanstd(f, axis=0)
    spread[~(spread > 0)] = np.nan  # none, one or every texture alike: no spread (a lone value's is 0)
    return spread


def admissible(ta, tb) -> str | None:
    """None if two textures may form a similar pair, else the reason they may not."""
    if ta.group != tb.group:
        return "different groups"
    if ta.material != tb.material:
        return "different thermal materials"
    ea, eb = ta.modulus_Pa, tb.modulus_Pa
    if min(ea, eb) < RIGID_MODULUS_PA and max(ea, eb) > COMPLIANCE_RATIO * min(ea, eb):
        return "different compliance"
    if bool(ta.periodic) != bool(tb.periodic):
        return "one has a periodic relief, the other none"
    return None


def why_not_pairs(textures, lib: dict, most: int = 4) -> list[str]:
    """Why textures of one library group among ``textures`` are no similar pair: ``"T43/T46: different thermal
    materials"`` for the first ``most`` such pairs (by number), then how many more."""
    ids = sorted(int(n) for n in textures)
    found = [f"T{a}/T{b}: {why}" for i, a in enumerate(ids) for b in ids[i + 1:]
             if lib[a].group == lib[b].group and (why := admissible(lib[a], lib[b])) is not None]
    return found[:most] + ([f"{len(found) - most} more"] if len(found) > most else [])


def description_distance(ta, tb, scales: np.ndarray) -> float:
    """Distance of two textures' descriptions in units of the library's spread (absent periodic features: 0)."""
    d = np.nan_to_num((description_features(ta) - description_features(tb)) / scales)
    return float(np.sqrt(np.sum(d * d)))


def similar_description_pairs(textures, n_pairs: int, lib: dict) -> list[tuple[int, int]]:
    """Up to ``n_pairs`` disjoint admissible pairs among ``textures`` (ids), nearest descriptions first, one per
    library group while possible (see the module docstring)."""
    scales = feature_scales(lib)
    ids = sorted(int(n) for n in textures)
    cands = sorted((description_distance(lib[a], lib[b], scales), a, b)
                   for i, a in enumerate(ids) for b in ids[i + 1:] if admissible(lib[a], lib[b]) is None)
    used, groups, pairs = set(), set(), []
    for one_per_group in (True, False):
        for _, a, b in cands:
            if len(pairs) == n_pairs:
                return pairs
            if a in used or b in used or (one_per_group and lib[a].group in groups):
                continue
            pairs.append((a, b))
            used |= {a, b}
            groups.add(lib[a].group)
    return pairs


def pair_separation_sigma(model, pairs) -> list[list[float]]:
    """Diagnostic only: per pair and property, the largest |difference of the training means| over the pooled
    training σ, √((σa² + σb²)/2), over the model's movements (those exploration can choose)."""
    out = []
    for a, b in pairs:
        ia, ib = model.texture_index([a, b])
        pooled = np.sqrt((model.sigma[ia] ** 2 + model.sigma[ib] ** 2) / 2)  # (M, 3)
        out.append([float(x) for x in np.max(np.abs(model.mean[ia] - model.mean[ib]) / pooled, axis=0)])
    return out


def nearest_neighbour_sigma(model, textures) -> dict[int, tuple[float, int]]:
    """Diagnostic only: per texture of ``textures``, how far its nearest other texture of the model lies — the
    largest |difference of the training means| over the pooled σ, over every property and movement of the model
    — and which texture that is: {texture: (separation in σ, nearest texture)}."""
    out = {}
    for t in textures:
        i = int(model.texture_index([t])[0])
        pooled = np.sqrt((model.sigma[i] ** 2 + model.sigma ** 2) / 2)  # (T, M, 3)
        sep = np.max(np.abs(model.mean[i] - model.mean) / pooled, axis=(1, 2))
        sep[i] = np.inf
        j = int(np.argmin(sep))
        out[int(t)] = (float(sep[j]), int(model.textures[j]))
    return out
