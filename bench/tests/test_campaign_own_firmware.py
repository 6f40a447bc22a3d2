"""A firmware team checks its own firmware against the fault catalogue: ``run_campaign(firmware=...)`` and
``biotac-bench campaign --firmware FILE...`` run every case on it (the reference firmware had been the only one), a
firmware that misnumbers its frames fails the cases that can see it, and the JUnit report names the firmware and
carries the schema's ``errors`` and ``skipped`` counts, which CI tools validating against it require."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import replace

import pytest

from bench.campaigns import faults as campaign
from bench.hosts.cosim import FIRMWARE_DIR

pytestmark = pytest.mark.firmware

REFERENCE = (FIRMWARE_DIR / "bt_bridge.c").read_text()
SEQ_STEP = "    b->seq++;\n"
assert REFERENCE.count(SEQ_STEP) == 1, "the reference firmware's frame numbering changed: update this test's edit"


def own(tmp_path, skip_numbers: bool = False):
    """The reference firmware as the user's own; with ``skip_numbers`` every frame's number jumps by 2 (a host counts
    a dropped frame between any two)."""
    src = tmp_path / ("skipping.c" if skip_numbers else "mine.c")
    src.write_text(REFERENCE.replace(SEQ_STEP, "    b->seq += 2;\n") if skip_numbers else REFERENCE)
    return src


def test_a_campaign_runs_your_firmware_and_fails_it_where_it_misbehaves(tmp_path):
    good, bad = own(tmp_path), own(tmp_path, skip_numbers=True)
    tasks = campaign.campaign_tasks(["none"], ["rest"], [0])
    ran = {}
    for name, firmware in (("good", [good]), ("bad", [bad])):
        task = replace(tasks[0], firmware=tuple(map(str, firmware)))
        ran[name] = campaign.run_case_task(task)
    assert ran["good"]["passed"] and ran["good"]["firmware"] == str(good)
    assert not ran["bad"]["passed"] and "dropped" in ran["bad"]["problem"] and ran["bad"]["firmware"] == str(bad)
    campaign.write_junit([ran["bad"]], tmp_path / "c.xml")
    suite = ET.parse(tmp_path / "c.xml").getroot()
    assert (suite.get("failures"), suite.get("errors"), suite.get("skipped")) == ("1", "0", "0")
    props = {p.get("name"): p.get("value") for p in suite.iter("property")}
    assert props == {"spi": "software", "firmware": str(bad), "driver": "bench.hosts.driver:BridgeDriver"}


def test_the_reference_firmware_is_named_so_in_the_report(tmp_path):
    results = [{"fault": "none", "scene": "rest", "seed": 0, "expected": "-", "passed": True, "problem": None,
                "seconds": 0.1}]  # results from before the firmware was recorded: the reference one
    campaign.write_junit(results, tmp_path / "c.xml")
    props = {p.get("name"): p.get("value") for p in ET.parse(tmp_path / "c.xml").getroot().iter("property")}
    assert props["firmware"] == "reference"


def test_the_campaign_command_takes_your_firmware_and_refuses_a_library_beside_sources(tmp_path, capsys):
    from bench.cli.main import main

    src, report = own(tmp_path), tmp_path / "c.xml"
    assert main(["campaign", "--firmware", str(src), "--faults", "none,serial_loss", "--scenes", "rest",
                 "--workers", "1", "--quiet", "--junit", str(report)]) == 0
    assert f"firmware: {src}" in capsys.readouterr().err
    props = {p.get("name"): p.get("value") for p in ET.parse(report).getroot().iter("property")}
    assert props["firmware"] == str(src)
    lib = tmp_path / "lib.so"
    lib.write_bytes(b"\x7fELF")
    other = tmp_path / "c2.xml"
    assert main(["campaign", "--firmware", str(lib), str(src), "--junit", str(other)]) == 2
    assert "campaign --firmware: " in capsys.readouterr().err and not other.exists()
