"""Every published figure of SENSOR.md, measured on the emulator (the same checks as scripts/claims)."""

import pytest

from bench.verification.claims import CLAIM_GROUPS, Bench

pytestmark = pytest.mark.claims

_results = {}


def _claims(group):
    if group not in _results:
        _results[group] = CLAIM_GROUPS[group](Bench())
    return _results[group]


@pytest.mark.parametrize("group", list(CLAIM_GROUPS))
def test_published_figures_hold(group):
    failed = [f"{c.name}: expected {c.expected}, measured {c.measured:.4g} {c.unit}, accepted {c.tolerance}"
              for c in _claims(group) if not c.passed]
    assert not failed, "\n".join(failed)
    assert _claims(group), "a claim group that checks nothing"
