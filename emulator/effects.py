"""The effect graph: stages that consume and produce named signals, built on demand.

A *signal* is an array of samples on the emulator's uniform time grid, in SI
units (``*_N``, ``*_Pa``, ``*_V``).  Every signal is the sum of the
contributions of the effects that produce it.  An :class:`Effect` declares what
it consumes and produces; :func:`build_graph` keeps only the effects needed to
produce the demanded signals from the stimuli that exist, and orders them.

Each effect that draws random numbers gets its own generator, derived from the
scene seed and the effect's *name*, so leaving one effect out never changes the
samples of another.
"""

from __future__ import annotations

import hashlib
import time
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np


def effect_rng(seed: int, name: str) -> np.random.Generator:
    """The random stream of effect ``name`` for scene ``seed`` (independent of all other effects)."""
    key = int.from_bytes(hashlib.sha256(name.encode()).digest()[:8], "little")
    return np.random.default_rng(np.random.SeedSequence([seed, key]))


@dataclass
class Block:
    """One block of grid samples [n0, n0 + n)."""

    n0: int
    n: int
    fs: float

    @property
    def times(self) -> np.ndarray:
        return (self.n0 + np.arange(self.n)) / self.fs


class Effect(ABC):
    """A stage of the model. Subclasses set ``consumes``, ``produces`` and implement :meth:`process`."""

    name: str = "effect"
    consumes: tuple[str, ...] = ()
    produces: tuple[str, ...] = ()
    #: True if the effect outputs zero whenever its inputs are zero: it is left out when nothing feeds it.
    passive: bool = False

    def settle(self, inputs: dict[str, float]) -> dict[str, float]:
        """Set internal state to steady state for constant ``inputs``; return the steady outputs."""
        return {s: 0.0 for s in self.produces}

    @abstractmethod
    def process(self, block: Block, inputs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Contributions to the produced signals over ``block``: new arrays of ``block.n`` samples.

        Inputs must not be modified; returned arrays belong to the graph (it sums into them).
        """

    def describe(self) -> str:
        return (self.__doc__ or "").strip().splitlines()[0] if self.__doc__ else self.name


@dataclass
class EffectCost:
    name: str
    description: str
    consumes: tuple[str, ...]
    produces: tuple[str, ...]
    seconds: float = 0.0
    samples: int = 0


def _drop_unfed_passive(candidates: list[Effect]) -> list[Effect]:
    kept = list(candidates)
    while True:
        produced = {s for e in kept for s in e.produces}
        unfed = [e for e in kept if e.passive and not any(c in produced for c in e.consumes)]
        if not unfed:
            return kept
        kept = [e for e in kept if e not in unfed]


@dataclass
class Graph:
    """Effects in dependency order, with their accumulated cost."""

    effects: list[Effect]
    costs: dict[str, EffectCost] = field(default_factory=dict)

    def __post_init__(self):
        self.costs = {
            e.name: EffectCost(e.name, e.describe(), tuple(e.consumes), tuple(e.produces)) for e in self.effects
        }

    def settle(self) -> dict[str, float]:
        """Bring every effect to its resting steady state; return the resting value of each signal."""
        values: dict[str, float] = {}
        for e in self.effects:
            outs = e.settle({s: values.get(s, 0.0) for s in e.consumes})
            for s, v in outs.items():
                values[s] = values.get(s, 0.0) + v
        return values

    def run(self, block: Block) -> dict[str, np.ndarray]:
        """Evaluate every effect over ``block``; returns all signals (sums of contributions)."""
        signals: dict[str, np.ndarray] = {}
        for e in self.effects:
            t0 = time.perf_counter()
            zeros = None
            inputs = {}
            for s in e.consumes:
                if s in signals:
                    inputs[s] = signals[s]
                else:
                    if zeros is None:
                        zeros = np.zeros(block.n)
                    inputs[s] = zeros
            outs = e.process(block, inputs)
            for s, v in outs.items():
                if s in signals:
                    np.add(signals[s], v, out=signals[s])  # effects return arrays they own
                else:
                    signals[s] = np.asarray(v, dtype=float)
            cost = self.costs[e.name]
            cost.seconds += time.perf_counter() - t0
            cost.samples += block.n
        return signals


def build_graph(candidates: list[Effect], demanded: set[str]) -> Graph:
    """Keep the effects needed to produce ``demanded`` signals, in an order where producers run first.

    An effect is needed if it produces a needed signal; its consumed signals then become needed.
    A consumed signal that nothing produces is zero, so a *passive* effect fed only by such signals
    (e.g. force coupling in a scene with no force stimulus) is left out.
    """
    candidates = _drop_unfed_passive(candidates)
    producers: dict[str, list[Effect]] = {}
    for e in candidates:
        for s in e.produces:
            producers.setdefault(s, []).append(e)
    needed_signals = set(demanded)
    needed: list[Effect] = []
    frontier = list(demanded)
    while frontier:
        s = frontier.pop()
        for e in producers.get(s, []):
            if e not in needed:
                needed.append(e)
                for c in e.consumes:
                    if c not in needed_signals:
                        needed_signals.add(c)
                        frontier.append(c)
    # topological order: an effect runs after every producer of what it consumes
    ordered: list[Effect] = []
    placed: set[int] = set()
    pending = [e for e in candidates if e in needed]
    while pending:
        progress = False
        for e in list(pending):
            deps = [p for c in e.consumes for p in producers.get(c, []) if p in needed]
            if all(id(p) in placed for p in deps):
                ordered.append(e)
                placed.add(id(e))
                pending.remove(e)
                progress = True
        if not progress:
            raise RuntimeError("cycle in the effect graph: " + ", ".join(e.name for e in pending))
    return Graph(ordered)
