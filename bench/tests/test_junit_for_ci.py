"""The campaign's JUnit XML as a CI system (Jenkins, GitLab) reads it: the suite says when the campaign began
(``timestamp``, UTC without a zone, as the Ant JUnit schema has it) and on which host (``hostname``); every test
case — a passing one too — carries its output (``system-out``: what ran and what was expected); failures and errors
carry a ``type``; the suite ends with the ``system-out`` and ``system-err`` that schema requires."""

import re
import socket
import time
import xml.etree.ElementTree as ET
from datetime import datetime, timedelta, timezone

import pytest

from bench.campaigns import faults as campaign
from bench.tests.test_cli_review import invoke

pytestmark = pytest.mark.unit

RESULTS = [{"fault": "serial_loss", "scene": s, "seed": 2, "spi": "software", "firmware": "reference",
            "expected": "the driver resynchronises", "passed": s != "taps",
            "problem": None if s != "taps" else "3 corrupted frames reached the caller", "seconds": 0.25}
           for s in ("rest", "taps")]
#: 12:34:56.7 at UTC+01:00 is 11:34:56 UTC (the fraction cut, not rounded: the campaign had begun by then)
STARTED = datetime(2026, 3, 1, 12, 34, 56, 700000, tzinfo=timezone(timedelta(hours=1)))


def _suite(path) -> ET.Element:
    return ET.parse(path).getroot()


def _ci_shape(suite: ET.Element) -> None:
    """What every report holds for CI: timestamp and hostname, properties first, the cases, then the suite's
    system-out and system-err; each case with one system-out; each failure or error with a message and a type."""
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d", suite.get("timestamp")), suite.get("timestamp")
    assert suite.get("hostname") == (socket.gethostname() or "localhost")
    tags = [child.tag for child in suite]
    assert tags == ["properties"] + ["testcase"] * int(suite.get("tests")) + ["system-out", "system-err"], tags
    for case in suite.iter("testcase"):
        assert len(case.findall("system-out")) == 1 and case.find("system-out").text.strip(), ET.tostring(case)
        for bad in case.findall("failure") + case.findall("error"):
            assert bad.get("message") and bad.get("type"), ET.tostring(case)


def test_every_case_carries_its_output_and_the_suite_when_and_where_it_ran(tmp_path):
    campaign.write_junit(RESULTS, tmp_path / "c.xml", STARTED)
    suite = _suite(tmp_path / "c.xml")
    _ci_shape(suite)
    assert suite.get("timestamp") == "2026-03-01T11:34:56"
    passed, failed = suite.findall("testcase")
    assert passed.find("failure") is None
    out = passed.find("system-out").text
    assert out.splitlines() == ["fault serial_loss in scene rest, seed 2, over the software SPI bus, firmware "
                                "reference, driver bench.hosts.driver:BridgeDriver",
                                "expected: the driver resynchronises", "PASS", "wall time 0.250 s"]
    assert "FAIL: 3 corrupted frames reached the caller" in failed.find("system-out").text
    assert failed.find("failure").get("type") == "unexpected-reaction"


def test_an_unfinished_campaigns_report_has_the_same_shape(tmp_path):
    campaign.write_unfinished_junit(tmp_path / "c.xml", "stopped by Ctrl-C", "rtl", STARTED)
    suite = _suite(tmp_path / "c.xml")
    _ci_shape(suite)
    assert suite.get("timestamp") == "2026-03-01T11:34:56" and suite.get("errors") == "1"
    assert suite.find("testcase/error").get("type") == "unfinished"
    assert suite.find("testcase/system-out").text == "stopped by Ctrl-C\n"


def test_a_stopped_campaigns_report_with_finished_cases_and_a_driver_error_has_the_same_shape(tmp_path):
    """The cases that had finished (a pass, a failure, and an error: a case whose driver raised, its message
    holding an escape character) before the one saying it stopped: the counts add up (tests = cases + 1; the
    driver's error and the stop are errors, the failure a failure) and the report parses, control characters and
    all."""
    errored = dict(RESULTS[0], seed=3, passed=False, error=True, driver="team.py:open",
                   problem="driver team.py:open raised OSError: \x1b[31mbusy")
    campaign.write_unfinished_junit(tmp_path / "c.xml", "stopped; the 3 that had finished are reported", "software",
                                    STARTED, RESULTS + [errored])
    suite = _suite(tmp_path / "c.xml")
    _ci_shape(suite)
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors")) == ("4", "1", "2")
    kinds = [[(bad.tag, bad.get("type")) for bad in case if bad.tag != "system-out"] for case in suite.iter("testcase")]
    assert kinds == [[], [("failure", "unexpected-reaction")], [("error", "driver-error")], [("error", "unfinished")]]
    assert suite.findall("testcase")[2].find("error").get("message").endswith("\\x1b[31mbusy")
    props = {p.get("name"): p.get("value") for p in suite.iter("property")}
    assert props == {"spi": "software", "firmware": "reference",
                     "driver": "bench.hosts.driver:BridgeDriver; team.py:open"}


def test_a_machine_without_a_name_is_localhost(tmp_path, monkeypatch):
    monkeypatch.setattr(socket, "gethostname", lambda: "")
    campaign.write_junit(RESULTS, tmp_path / "c.xml")
    assert _suite(tmp_path / "c.xml").get("hostname") == "localhost"


def test_the_campaign_command_stamps_its_report_with_when_it_began(tmp_path, monkeypatch, capsys):
    """The timestamp is the campaign's start, not the moment the report was written after the cases ran."""
    began = []

    def run_campaign(*a, **kw):
        began.append(datetime.now(timezone.utc).replace(microsecond=0, tzinfo=None))
        time.sleep(1.2)  # the cases take a while
        return RESULTS[:1]

    monkeypatch.setattr(campaign, "run_campaign", run_campaign)
    status, out, err = invoke(["campaign", "--faults", "serial_loss", "--scenes", "rest", "--junit",
                               tmp_path / "c.xml", "--quiet"], capsys)
    assert status == 0, err
    suite = _suite(tmp_path / "c.xml")
    _ci_shape(suite)
    assert datetime.fromisoformat(suite.get("timestamp")) <= began[0], (suite.get("timestamp"), began)
