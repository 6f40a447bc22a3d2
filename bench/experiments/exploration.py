"""Bayesian exploration (D ch. 6, eqs 6.1–6.13): the texture model, the pilot stage and virtual exploration.

Vocabulary (D's):

* a **trial table** (:class:`TrialTable`) is long-format data: one row per (texture, movement, property, trial)
  with the property's value (traction in A, roughness and fineness as the logs of
  :mod:`bench.textures.properties`). Ids are non-negative integers; property ids are 0 traction, 1 roughness,
  2 fineness (:data:`PROPERTIES`).
* the **model** (:class:`TextureModel`, :func:`fit_model`) is one normal distribution per (texture, movement,
  property), fitted to the training trials (D: five per combination).
* **confusion** between textures i and j at movement m and property p is the Bhattacharyya coefficient of their
  two normals (D eqs 6.5–6.7, :func:`bhattacharyya`); the **expected uncertainty** after making (m, p) is
  ``U = 1 − Σ_i P_i² / Σ_j C_ij P_j`` (D eq. 6.11, :func:`expected_uncertainty`); the **benefit** of making it is
  ``B = 1 − U^α``, ``α = 1/n`` (D eqs 6.12–6.13, :func:`benefit`).
* the **pilot stage** (:func:`pilot_uncertainty`, :func:`least_uncertain_movements`) ranks movements by U with
  equal priors over a set of textures, per property, optionally excluding movements (the high-power ones that
  wore the fingerprints, :func:`movement_grid`).
* **virtual exploration** (:func:`simulate`) replays D's Monte Carlo: at each step a strategy picks one
  (movement, property); the measurement is that property from a randomly chosen *validation* trial of the true
  texture at that movement (D: "a randomly selected trial from the unseen validation set of the texture being
  explored was given to the classifier"); the posterior over the candidates is updated by Bayes' rule
  (D eqs 6.3–6.4) until one candidate's probability exceeds the threshold (D: 99.9 % for pairs, 99 % for the
  117-way task) or ``max_moves`` (10) movements were made; the decision is the most probable candidate.

Decisions where D is silent or ambiguous (each is a parameter or documented here):

* **one property per movement**: every movement yields all three properties, but D "only considered a single
  signal during an exploration movement" (multivariate use converged fast and often wrongly) and chose among all
  nine movement × signal combinations. So each step picks a (movement, property) pair and updates the posterior
  with that one value.
* **α's n counts the movement** made before in this exploration, whatever property was read from it (D: "the
  number of times an exploratory movement has been made previously"), and the candidate use itself counts:
  ``n = 1 + previous uses``. So a first use has α = 1, B = 1 − U (D's first pick is the movement of least
  uncertainty, as D reports: "all textures starting with equal probability ... this first movement will produce
  the largest benefit"; taking n = previous uses literally would give α = ∞ and B = 1 for every unused movement).
  ``make_bayesian(count_by="combination")`` counts (movement, property) pairs instead.
* **trials are drawn with replacement** (a movement may be repeated more often than there are validation trials).
* **σ**: the sample standard deviation (ddof = 1, as MATLAB's ``std``) with a floor
  ``max(sigma_floor, sigma_floor_rel × spread)``, ``spread`` the standard deviation of the texture means at that
  (movement, property): σ is never 0 and a combination whose trials happen to coincide does not become
  infinitely sharp.
* **threshold**: a candidate must *exceed* it (D: "greater than 99.9 %"). Exact ties (e.g. identical textures)
  are broken uniformly at random, both between equally beneficial choices and in the final decision.
* **cycle** visits the best movement for traction, roughness, fineness in that order; **random** draws uniformly
  from all movement × property combinations.
* **pruning**: in the benefit computation, candidates with posterior ≤ ``prune`` (default 1e-12) are left out of
  the sums in U; this changes U by at most their total probability. ``prune=0`` is the exact formula.

Randomness: each simulation draws all its uniforms from its own generator, seeded by
``SeedSequence(seed, spawn_key=(true_texture, simulation index))``; and every per-simulation computation is
independent of which other simulations run in the same batch (sequential sums, no BLAS). So a simulation's result
does not depend on how simulations are chunked, ordered or distributed (e.g. as Dask tasks).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from bench.errors import BenchError

#: Property ids and names.
PROPERTIES = ("traction", "roughness", "fineness")
TRACTION, ROUGHNESS, FINENESS = 0, 1, 2
#: D's stopping thresholds: pairs of textures, and absolute identification among many.
PAIR_THRESHOLD, ABSOLUTE_THRESHOLD = 0.999, 0.99
#: D's limit on the number of exploratory movements.
MAX_MOVES = 10
#: Default σ floors (see :func:`fit_model`).
SIGMA_FLOOR, SIGMA_FLOOR_REL = 1e-12, 1e-3
#: Default pruning threshold for the benefit computation (see module docstring).
PRUNE = 1e-12
_CHUNK_ELEMENTS = 1 << 21  # per-chunk size of the gathered confusion block in the benefit computation


class ExplorationError(BenchError, ValueError):
    """Bad input to the exploration functions (malformed table, incomplete model, unknown texture)."""


def _seqsum(x: np.ndarray, axis: int) -> np.ndarray:
    """Sum along ``axis`` in index order (a cumulative sum's last element): bit-identical whatever the other
    dimensions are, and unchanged by trailing zeros."""
    return np.take(np.cumsum(x, axis=axis), -1, axis=axis)


# ------------------------------------------------------------------------------------------------ trial table


@dataclass(frozen=True)
class TrialTable:
    """Long-format trials: equal-length 1-D arrays ``texture``, ``movement``, ``prop`` (0 traction, 1 roughness,
    2 fineness), ``trial`` (ints ≥ 0) and ``value`` (float; A for traction, ln-units for the others).
    Each (texture, movement, prop, trial) appears at most once."""

    texture: np.ndarray
    movement: np.ndarray
    prop: np.ndarray
    trial: np.ndarray
    value: np.ndarray

    def __post_init__(self):
        n = None
        for name in ("texture", "movement", "prop", "trial"):
            a = np.asarray(getattr(self, name))
            if a.ndim != 1:
                raise ExplorationError(f"trial table: {name} must be 1-D (got shape {a.shape})")
            if a.size and not (np.issubdtype(a.dtype, np.integer) or np.all(np.mod(a, 1) == 0)):
                raise ExplorationError(f"trial table: {name} must hold integers")
            a = a.astype(np.int64)
            if a.size and a.min() < 0:
                raise ExplorationError(f"trial table: {name} ids must be >= 0")
            if n is not None and a.size != n:
                raise ExplorationError(f"trial table: {name} has {a.size} rows, texture has {n}")
            n = a.size
            object.__setattr__(self, name, a)
        v = np.asarray(self.value, dtype=np.float64)
        if v.ndim != 1 or v.size != n:
            raise ExplorationError(f"trial table: value must be 1-D with {n} rows (got shape {v.shape})")
        if not np.all(np.isfinite(v)):
            raise ExplorationError("trial table: value contains NaN or infinite entries")
        object.__setattr__(self, "value", v)
        if n and self.prop.max() >= len(PROPERTIES):
            raise ExplorationError(f"trial table: prop ids are 0..{len(PROPERTIES) - 1} ({', '.join(PROPERTIES)})")
        if n:
            keys = np.stack([self.texture, self.movement, self.prop, self.trial], axis=1)
            if np.unique(keys, axis=0).shape[0] != n:
                raise ExplorationError("trial table: duplicate (texture, movement, prop, trial) rows")

    def __len__(self) -> int:
        return int(self.value.size)

    @classmethod
    def from_wide(cls, texture, movement, trial, traction, roughness, fineness) -> "TrialTable":
        """From one row per trial with all three properties (e.g. :func:`bench.textures.properties.properties`
        of each recording) to the long format."""
        cols = [np.asarray(c) for c in (texture, movement, trial)]
        vals = [np.asarray(v, dtype=np.float64) for v in (traction, roughness, fineness)]
        n = cols[0].size
        return cls(np.tile(cols[0], 3), np.tile(cols[1], 3), np.repeat(np.arange(3), n), np.tile(cols[2], 3),
                   np.concatenate(vals))

    @classmethod
    def concat(cls, tables: Sequence["TrialTable"]) -> "TrialTable":
        """Rows of all ``tables`` in order."""
        return cls(*(np.concatenate([getattr(t, k) for t in tables])
                     for k in ("texture", "movement", "prop", "trial", "value")))

    def select(self, textures=None, movements=None, props=None) -> "TrialTable":
        """The rows whose texture, movement and prop ids are in the given collections (None: any)."""
        keep = np.ones(len(self), bool)
        for col, ids in ((self.texture, textures), (self.movement, movements), (self.prop, props)):
            if ids is not None:
                keep &= np.isin(col, np.asarray(ids))
        return TrialTable(self.texture[keep], self.movement[keep], self.prop[keep], self.trial[keep],
                          self.value[keep])


# ------------------------------------------------------------------------------------------------ model


@dataclass(frozen=True)
class TextureModel:
    """Normals per (texture, movement, property): ``mean``, ``sigma`` and ``n_trials`` of shape (T, M, 3), indexed
    by the sorted id arrays ``textures`` (T,) and ``movements`` (M,)."""

    textures: np.ndarray
    movements: np.ndarray
    mean: np.ndarray
    sigma: np.ndarray
    n_trials: np.ndarray
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def texture_index(self, ids) -> np.ndarray:
        """Indices into ``textures`` of the given texture ids (ExplorationError on unknown ids)."""
        return _index(self.textures, ids, "texture")

    def movement_index(self, ids) -> np.ndarray:
        """Indices into ``movements`` of the given movement ids (ExplorationError on unknown ids)."""
        return _index(self.movements, ids, "movement")

    def confusion(self, textures=None) -> np.ndarray:
        """Confusion matrices C[i, j, m, p] among ``textures`` (ids; default all), D eq. 6.7. Cached."""
        idx = np.arange(self.textures.size) if textures is None else self.texture_index(textures)
        key = idx.tobytes()
        if key not in self._cache:
            mu, s = self.mean[idx], self.sigma[idx]
            self._cache[key] = bhattacharyya(mu[:, None], s[:, None], mu[None, :], s[None, :])
        return self._cache[key]


def _index(ids_sorted: np.ndarray, ids, what: str) -> np.ndarray:
    ids = np.atleast_1d(np.asarray(ids, dtype=np.int64))
    pos = np.clip(np.searchsorted(ids_sorted, ids), 0, max(ids_sorted.size - 1, 0))
    bad = ids_sorted.size == 0 or not np.all(ids_sorted[pos] == ids)
    if bad:
        unknown = ids if ids_sorted.size == 0 else ids[ids_sorted[pos] != ids]
        raise ExplorationError(f"unknown {what} id(s): {', '.join(map(str, unknown[:10]))}")
    return pos


def fit_model(table: TrialTable, sigma_floor: float = SIGMA_FLOOR,
              sigma_floor_rel: float = SIGMA_FLOOR_REL) -> TextureModel:
    """Fit a normal per (texture, movement, property) to ``table`` (D: from the training trials).

    mean = sample mean; σ = sample standard deviation with ddof = 1 (0 for a single trial), floored at
    ``max(sigma_floor, sigma_floor_rel × spread)`` where ``spread`` is the standard deviation (ddof = 0) of the
    texture means at that (movement, property). Every (texture, movement, property) of the table's textures and
    movements must have at least one trial.
    """
    if len(table) == 0:
        raise ExplorationError("trial table is empty")
    tex, ti = np.unique(table.texture, return_inverse=True)
    mov, mi = np.unique(table.movement, return_inverse=True)
    T, M, P = tex.size, mov.size, len(PROPERTIES)
    flat = (ti * M + mi) * P + table.prop
    n = np.bincount(flat, minlength=T * M * P)
    if np.any(n == 0):
        t, m, p = np.unravel_index(np.flatnonzero(n == 0), (T, M, P))
        missing = [f"texture {tex[a]} movement {mov[b]} {PROPERTIES[c]}" for a, b, c in zip(t[:5], m[:5], p[:5])]
        raise ExplorationError(f"incomplete trial table: {int(np.sum(n == 0))} (texture, movement, property) "
                               f"combination(s) without trials, e.g. {'; '.join(missing)}")
    mean = np.bincount(flat, weights=table.value, minlength=T * M * P) / n
    ss = np.bincount(flat, weights=(table.value - mean[flat]) ** 2, minlength=T * M * P)
    sigma = np.sqrt(np.where(n > 1, ss / np.maximum(n - 1, 1), 0.0))
    mean, sigma, n = mean.reshape(T, M, P), sigma.reshape(T, M, P), n.reshape(T, M, P)
    floor = _sigma_floor(mean, sigma_floor, sigma_floor_rel)
    return TextureModel(tex, mov, mean, np.maximum(sigma, floor), n)


def _sigma_floor(mean: np.ndarray, sigma_floor: float, sigma_floor_rel: float) -> np.ndarray:
    """σ floor per (movement, property) from the texture means (T, M, P): max(floor, rel × their spread)."""
    floor = np.maximum(sigma_floor, sigma_floor_rel * mean.std(axis=0))
    if not np.all(floor > 0):
        raise ExplorationError(f"sigma_floor must be > 0 (got {sigma_floor})")
    return floor


def spread_check(train: TrialTable, validation: TrialTable, sigma_floor: float = SIGMA_FLOOR,
                 sigma_floor_rel: float = SIGMA_FLOOR_REL) -> dict:
    """Do the validation trials look like the training trials?  Per property: the median |z| of each validation
    trial against its texture's training normal (:func:`fit_model`), the median |z| of each training trial
    against the normal of the *other* training trials of its texture and movement (leave-one-out, same σ floor;
    cells with fewer than 3 trials skipped), and their ratio.  Near 1: validation trials scatter as training
    trials do; well above 1: they are shifted (another skin state, another session).  Dimensionless."""
    model = fit_model(train, sigma_floor, sigma_floor_rel)
    floor = _sigma_floor(model.mean, sigma_floor, sigma_floor_rel)
    ti, mi, p = model.texture_index(validation.texture), model.movement_index(validation.movement), validation.prop
    z_val = (validation.value - model.mean[ti, mi, p]) / model.sigma[ti, mi, p]
    T, M, P = model.mean.shape
    x = train.value
    g = (model.texture_index(train.texture) * M + model.movement_index(train.movement)) * P + train.prop
    n, total, total_sq = (np.bincount(g, weights=w, minlength=T * M * P)[g] for w in (None, x, x * x))
    n1 = n - 1  # trials left when one is held out
    keep = n1 >= 2
    n1, x, mean1 = n1[keep], x[keep], (total[keep] - x[keep]) / n1[keep]
    var1 = (total_sq[keep] - x * x - n1 * mean1**2) / (n1 - 1)
    floor_rows = floor[model.movement_index(train.movement)[keep], train.prop[keep]]
    z_loo = (x - mean1) / np.maximum(np.sqrt(np.maximum(var1, 0.0)), floor_rows)
    out = {}
    for name, v_sel, t_sel in [(name, validation.prop == k, train.prop[keep] == k) for k, name in enumerate(PROPERTIES)] \
            + [("all", np.ones(z_val.size, bool), np.ones(z_loo.size, bool))]:
        zv = float(np.median(np.abs(z_val[v_sel]))) if v_sel.any() else float("nan")
        zl = float(np.median(np.abs(z_loo[t_sel]))) if t_sel.any() else float("nan")
        out[name] = {"validation_median_abs_z": zv, "leave_one_out_median_abs_z": zl, "ratio": zv / zl,
                     "n_validation": int(v_sel.sum()), "n_training": int(t_sel.sum())}
    return out


# ------------------------------------------------------------------------------------------------ D's formulas


def bhattacharyya(mu1, sigma1, mu2, sigma2) -> np.ndarray:
    """Bhattacharyya coefficient ∫√(p·q) dx of N(mu1, sigma1²) and N(mu2, sigma2²) (broadcasting; D eq. 6.7):
    ``√(2σ1σ2/(σ1²+σ2²)) · exp(−(µ1−µ2)² / (4(σ1²+σ2²)))``, in [0, 1], 1 for identical normals."""
    mu1, sigma1, mu2, sigma2 = (np.asarray(a, dtype=np.float64) for a in (mu1, sigma1, mu2, sigma2))
    v = sigma1**2 + sigma2**2
    return np.sqrt(2.0 * sigma1 * sigma2 / v) * np.exp(-((mu1 - mu2) ** 2) / (4.0 * v))


def expected_uncertainty(confusion: np.ndarray, prior: np.ndarray) -> np.ndarray:
    """Expected uncertainty U (D eq. 6.11) for each trailing combination of ``confusion`` (T, T, ...) under
    ``prior`` (T,) (normalised here): ``U = 1 − Σ_i P_i² / Σ_j C_ij P_j``; terms with P_i = 0 vanish."""
    p = np.asarray(prior, dtype=np.float64)
    p = p / p.sum()
    c = np.asarray(confusion, dtype=np.float64)
    q = np.tensordot(p, c, axes=([0], [1]))  # Σ_j C_ij P_j, shape (T, ...)
    pi = p.reshape((-1,) + (1,) * (c.ndim - 2))
    terms = np.divide(pi**2, q, out=np.zeros(q.shape), where=pi > 0)
    return 1.0 - terms.sum(axis=0)


def benefit(uncertainty, n_made) -> np.ndarray:
    """Benefit ``B = 1 − U^α``, ``α = 1/n``, ``n = 1 + n_made`` (D eqs 6.12–6.13; ``n_made`` = times the movement
    was already made). U is clipped to [0, 1] (rounding)."""
    u = np.clip(np.asarray(uncertainty, dtype=np.float64), 0.0, 1.0)
    return 1.0 - u ** (1.0 / (1.0 + np.asarray(n_made, dtype=np.float64)))


def update_posterior(prior, mean, sigma, value) -> np.ndarray:
    """Bayes' rule with normal likelihoods (D eqs 6.3–6.4): ``prior`` (..., T), per-texture ``mean`` and ``sigma``
    (..., T), measured ``value`` (...) → posterior (..., T) summing to 1 along the last axis. Computed in the log
    domain (no underflow when a value is far from every texture); textures with prior 0 stay at 0."""
    prior = np.asarray(prior, dtype=np.float64)
    with np.errstate(divide="ignore"):
        lp = np.log(prior) + _loglik(np.asarray(value, dtype=np.float64)[..., None], mean, sigma)
    return _normalise(lp)[1]


def _loglik(x, mean, sigma):
    z = (x - mean) / sigma
    return -0.5 * z * z - np.log(sigma)


def _normalise(logp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(log posterior, posterior) from unnormalised log probabilities along the last axis (row-wise exact)."""
    z = logp - logp.max(axis=-1, keepdims=True)
    e = np.exp(z)
    s = _seqsum(e, -1)[..., None]
    return z - np.log(s), e / s


# ------------------------------------------------------------------------------------------------ pilot stage


def movement_grid(n_steps: int = 6) -> dict[str, np.ndarray]:
    """D's grid of movements (eqs 6.20–6.22): ids 0…35 = (i_force − 1)·6 + (i_velocity − 1), with
    ``force_N = 0.2·10^((i−1)/5)``, ``velocity_m_s = 0.01·10^((i−1)/5)`` and ``power_level = i_force + i_velocity``
    (equal sliding power along an anti-diagonal; level 7 is the main one). ``high_power`` marks levels above 7,
    the lower-right half plane D excluded for wearing the fingerprints (D names 1.26 N at 6.31 cm/s, level 10,
    among them; D's figure, not its text, gives the exact boundary: pass another mask if yours differs)."""
    i_f, i_v = np.meshgrid(np.arange(1, n_steps + 1), np.arange(1, n_steps + 1), indexing="ij")
    i_f, i_v = i_f.ravel(), i_v.ravel()
    level = i_f + i_v
    return {"movement": np.arange(i_f.size), "i_force": i_f, "i_velocity": i_v,
            "force_N": 0.2 * 10.0 ** ((i_f - 1) / 5), "velocity_m_s": 0.01 * 10.0 ** ((i_v - 1) / 5),
            "power_level": level, "high_power": level > n_steps + 1}


def pilot_uncertainty(model: TextureModel, textures=None, exclude_movements=()) -> np.ndarray:
    """U (M, 3) per movement and property with equal priors over ``textures`` (ids; default all) — D's pilot
    analysis (Fig. 6-7). Excluded movements (ids) get NaN."""
    c = model.confusion(textures)
    u = expected_uncertainty(c, np.ones(c.shape[0]))
    if len(exclude_movements):
        u[model.movement_index(exclude_movements)] = np.nan
    return u


def least_uncertain_movements(model: TextureModel, textures=None, exclude_movements=()) -> np.ndarray:
    """Movement id (3,) of least pilot uncertainty for each property (traction, roughness, fineness); ties go to
    the lowest movement id."""
    u = pilot_uncertainty(model, textures, exclude_movements)
    if np.all(np.isnan(u)):
        raise ExplorationError("every movement is excluded")
    return model.movements[np.nanargmin(u, axis=0)]


# ------------------------------------------------------------------------------------------------ strategies


@dataclass(frozen=True)
class ExplorationContext:
    """What strategies may use, fixed for one simulation call: the model restricted to the ``candidates`` (K,)
    (``mean``/``sigma`` (K, M, 3), ``confusion`` (K, K, M·3)), ``best`` movement index per property (for cycling),
    and the pruning threshold."""

    model: TextureModel
    candidates: np.ndarray
    mean: np.ndarray
    sigma: np.ndarray
    confusion: np.ndarray
    best: np.ndarray
    prune: float
    backend: str = "auto"

    @property
    def n_choices(self) -> int:
        """Number of (movement, property) combinations: choice index q = movement_index·3 + property."""
        return self.mean.shape[1] * self.mean.shape[2]


@dataclass
class ExplorationState:
    """The live simulations' state at a step: ``posterior`` (S, K) over the candidates, ``made`` (S, M, 3) how
    often each (movement, property) was chosen so far, and ``step`` (0-based)."""

    posterior: np.ndarray
    made: np.ndarray
    step: int


#: A strategy maps (context, state, u) to choice indices (S,), u (S,) being uniforms in [0, 1) from each
#: simulation's own generator. It must be pure: its answer depends only on these arguments.
Strategy = Callable[[ExplorationContext, ExplorationState, np.ndarray], np.ndarray]


def _pick_max(score: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Index of the maximum along the last axis per row; exact ties broken uniformly using ``u``."""
    ties = score == score.max(axis=-1, keepdims=True)
    k = np.cumsum(ties, axis=-1)
    target = np.floor(u * k[..., -1]).astype(np.int64) + 1
    return np.argmax(k >= target[..., None], axis=-1)


def uncertainty_rows(confusion: np.ndarray, posterior: np.ndarray, prune: float = PRUNE,
                     backend: str = "auto") -> np.ndarray:
    """U (S, Q) for each row of ``posterior`` (S, K) and each of the Q matrices in ``confusion`` (K, K, Q),
    summing only over candidates with posterior > ``prune``, in index order and sequentially, so a row's result
    depends on that row alone (not on the batch it is computed in).

    ``backend``: "numpy" (vectorised over the rows, gathering each row's k×k×Q block), "numba" (a compiled loop
    over rows reading the blocks in place: ~10× faster, same operations in the same order) or "auto" (numba when
    it imports)."""
    posterior = np.ascontiguousarray(posterior, dtype=np.float64)
    confusion = np.ascontiguousarray(confusion, dtype=np.float64)
    if backend == "auto":
        backend = "numba" if _numba_kernel() is not None else "numpy"
    if backend == "numba":
        kernel = _numba_kernel()
        if kernel is None:
            raise ExplorationError("numba is not available")
        out = np.empty((posterior.shape[0], confusion.shape[2]))
        kernel(confusion, posterior, float(prune), out)
        return out
    if backend != "numpy":
        raise ValueError(f"backend must be 'auto', 'numba' or 'numpy' (got {backend!r})")
    S, K = posterior.shape
    Q = confusion.shape[2]
    active = posterior > prune
    count = active.sum(axis=1)
    order = np.argsort(~active, axis=1, kind="stable")  # each row's active candidates first, in index order
    out = np.empty((S, Q))
    # rows are grouped by how many candidates they keep (no padding), and chunked to bound memory
    for k in np.unique(count):
        rows = np.flatnonzero(count == k)
        if k == 0:  # nothing above the pruning threshold: no term, U = 1 (as the compiled kernel)
            out[rows] = 1.0
            continue
        step = max(1, _CHUNK_ELEMENTS // (int(k) * int(k) * Q))
        for a in range(0, rows.size, step):
            r = rows[a:a + step]
            idx = order[r, :k]
            p = np.take_along_axis(posterior[r], idx, axis=1)  # (s, k)
            g = confusion[idx[:, :, None], idx[:, None, :]]    # (s, k, k, Q)
            q = _seqsum(g * p[:, None, :, None], axis=2)        # Σ_j C_ij P_j, (s, k, Q)
            out[r] = 1.0 - _seqsum((p * p)[:, :, None] / q, axis=1)
    return out


_KERNEL: list = []


def _numba_kernel():
    """The compiled U kernel (built on first use; None when numba is unavailable)."""
    if not _KERNEL:
        try:
            import numba
        except ImportError:  # pragma: no cover - numba is a pinned dependency
            _KERNEL.append(None)
            return None

        @numba.njit(cache=True, nogil=True)
        def kernel(conf, post, prune, out):  # pragma: no cover - compiled
            S, K = post.shape
            Q = conf.shape[2]
            idx = np.empty(K, np.int64)
            acc = np.empty(Q)
            tot = np.empty(Q)
            for s in range(S):
                k = 0
                for j in range(K):
                    if post[s, j] > prune:
                        idx[k] = j
                        k += 1
                for c in range(Q):
                    tot[c] = 0.0
                for a in range(k):
                    i = idx[a]
                    for c in range(Q):
                        acc[c] = 0.0
                    for b in range(k):
                        j = idx[b]
                        pj = post[s, j]
                        for c in range(Q):
                            acc[c] += conf[i, j, c] * pj
                    pi2 = post[s, i] * post[s, i]
                    for c in range(Q):
                        tot[c] += pi2 / acc[c]
                for c in range(Q):
                    out[s, c] = 1.0 - tot[c]

        _KERNEL.append(kernel)
    return _KERNEL[0]


def make_bayesian(count_by: str = "movement") -> Strategy:
    """D's Bayesian exploration: the (movement, property) of maximal benefit ``1 − U^(1/n)``; ``count_by``
    "movement" (D) or "combination" decides what n counts."""
    if count_by not in ("movement", "combination"):
        raise ValueError(f"count_by must be 'movement' or 'combination' (got {count_by!r})")

    def bayesian(ctx: ExplorationContext, state: ExplorationState, u: np.ndarray) -> np.ndarray:
        post = state.posterior
        if post.shape[0] > 1 and np.array_equal(post, np.broadcast_to(post[:1], post.shape)):
            unc = np.broadcast_to(uncertainty_rows(ctx.confusion, post[:1], ctx.prune, ctx.backend),
                                  (post.shape[0], ctx.n_choices))
        else:
            unc = uncertainty_rows(ctx.confusion, post, ctx.prune, ctx.backend)
        made = state.made
        if count_by == "movement":
            made = np.broadcast_to(made.sum(axis=2, keepdims=True), made.shape)
        return _pick_max(benefit(unc, made.reshape(made.shape[0], -1)), u)

    bayesian.__name__ = "bayesian" if count_by == "movement" else "bayesian_by_combination"
    return bayesian


def cycle(ctx: ExplorationContext, state: ExplorationState, u: np.ndarray) -> np.ndarray:
    """Cycle through the best movement of each property: traction, roughness, fineness, traction, …"""
    p = state.step % len(PROPERTIES)
    return np.full(u.shape, ctx.best[p] * len(PROPERTIES) + p, dtype=np.int64)


def random_choice(ctx: ExplorationContext, state: ExplorationState, u: np.ndarray) -> np.ndarray:
    """A uniformly random (movement, property) combination."""
    return np.minimum((u * ctx.n_choices).astype(np.int64), ctx.n_choices - 1)


STRATEGIES: dict[str, Strategy] = {"bayesian": make_bayesian(), "cycle": cycle, "random": random_choice}


# ------------------------------------------------------------------------------------------------ simulation


@dataclass(frozen=True)
class ExplorationResult:
    """Per simulation (S rows): ``sim_index``; ``decided`` texture id; ``correct``; ``n_moves``; ``converged``
    (a candidate exceeded the threshold); per step (S, max_moves; −1 / NaN after stopping) ``movement`` id,
    ``prop`` id, ``trial`` (validation trial id drawn) and ``value``; ``posterior`` (S, max_moves + 1, K) over
    ``candidates`` (K,) before the first and after each step (NaN after stopping) — D Fig. 6-10."""

    true_texture: int
    candidates: np.ndarray
    strategy: str
    threshold: float
    max_moves: int
    sim_index: np.ndarray
    decided: np.ndarray
    correct: np.ndarray
    n_moves: np.ndarray
    converged: np.ndarray
    movement: np.ndarray
    prop: np.ndarray
    trial: np.ndarray
    value: np.ndarray
    posterior: np.ndarray

    _PER_SIM = ("sim_index", "decided", "correct", "n_moves", "converged", "movement", "prop", "trial", "value",
                "posterior")

    def __len__(self) -> int:
        return int(self.sim_index.size)

    @classmethod
    def concat(cls, results: Sequence["ExplorationResult"]) -> "ExplorationResult":
        """Simulations of several results (same true texture, candidates and settings) in one, by sim_index."""
        first = results[0]
        for r in results[1:]:
            if (r.true_texture, r.strategy, r.threshold, r.max_moves) != (
                    first.true_texture, first.strategy, first.threshold, first.max_moves) or \
                    not np.array_equal(r.candidates, first.candidates):
                raise ExplorationError("can only concatenate results of the same texture, candidates and settings")
        order = np.argsort(np.concatenate([r.sim_index for r in results]), kind="stable")
        per = {k: np.concatenate([getattr(r, k) for r in results])[order] for k in cls._PER_SIM}
        return cls(first.true_texture, first.candidates, first.strategy, first.threshold, first.max_moves, **per)


def _validation_block(model: TextureModel, table: TrialTable, true_texture: int):
    """(values, trial ids, counts) of the true texture's validation trials: (M, 3, R), (M, 3, R), (M, 3)."""
    rows = table.texture == true_texture
    mov, prop, trial, val = table.movement[rows], table.prop[rows], table.trial[rows], table.value[rows]
    keep = np.isin(mov, model.movements)
    mov, prop, trial, val = mov[keep], prop[keep], trial[keep], val[keep]
    M, P = model.movements.size, len(PROPERTIES)
    g = model.movement_index(mov) * P + prop if mov.size else np.zeros(0, np.int64)
    count = np.bincount(g, minlength=M * P)
    if np.any(count == 0):
        m, p = np.divmod(np.flatnonzero(count == 0), P)
        raise ExplorationError(
            f"validation table has no trials of texture {true_texture} at "
            + "; ".join(f"movement {model.movements[a]} {PROPERTIES[b]}" for a, b in zip(m[:5], p[:5]))
            + (f" (and {m.size - 5} more)" if m.size > 5 else ""))
    order = np.lexsort((trial, g))
    g, trial, val = g[order], trial[order], val[order]
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    rank = np.arange(g.size) - start[g]
    R = int(count.max())
    values = np.full((M * P, R), np.nan)
    trials = np.full((M * P, R), -1, np.int64)
    values[g, rank], trials[g, rank] = val, trial
    return values.reshape(M, P, R), trials.reshape(M, P, R), count.reshape(M, P)


def sim_uniforms(seed: int, true_texture: int, sim_indices: np.ndarray, max_moves: int) -> np.ndarray:
    """Uniforms (S, max_moves + 1, 3) of each simulation, from ``SeedSequence(seed, spawn_key=(true_texture,
    sim))``: per step [choice, trial, tie-break] (the last row's tie-break decides the final answer)."""
    return np.stack([
        np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(int(true_texture), int(i)))))
        .random((max_moves + 1, 3)) for i in sim_indices]) if len(sim_indices) else np.zeros((0, max_moves + 1, 3))


def prepare(model: TextureModel, candidates=None, best_movements=None, exclude_movements=(),
            prune: float = PRUNE, backend: str = "auto") -> ExplorationContext:
    """The :class:`ExplorationContext` for ``candidates`` (ids; default all of the model's textures).
    ``best_movements`` (ids per property) for cycling defaults to :func:`least_uncertain_movements` over all the
    model's textures, without ``exclude_movements``. ``backend`` is :func:`uncertainty_rows`'s."""
    cand = model.textures if candidates is None else np.asarray(candidates, dtype=np.int64)
    if cand.ndim != 1 or cand.size == 0 or np.unique(cand).size != cand.size:
        raise ExplorationError("candidates must be a non-empty list of distinct texture ids")
    idx = model.texture_index(cand)
    best = least_uncertain_movements(model, exclude_movements=exclude_movements) if best_movements is None \
        else np.asarray(best_movements, dtype=np.int64)
    if best.shape != (len(PROPERTIES),):
        raise ExplorationError("best_movements must give one movement id per property")
    conf = model.confusion(cand)
    return ExplorationContext(model, cand, model.mean[idx], model.sigma[idx],
                              np.ascontiguousarray(conf.reshape(cand.size, cand.size, -1)),
                              model.movement_index(best), float(prune), backend)


def simulate(model: TextureModel, validation_table: TrialTable, true_texture: int, candidates=None,
             strategy: str | Strategy = "bayesian", threshold: float | None = None, max_moves: int = MAX_MOVES,
             n_sims: int = 1000, seed: int = 0, *, first_sim: int = 0, best_movements=None,
             exclude_movements=(), prune: float = PRUNE, backend: str = "auto",
             context: ExplorationContext | None = None) -> ExplorationResult:
    """Virtual exploration of ``true_texture`` among ``candidates``: simulations ``first_sim … first_sim + n_sims
    − 1`` (see module docstring). ``threshold`` defaults to D's: 0.999 for two candidates, else 0.99. A prepared
    ``context`` (:func:`prepare`) may be passed to reuse it across calls (then ``candidates``, ``best_movements``,
    ``exclude_movements``, ``prune`` and ``backend`` are ignored)."""
    ctx = context if context is not None else prepare(model, candidates, best_movements, exclude_movements, prune,
                                                      backend)
    strat = STRATEGIES[strategy] if isinstance(strategy, str) else strategy
    name = strategy if isinstance(strategy, str) else getattr(strategy, "__name__", "custom")
    K, M, P = ctx.mean.shape
    if threshold is None:
        threshold = PAIR_THRESHOLD if K == 2 else ABSOLUTE_THRESHOLD
    if not 0.0 < threshold < 1.0:
        raise ExplorationError(f"threshold must be in (0, 1) (got {threshold})")
    if max_moves < 1 or n_sims < 0 or first_sim < 0:
        raise ExplorationError("need max_moves >= 1, n_sims >= 0, first_sim >= 0")
    true_texture = int(true_texture)
    values, trials, counts = _validation_block(model, validation_table, true_texture)

    S = int(n_sims)
    sims = np.arange(first_sim, first_sim + S)
    u = sim_uniforms(seed, true_texture, sims, max_moves)
    logp = np.full((S, K), -np.log(K))
    post = np.full((S, K), 1.0 / K)
    made = np.zeros((S, M, P), np.int64)
    hist = np.full((S, max_moves + 1, K), np.nan)
    hist[:, 0] = post
    mov_out = np.full((S, max_moves), -1, np.int64)
    prop_out = np.full((S, max_moves), -1, np.int64)
    trial_out = np.full((S, max_moves), -1, np.int64)
    val_out = np.full((S, max_moves), np.nan)
    n_moves = np.zeros(S, np.int64)
    live = np.ones(S, bool)
    mean_q = ctx.mean.reshape(K, M * P).T  # (Q, K)
    sigma_q = ctx.sigma.reshape(K, M * P).T
    for step in range(max_moves):
        r = np.flatnonzero(live)
        if r.size == 0:
            break
        q = np.asarray(strat(ctx, ExplorationState(post[r], made[r], step), u[r, step, 0]), dtype=np.int64)
        if q.shape != r.shape or np.any((q < 0) | (q >= M * P)):
            raise ExplorationError(f"strategy {name} returned invalid choices")
        m, p = np.divmod(q, P)
        k = np.minimum((u[r, step, 1] * counts[m, p]).astype(np.int64), counts[m, p] - 1)
        x = values[m, p, k]
        lp, post_r = _normalise(logp[r] + _loglik(x[:, None], mean_q[q], sigma_q[q]))
        logp[r], post[r] = lp, post_r
        made[r, m, p] += 1
        hist[r, step + 1] = post_r
        mov_out[r, step], prop_out[r, step], trial_out[r, step], val_out[r, step] = \
            ctx.model.movements[m], p, trials[m, p, k], x
        n_moves[r] = step + 1
        live[r] = post_r.max(axis=1) <= threshold
    converged = post.max(axis=1) > threshold
    decided = ctx.candidates[_pick_max(post, u[:, max_moves, 2])] if S else np.zeros(0, np.int64)
    return ExplorationResult(true_texture, ctx.candidates, name, float(threshold), int(max_moves), sims, decided,
                             decided == true_texture, n_moves, converged, mov_out, prop_out, trial_out, val_out,
                             hist)


# ------------------------------------------------------------------------------------------------ summaries


def _results(results) -> list[ExplorationResult]:
    return [results] if isinstance(results, ExplorationResult) else list(results)


def accuracy(results) -> float:
    """Fraction of simulations that decided the true texture (one result or several)."""
    c = np.concatenate([r.correct for r in _results(results)])
    return float(c.mean()) if c.size else float("nan")


def median_moves(results, unconverged: str = "inf") -> float:
    """Median number of movements. ``unconverged="inf"`` counts simulations that hit the move limit without
    converging as infinitely long (D Table 6-5: the median is undefined — here inf — when fewer than half
    converge); ``"limit"`` counts them at the limit; ``"exclude"`` leaves them out."""
    rs = _results(results)
    n = np.concatenate([r.n_moves for r in rs]).astype(np.float64)
    conv = np.concatenate([r.converged for r in rs])
    if unconverged == "inf":
        n = np.where(conv, n, np.inf)
    elif unconverged == "exclude":
        n = n[conv]
    elif unconverged != "limit":
        raise ValueError(f"unconverged must be 'inf', 'limit' or 'exclude' (got {unconverged!r})")
    if n.size == 0:
        return float("nan")
    s = np.sort(n)
    mid = (s.size - 1) / 2
    lo, hi = s[int(np.floor(mid))], s[int(np.ceil(mid))]
    return float(lo if lo == hi else (lo + hi) / 2)


def confusion_matrix(results, labels=None) -> tuple[np.ndarray, np.ndarray]:
    """(labels, counts) with counts[a, b] = simulations of true texture labels[a] that decided labels[b];
    labels default to the sorted union of true and decided textures."""
    rs = _results(results)
    true = np.concatenate([np.full(len(r), r.true_texture, np.int64) for r in rs])
    dec = np.concatenate([r.decided for r in rs])
    labels = np.unique(np.concatenate([true, dec])) if labels is None else np.asarray(labels, dtype=np.int64)
    ti, di = np.searchsorted(labels, true), np.searchsorted(labels, dec)
    ok = (ti < labels.size) & (di < labels.size)
    ok[ok] &= (labels[ti[ok]] == true[ok]) & (labels[di[ok]] == dec[ok])
    counts = np.zeros((labels.size, labels.size), np.int64)
    np.add.at(counts, (ti[ok], di[ok]), 1)
    return labels, counts
