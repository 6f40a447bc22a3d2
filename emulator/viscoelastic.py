"""Linear viscoelastic creep of the silicone skin: a Prony series integrated exactly, sample by sample.

A force history F(t) held on a viscoelastic body produces a response (indentation, or the share of the
load that reaches the fluid) that follows the *normalized creep function*

    c(t) = 1 − Σ_i w_i · exp(−t/τ_i),      c(0) = r = 1 − Σ w_i,   c(∞) = 1,

so a step of force gives an instantaneous response r (the instantaneous/relaxed ratio) that creeps to 1
with retardation times τ_i.  One term is the standard linear solid (a spring in parallel with a Maxwell
arm); more terms are a Prony series.  The response to any force history is the convolution

    y = r·F + Σ_i w_i · L_i[F],     L_i: first-order low-pass of time constant τ_i (unit DC gain),

and each low-pass is advanced by its exact solution for a force varying linearly between samples
(first-order hold): results do not depend on block size (the states are carried) and need no small-step
condition.  Loading then unloading traces a loop (hysteresis); a held force creeps.

API
---
* :class:`Creep` — ``Creep(taus_s, weights).step(force, fs)`` returns the creep response of an array of
  force samples at ``fs`` Hz and keeps the state for the next call; ``settle(x0)`` starts from rest at a
  constant force.  ``Creep.standard_linear_solid(tau_s, ratio)`` builds the one-term model.
* :func:`instantaneous_to_relaxed_ratio` — r for given weights; :func:`sls_retardation` — the creep
  (retardation) time and r of a skin whose *modulus* relaxes from E0 to E∞ with relaxation time τ_E,
  when it shares the load in parallel with an elastic path (the fluid).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from emulator import filters


def instantaneous_to_relaxed_ratio(weights: Sequence[float]) -> float:
    """r = c(0)/c(∞) = 1 − Σ w_i of a normalized creep function (1)."""
    r = 1.0 - float(sum(weights))
    if not 0.0 < r <= 1.0:
        raise ValueError(f"creep weights {list(weights)} sum to {1 - r:g}: must sum to [0, 1)")
    return r


def sls_retardation(relaxation_time_s: float, relaxed_fraction: float, parallel_stiffness_fraction: float = 0.0):
    """Creep of a standard linear solid, optionally in parallel with an elastic path.

    The skin's modulus relaxes from E0 to E∞ = ``relaxed_fraction``·E0 with relaxation time
    ``relaxation_time_s`` (under held strain).  Under held *force* the body creeps more slowly: the
    retardation time is τ_E·E0/E∞.  ``parallel_stiffness_fraction`` q = k_parallel/k_skin,relaxed adds a
    purely elastic path (the fluid) that shares the deformation.  Returns (retardation time s,
    instantaneous/relaxed ratio r of the deformation under a held force).
    """
    if not 0.0 < relaxed_fraction <= 1.0:
        raise ValueError(f"relaxed_fraction = {relaxed_fraction!r}: must be in (0, 1]")
    if relaxation_time_s <= 0.0:
        raise ValueError(f"relaxation_time_s = {relaxation_time_s!r}: must be > 0")
    k_relaxed = 1.0 + parallel_stiffness_fraction  # total relaxed stiffness, in units of the skin's E∞
    k_instant = 1.0 / relaxed_fraction + parallel_stiffness_fraction
    return relaxation_time_s * k_instant / k_relaxed, k_relaxed / k_instant


class Creep:
    """Normalized creep response of a force history (Prony series, exact first-order-hold update).

    ``taus_s`` retardation times (s) and ``weights`` (dimensionless, Σ < 1).  The output has the unit of
    the input: for a constant force F it tends to F; just after a step it is r·F.
    """

    def __init__(self, taus_s: Sequence[float], weights: Sequence[float]):
        if len(taus_s) != len(weights):
            raise ValueError("creep: give one weight per retardation time")
        if any(not (t > 0 and math.isfinite(t)) for t in taus_s):
            raise ValueError(f"creep retardation times {list(taus_s)} s: each must be finite and > 0")
        if any(w < 0 for w in weights):
            raise ValueError(f"creep weights {list(weights)}: each must be ≥ 0")
        self.taus = np.asarray(taus_s, float)
        self.weights = np.asarray(weights, float)
        self.ratio = instantaneous_to_relaxed_ratio(self.weights)
        self.state = np.zeros(len(self.taus))  # each low-pass output at the last sample
        self.last = 0.0  # the last input sample (the first-order hold needs it)
        self._coeffs: dict[float, list[tuple[np.ndarray, np.ndarray]]] = {}

    @classmethod
    def standard_linear_solid(cls, tau_s: float, ratio: float) -> "Creep":
        """One-term model: response r·F at a step, creeping to F with retardation time ``tau_s``."""
        return cls([tau_s], [1.0 - ratio])

    def _filters(self, fs: float):
        """Exact first-order-hold discretization of each low-pass at ``fs`` (cached)."""
        if fs not in self._coeffs:
            h = 1.0 / fs
            out = []
            for tau in self.taus:
                a = math.exp(-h / tau)
                g = tau / h * (1.0 - a)  # ∫ of the step response over one interval, per h
                b0, b1 = 1.0 - g, g - a  # y[n] = a·y[n−1] + b0·u[n] + b1·u[n−1]   (a + b0 + b1 = 1)
                out.append((np.array([b0, b1]), np.array([1.0, -a])))
            self._coeffs[fs] = out
        return self._coeffs[fs]

    def settle(self, x0: float) -> None:
        """Start at rest under the constant input ``x0`` (fully crept)."""
        self.state[:] = x0
        self.last = float(x0)

    def step(self, force: np.ndarray, fs: float) -> np.ndarray:
        """Creep response of ``force`` samples at ``fs`` Hz, continuing from the carried state."""
        u = np.asarray(force, float)
        if u.size == 0:
            return u.copy()
        y = self.ratio * u
        for i, (b, a) in enumerate(self._filters(fs)):
            # lfilter's state for y[n] = −a1·y[n−1] + b0·u[n] + b1·u[n−1]: zi = b1·u[−1] − a1·y[−1]
            zi = np.array([b[1] * self.last - a[1] * self.state[i]])
            lp, _ = filters.lfilter(b, a, u, zi)
            self.state[i] = lp[-1]
            y += self.weights[i] * lp
        self.last = float(u[-1])
        return y
