"""The campaign's JUnit XML stays well-formed whatever text a case carries: XML 1.0 has no way to write most
control characters (ESC from a coloured message, NUL, BEL), so a problem, a firmware path or an unfinished
campaign's reason holding one is written with it spelled out (``\\x1b``), never raw (a CI parser would refuse the
whole report)."""

import xml.etree.ElementTree as ET

import pytest

from bench.campaigns import faults as campaign

pytestmark = pytest.mark.unit

CONTROL = "\x1b[31mred\x1b[0m \x00 \x07 \ufffe"


def test_a_case_with_control_characters_gives_a_parseable_report_that_names_them(tmp_path):
    result = {"fault": "serial_loss", "scene": "taps", "seed": 2, "spi": "software", "passed": False,
              "firmware": f"/tmp/fw{CONTROL}.c", "expected": f"resync {CONTROL}", "problem": f"frames {CONTROL}",
              "seconds": 0.25}
    path = tmp_path / "junit.xml"
    campaign.write_junit([result], path)
    suite = ET.parse(path).getroot()  # well-formed
    case = suite.find("testcase")
    assert "\\x1b[31mred\\x1b[0m \\x00 \\x07 \\ufffe" in case.find("failure").get("message")
    assert "\\x1b" in case.find("system-out").text and "\\x00" in case.find("failure").text
    assert "\\x1b" in suite.find("properties/property[@name='firmware']").get("value")
    assert "\t" not in CONTROL and "tab\tand\nline" == campaign.xml_text("tab\tand\nline")  # (allowed: kept)


def test_an_unfinished_campaign_with_control_characters_in_its_reason_gives_a_parseable_report(tmp_path):
    path = tmp_path / "junit.xml"
    campaign.write_unfinished_junit(path, f"could not build {CONTROL}")
    error = ET.parse(path).getroot().find("testcase/error")
    assert error.get("message") == "could not build \\x1b[31mred\\x1b[0m \\x00 \\x07 \\ufffe"
