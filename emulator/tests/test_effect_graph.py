"""The effect graph's own rules (emulator/effects.py), on toy effects: only what the demanded signals need, producers
before consumers whatever order the candidates come in, contributions summed, unfed passive chains left out, a
cycle refused by name, and each effect's cost counted in samples."""

import numpy as np
import pytest

from emulator.effects import Block, Effect, build_graph

pytestmark = pytest.mark.unit


class Toy(Effect):
    """out = gain × (sum of inputs) + offset, per sample."""

    def __init__(self, name, consumes=(), produces=(), gain=1.0, offset=0.0, passive=False):
        self.name, self.consumes, self.produces = name, tuple(consumes), tuple(produces)
        self.gain, self.offset, self.passive = gain, offset, passive

    def process(self, block, inputs):
        total = sum((inputs[s] for s in self.consumes), np.zeros(block.n))
        return {s: self.gain * total + self.offset for s in self.produces}


def names(graph):
    return [e.name for e in graph.effects]


def test_producers_run_before_consumers_whatever_order_the_candidates_come_in():
    """c = 3·b, b = 2·a, a = 1: given consumer first, the graph orders a, b, c and c reads 6 everywhere."""
    chain = [Toy("to_c", ["b"], ["c"], gain=3.0), Toy("to_b", ["a"], ["b"], gain=2.0), Toy("source", [], ["a"], offset=1.0)]
    graph = build_graph(chain, {"c"})
    assert names(graph) == ["source", "to_b", "to_c"]
    out = graph.run(Block(0, 5, 1000.0))
    assert np.array_equal(out["c"], np.full(5, 6.0))


def test_only_what_the_demanded_signals_need_is_built():
    """An effect producing a signal nobody demands, and the source only it consumes, are left out."""
    candidates = [Toy("source", [], ["a"], offset=1.0), Toy("to_b", ["a"], ["b"]),
                  Toy("other_source", [], ["z"], offset=5.0), Toy("to_y", ["z"], ["y"])]
    assert names(build_graph(candidates, {"b"})) == ["source", "to_b"]
    assert names(build_graph(candidates, {"y"})) == ["other_source", "to_y"]


def test_two_producers_of_a_signal_add_and_its_consumer_waits_for_both():
    """Every signal is the sum of its producers' contributions: a = 1 + 2, read by a consumer listed first."""
    candidates = [Toy("reader", ["a"], ["r"], gain=10.0), Toy("one", [], ["a"], offset=1.0),
                  Toy("two", [], ["a"], offset=2.0)]
    graph = build_graph(candidates, {"r"})
    assert names(graph)[-1] == "reader" and set(names(graph)) == {"one", "two", "reader"}
    assert np.array_equal(graph.run(Block(0, 3, 1000.0))["r"], np.full(3, 30.0))


def test_a_chain_of_passive_effects_fed_by_nothing_is_left_out_but_an_active_one_stays():
    """Force coupling with no force stimulus: a passive effect whose inputs nothing produces is left out, and then
    so is a passive effect fed only by it; an active effect (a noise source, say) on the same unfed input stays and
    sees zeros."""
    candidates = [Toy("coupling", ["force"], ["x"], passive=True), Toy("resonance", ["x"], ["y"], passive=True),
                  Toy("noise", ["force"], ["y"], offset=0.5)]
    graph = build_graph(candidates, {"y"})
    assert names(graph) == ["noise"]
    assert np.array_equal(graph.run(Block(0, 4, 1000.0))["y"], np.full(4, 0.5))
    fed = build_graph(candidates + [Toy("press", [], ["force"], offset=1.0)], {"y"})
    assert set(names(fed)) == {"press", "coupling", "resonance", "noise"}


def test_a_cycle_is_refused_naming_its_effects():
    candidates = [Toy("left", ["b"], ["a"]), Toy("right", ["a"], ["b"])]
    with pytest.raises(RuntimeError, match="cycle in the effect graph: (left, right|right, left)$"):
        build_graph(candidates, {"a"})


def test_each_effect_counts_the_samples_it_processed():
    """The cost table behind the benchmark's per-effect rows: samples add up block by block."""
    graph = build_graph([Toy("source", [], ["a"], offset=1.0), Toy("to_b", ["a"], ["b"])], {"b"})
    for n0, n in ((0, 100), (100, 37), (137, 263)):
        graph.run(Block(n0, n, 1000.0))
    assert {name: c.samples for name, c in graph.costs.items()} == {"source": 400, "to_b": 400}
    assert all(c.seconds > 0 for c in graph.costs.values())
    assert graph.costs["to_b"].consumes == ("a",) and graph.costs["to_b"].produces == ("b",)


def test_a_passive_effect_fed_by_one_of_its_inputs_stays():
    """A passive effect is left out only when none of its inputs is produced: fed by one of two (a pressure with no
    temperature model beside it), it runs and reads zeros for the other."""
    candidates = [Toy("source", [], ["a"], offset=2.0), Toy("mix", ["a", "unfed"], ["y"], gain=3.0, passive=True)]
    graph = build_graph(candidates, {"y"})
    assert names(graph) == ["source", "mix"]
    assert np.array_equal(graph.run(Block(0, 4, 1000.0))["y"], np.full(4, 6.0))


def test_each_effect_draws_its_own_random_stream_from_the_seed_and_its_name():
    """effect_rng(seed, name): the same seed and name give the same numbers, another name other numbers (so two noise
    sources never add coherently), another seed other numbers."""
    from emulator.effects import effect_rng

    def draw(seed, name):
        return effect_rng(seed, name).standard_normal(8)

    assert np.array_equal(draw(1, "johnson"), draw(1, "johnson"))
    assert not np.array_equal(draw(1, "johnson"), draw(1, "amplifier"))
    assert not np.array_equal(draw(1, "johnson"), draw(2, "johnson"))
