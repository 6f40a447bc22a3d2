"""The claims' machinery: labels are required and checked, groups register by decorator and reach the CLI's
choices, the table and JSON show each row's kind and source, and a multi-seed run reports each claim's spread and
the seeds it fails for."""

import json

import pytest

from bench.cli import main as cli
from bench.verification import claims
from bench.verification.claims import (CLAIM_GROUPS, Bench, Claim, claim_group, format_spread_table, format_table,
                                       run_claims, run_claims_over_seeds)

pytestmark = pytest.mark.unit


def test_a_claim_must_say_what_kind_of_evidence_it_is():
    with pytest.raises(ValueError, match="kind"):
        Claim("x", "1", 1.0, 0.0, 2.0, "u", "D ch. 4")
    with pytest.raises(ValueError, match="kind"):
        Claim("x", "1", 1.0, 0.0, 2.0, "u", "D ch. 4", kind="proof")
    with pytest.raises(ValueError, match="knob"):
        Claim("x", "1", 1.0, 0.0, 2.0, "u", "D ch. 4", kind="calibrated")
    with pytest.raises(ValueError, match="source"):
        Claim("x", "1", 1.0, 0.0, 2.0, "u", "", kind="prediction")
    c = Claim("x", "1", 1.0, 0.0, 2.0, "u", "D ch. 4", kind="calibrated", calibration="k tuned to 1")
    assert c.as_dict()["kind"] == "calibrated" and c.as_dict()["calibration"] == "k tuned to 1"


def test_the_shipped_groups_are_registered_in_order_and_reach_the_cli():
    assert list(CLAIM_GROUPS)[:9] == ["noise", "scales", "force", "impact", "detection", "false-detection",
                                      "vibration", "thermal", "electrodes"]

    @claim_group("test-only-group")
    def extra(bench):
        return [Claim("extra", "1", 1.0, 0.0, 2.0, "u", "test", kind="consistency", note="a test")]

    try:
        assert cli.main(["claims", "--only", "test-only-group", "--json"]) == 0  # --only's choices: the registry
        assert [c.name for c in run_claims(Bench(), ["test-only-group"])] == ["extra"]
        with pytest.raises(ValueError, match="twice"):
            claim_group("test-only-group")(lambda b: [])
    finally:
        del CLAIM_GROUPS["test-only-group"]
    with pytest.raises(SystemExit):
        cli.main(["claims", "--only", "test-only-group"])


def test_the_cli_offers_every_registered_group(capsys):
    with pytest.raises(SystemExit):
        cli.main(["claims", "--help"])
    out = capsys.readouterr().out
    for name in CLAIM_GROUPS:
        assert name in out


def test_table_and_json_show_kind_and_source(capsys):
    rows = run_claims(Bench(quick=True), ["scales"])
    table = format_table(rows)
    assert "kind" in table.splitlines()[0] and "source" in table.splitlines()[0]
    assert "PDC scale" in table and "derived" in table and "D Table 4-1" in table
    assert table.splitlines()[-1].startswith("kinds: 0 prediction, 0 calibrated, 3 derived, 1 consistency")
    assert cli.main(["claims", "--only", "scales", "--json", "--quick"]) == 0
    for row in json.loads(capsys.readouterr().out):
        assert row["kind"] in claims.KINDS and row["source"]


def test_a_multi_seed_run_reports_the_spread_and_the_seeds_that_fail():
    @claim_group("test-seeded")
    def seeded(bench):
        return [Claim("lucky", "< 2014.5", float(bench.seed), 0.0, 2014.5, "seed", "test", kind="consistency",
                      note="fails for some seeds")]

    try:
        rows = run_claims_over_seeds(lambda s: Bench(seed=s), range(2012, 2017), ["test-seeded"])
    finally:
        del CLAIM_GROUPS["test-seeded"]
    (r,) = rows
    assert (r.min, r.max) == (2012.0, 2016.0) and r.failed_seeds == [2015, 2016]
    table = format_spread_table(rows)
    assert "3/5 (fails for seed 2015, 2016)" in table and "0 of 1 claims pass for every seed" in table
    assert r.as_dict()["failed_seeds"] == [2015, 2016]


def test_a_documented_deviation_is_reported_across_seeds_not_hidden():
    @claim_group("test-deviating")
    def deviating(bench):
        return [Claim("not reproduced", "> 2013.5", float(bench.seed), 2013.5, 1e9, "seed", "test",
                      kind="prediction", deviation="the model lacks it")]

    try:
        rows = run_claims_over_seeds(lambda s: Bench(seed=s), range(2012, 2015), ["test-deviating"])
    finally:
        del CLAIM_GROUPS["test-deviating"]
    (r,) = rows
    assert r.passed == [False, False, True] and r.failed_seeds == [2014]  # it passed for 2014: recheck it
    assert "(documented deviation) passes for seed 2014: recheck it" in format_spread_table(rows)

