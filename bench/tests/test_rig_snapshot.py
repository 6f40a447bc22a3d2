"""The rig's rewind snapshot: its copier is ``copy.deepcopy``'s copy, faster."""

from __future__ import annotations

import copy
import functools
import pickle
from dataclasses import dataclass

import numpy as np

from bench.rigs.texture_rig import _clone


class _Node:
    def __init__(self, value):
        self.value, self.children, self.parent = value, [], None

    def scaled(self, k):
        return self.value * k


@dataclass(frozen=True)
class _Frozen:
    a: float
    b: tuple


class _Slotted:
    __slots__ = ("x",)

    def __init__(self, x):
        self.x = x


class _Items(list):
    def __init__(self, items, tag):
        super().__init__(items)
        self.tag = tag


def _graph():
    """An object graph with what a rig's run holds: plain objects in a cycle, shared arrays (F-ordered, a view),
    dicts with tuple keys, a frozen dataclass, a slotted object, a list subclass, a partial, a bound method."""
    shared = np.arange(12.0).reshape(3, 4)
    root, child = _Node(1.5), _Node(np.asfortranarray(shared))
    child.parent, root.children = root, [child, child]
    root.view, root.same = shared[:, 1], shared
    root.table = {("a", 1): shared, "b": [1, 2.5, None, "s"]}
    root.frozen = _Frozen(2.0, (shared, "x"))
    root.slotted, root.items = _Slotted([3]), _Items([shared, 4], "t")
    root.call, root.method = functools.partial(np.add, shared), child.scaled
    return root


def test_the_snapshot_copier_gives_deepcopys_copy():
    """(consistency) :func:`_clone` of a graph equals ``copy.deepcopy`` of it: the same pickled bytes (values,
    memory orders, and which parts are one object), nothing of the original in the copy but what the memo shares
    and immutable values, the copy's own cycle and sharing kept."""
    root = _graph()
    kept = np.ones(3)
    root.kept = kept
    a, b = _clone(root, {id(kept): kept}), copy.deepcopy(root, {id(kept): kept})
    assert pickle.dumps(a) == pickle.dumps(b)
    assert a.kept is kept and a is not root and a.children[0] is a.children[1] and a.children[0].parent is a
    assert a.same is not root.same and a.table[("a", 1)] is a.same and a.frozen.b[0] is a.same
    assert a.children[0].value.flags.f_contiguous and not np.shares_memory(a.view, root.view)
    assert a.items.tag == "t" and a.items[0] is a.same and a.slotted is not root.slotted and a.slotted.x == [3]
    assert a.method.__self__ is a.children[0] and a.call.args[0] is a.same
    a.same[0, 0] = -1.0
    assert root.same[0, 0] == 0.0
