"""Command-line follow-ups: campaign's --junit checked before the campaign runs and its summary kept when the report
cannot be written; --json output that is standard JSON (null for a non-finite number); one SIGTERM wrapper in
bench.cli.args; campaign's help and argument checks from a light module whose names agree with the registries."""

from __future__ import annotations

import errno
import json
import re
import signal
import subprocess
import sys

import pytest

from bench.paths import REPO
from bench.tests.test_cli_review import invoke

pytestmark = pytest.mark.unit


def _strict_loads(text: str):
    """JSON as jq, Go or JavaScript read it: ``Infinity`` / ``NaN`` are errors."""

    def refuse(constant):
        raise ValueError(f"{constant} is not JSON")

    return json.loads(text, parse_constant=refuse)


# --- campaign --junit -----------------------------------------------------------------------------------------


def test_campaign_refuses_a_junit_path_where_no_file_can_be_created_before_running(monkeypatch, capsys, tmp_path):
    """/proc passes a permission check as root, but no file can be created there: found before the campaign, by
    creating a file (removed at once: a writable path's check leaves nothing behind)."""
    from bench.campaigns import faults
    from bench.cli.args import output_file

    def ran(*args, **kw):
        raise AssertionError("the campaign ran before --junit was found unwritable")

    monkeypatch.setattr(faults, "run_campaign", ran)
    status, out, err = invoke(["campaign", "--faults", "none", "--scenes", "rest", "--junit", "/proc/x.xml"], capsys)
    assert status == 2 and out == ""
    assert "--junit" in err and "/proc/x.xml" in err and len(err.strip().splitlines()) == 1
    assert output_file(str(tmp_path / "new" / "report.xml")) == str(tmp_path / "new" / "report.xml")
    assert list(tmp_path.iterdir()) == []


def test_two_campaigns_never_write_one_junit_report(monkeypatch, capsys, tmp_path):
    """A second campaign naming the --junit report a first one is still running for is refused before it runs (the
    later one silently replaced the earlier's cases); once the first has ended, the report can be written again."""
    import os

    from bench.campaigns import faults
    from bench.reporting.outdir import lock_exclusively

    report = tmp_path / "c.xml"
    first = lock_exclusively(tmp_path / ".c.xml.lock", "first", lambda who: who)  # a campaign still running

    def ran(*args, **kw):
        raise AssertionError("the second campaign ran")

    monkeypatch.setattr(faults, "run_campaign", ran)
    status, out, err = invoke(["campaign", "--faults", "none", "--scenes", "rest", "--junit", str(report)], capsys)
    assert status == 2 and out == "" and not report.exists()
    assert f"--junit {report}: another campaign (pid {os.getpid()}) is writing this report" in err, err
    os.close(first)
    monkeypatch.setattr(faults, "run_campaign", lambda *a, **kw: [
        {"fault": "none", "scene": "rest", "seed": 0, "expected": "-", "passed": True, "problem": None, "seconds": 0.1}])
    status, out, _ = invoke(["campaign", "--faults", "none", "--scenes", "rest", "--junit", str(report)], capsys)
    assert status == 0 and "<testsuite" in report.read_text()
    assert [p.name for p in tmp_path.iterdir()] == ["c.xml"]  # the lock file removed as the campaign ended


def test_a_lock_removed_by_its_holder_while_it_was_being_taken_is_taken_afresh(monkeypatch, tmp_path):
    """The holder ends (removes the lock file, then releases it) between our open and our flock: the flock then
    succeeds on the removed file, which locks nothing any other process can see.  The lock taken is a new file at
    the path, and a third taker is refused by it."""
    import fcntl
    import os

    from bench.reporting import outdir

    path = tmp_path / ".c.xml.lock"
    holder = outdir.lock_exclusively(path, "holder", lambda who: who)
    real_flock = fcntl.flock
    ends = [holder]

    def holder_ends_first(fd, op):
        if ends:
            outdir.release_and_remove(ends.pop(), path)
        return real_flock(fd, op)

    monkeypatch.setattr(fcntl, "flock", holder_ends_first)
    taken = outdir.lock_exclusively(path, "second", lambda who: who)
    monkeypatch.undo()
    try:
        assert os.path.samestat(os.fstat(taken), os.lstat(path))
        with pytest.raises(outdir.OutDirError, match=f"third: another run \\(pid {os.getpid()}\\)"):
            outdir.lock_exclusively(path, "third", lambda who: who)
    finally:
        os.close(taken)


def test_campaign_prints_its_summary_before_the_report_and_keeps_it_when_the_report_fails(monkeypatch, capsys,
                                                                                       tmp_path):
    from bench.campaigns import faults

    results = [{"fault": "none", "scene": "rest", "seed": 0, "expected": "no errors, no drops", "passed": True,
                "problem": None, "seconds": 0.5}]
    shown_before_writing = []

    def write_fails(res, path, started=None):
        shown_before_writing.append(capsys.readouterr().out)
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(faults, "run_campaign", lambda *a, **kw: results)
    monkeypatch.setattr(faults, "write_junit", write_fails)
    junit = tmp_path / "c.xml"
    status, out, err = invoke(["campaign", "--faults", "none", "--scenes", "rest", "--junit", junit, "--quiet"],
                              capsys)
    assert "1 passed, 0 failed" in shown_before_writing[0]
    assert status == 1 and "JUnit XML:" not in out
    assert f"--junit {junit}" in err and "No space left on device" in err and "summary above" in err


# --- JSON output ------------------------------------------------------------------------------------------------


def test_strict_json_writes_null_for_non_finite_numbers_and_plain_numbers_for_numpy_ones():
    import numpy as np

    from bench.cli.args import strict_json

    doc = {"high": float("inf"), "low": -np.inf, "nan": np.float32("nan"), "x": np.float64(1.5), "n": np.int64(3),
           "ok": True, "rows": [(1, float("-inf"))], "text": "inf"}
    assert _strict_loads(strict_json(doc, indent=2)) == {"high": None, "low": None, "nan": None, "x": 1.5, "n": 3,
                                                         "ok": True, "rows": [[1, None]], "text": "inf"}

    class Odd:  # reaches json's default=float: a non-finite number there is an error, never "Infinity"
        def __float__(self):
            return float("inf")

    with pytest.raises(ValueError, match="JSON"):
        strict_json({"odd": Odd()})


def test_claims_json_gives_null_for_an_unbounded_tolerance_and_says_so_in_its_help(monkeypatch, capsys):
    from bench.verification import claims
    from bench.verification.claims.core import Claim

    rows = [Claim("at least", "≥ 1", 2.0, 1.0, float("inf"), "N", "D 1.1", kind="prediction"),
            Claim("no data", "1", float("nan"), 0.5, 1.5, "N", "D 1.2", kind="prediction",
                  deviation="not measurable here")]
    monkeypatch.setattr(claims, "run_claims", lambda bench, groups, progress=None: rows)
    status, out, _ = invoke(["claims", "--json", "--only", "noise"], capsys)
    doc = _strict_loads(out)
    assert status == 0 and doc[0]["high"] is None and doc[0]["low"] == 1.0 and doc[1]["measured"] is None
    _, help_text, _ = invoke(["claims", "--help"], capsys)
    assert "null" in " ".join(help_text.split())


def test_the_cli_emits_json_only_through_strict_json():
    """Every JSON the command line prints or writes goes through strict_json (allow_nan=False)."""
    direct = [f"{p.name}:{n}" for p in sorted((REPO / "bench" / "cli").glob("*.py"))
              for n, line in enumerate(p.read_text().splitlines(), 1) if "json.dump" in line and p.name != "args.py"]
    assert direct == []


# --- the SIGTERM wrapper ----------------------------------------------------------------------------------------


def test_sigterm_like_ctrl_c_is_defined_once_in_args_and_imported_from_there(capsys):
    from bench.cli import args, experiments

    defined = [f"{p.name}" for p in sorted((REPO / "bench" / "cli").glob("*.py"))
               if re.search(r"^def _?sigterm_like_ctrl_c\b", p.read_text(), re.M)]
    assert defined == ["args.py"] and not hasattr(experiments, "_sigterm_like_ctrl_c")

    def terminated(a):
        raise args.Terminated()

    assert args.sigterm_like_ctrl_c(terminated)(None) == 128 + signal.SIGTERM
    assert capsys.readouterr().err == "terminated\n"


# --- campaign's names, light ------------------------------------------------------------------------------------


def _kinds(stimuli) -> str:
    """A stimulus set as its description starts: "2 × Tap", "no stimulus" for none."""
    kinds = [type(s).__name__ for s in stimuli]
    return ", ".join(f"{kinds.count(k)} × {k}" for k in dict.fromkeys(kinds)) or "no stimulus"


def test_the_campaign_names_and_the_registries_agree():
    from bench.campaigns import faults
    from bench.campaigns.case_names import FAULT_EXPECTED, SCENE_DESCRIPTIONS

    assert set(faults.FAULT_CASES) == set(FAULT_EXPECTED)
    assert list(faults.FAULTS) == list(FAULT_EXPECTED)
    assert all(faults.FAULTS[n].name == n and faults.FAULTS[n].expected == e for n, e in FAULT_EXPECTED.items())
    assert set(faults.SCENE_STIMULI) == set(SCENE_DESCRIPTIONS) and list(faults.SCENES) == list(SCENE_DESCRIPTIONS)
    for name, stimuli in faults.SCENES.items():
        described = SCENE_DESCRIPTIONS[name]
        assert described.startswith(_kinds(stimuli)), name
        for s in stimuli:  # each stimulus' time (s from power-on) is in the description
            when = getattr(s, "time_s", None)
            when = s.start if when is None else when
            assert re.search(rf"(?<![\d.]){re.escape(f'{when:g}')}(?![\d.])", described), (name, when)


def test_campaign_help_and_argument_checks_do_not_import_the_registries(tmp_path):
    """--help and the --faults/--scenes checks come from bench.campaigns.case_names; bench.campaigns.faults itself
    imports the bridge and the driver only where a case runs."""
    script = """
import sys
from bench.cli.main import build_parser
p = build_parser()
p.parse_args(["campaign", "--faults", "none,cs_glitch", "--scenes", "rest", "--junit", sys.argv[1]])
light = "bench.campaigns.faults" not in sys.modules
import bench.campaigns.faults
print(light, [m for m in ("bench.hosts.bridge", "bench.hosts.driver", "bench.hosts.cosim") if m in sys.modules])
"""
    done = subprocess.run([sys.executable, "-c", script, str(tmp_path / "c.xml")], cwd=REPO,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "[]"]

