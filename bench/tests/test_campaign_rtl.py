"""The fault campaign over the Verilog RTL (``campaign --spi rtl``): the same verdicts as over the software bus, the
bus named in the summary and the JUnit report, and a fault the RTL could not carry refused by name before anything
runs."""

import xml.etree.ElementTree as ET

import pytest

from bench.campaigns import faults as campaign
from bench.tests.test_cli_review import invoke

#: a small campaign over either bus: hot-plugging and the brown-out (the RTL's sensors present and reset mask), the
#: glitch and an SPI fault set mid-stream, each with a reaction of its own to see
FAULTS, SCENE = ["none", "unplug_replug", "parity_errors", "brownout_reset", "cs_glitch"], "rest"


@pytest.mark.rtl
@pytest.mark.firmware
def test_a_small_campaign_gives_the_same_verdicts_over_the_rtl_as_over_the_software_bus(tmp_path):
    """Five faults, one scene, one seed, on one LocalCluster worker: every case passes over both buses (the
    brown-out's check needs the reset to have lost a pending result, so over the RTL it passes only if the reset
    reached the RTL; unplug_replug's, the sensor lost and found again), each result and each report names its bus,
    and the two reports hold the same test cases."""
    from bench.campaigns.engine import ClusterSpec, close, connect

    client = connect(ClusterSpec(workers=1))
    try:
        runs = {spi: campaign.run_campaign(FAULTS, [SCENE], [0], client=client, spi=spi) for spi in ("software", "rtl")}
    finally:
        close(client)
    verdicts = {spi: [(r["fault"], r["passed"], r["problem"]) for r in results] for spi, results in runs.items()}
    assert verdicts["rtl"] == verdicts["software"] == [(f, True, None) for f in FAULTS]
    cases = {}
    for spi, results in runs.items():
        assert {r["spi"] for r in results} == {spi}
        assert campaign.summary(results).splitlines()[0].endswith(f"(SPI bus: {spi})")
        campaign.write_junit(results, tmp_path / f"{spi}.xml")
        suite = ET.parse(tmp_path / f"{spi}.xml").getroot()
        assert [(p.get("name"), p.get("value")) for p in suite.findall("properties/property")] == [
            ("spi", spi), ("firmware", "reference"), ("driver", "bench.hosts.driver:BridgeDriver")]
        cases[spi] = [(c.get("classname"), c.get("name")) for c in suite.findall("testcase")]
    assert cases["rtl"] == cases["software"]


@pytest.mark.unit
def test_a_fault_the_rtl_cannot_carry_is_refused_by_name_before_anything_runs(monkeypatch, capsys, tmp_path):
    """Every fault runs over the RTL now; one listed as needing the software bus (here ``unplug_replug``, as it
    was before hot-plugging reached the RTL) is refused over the RTL naming the fault, why, and what to run instead
    — by the task list and by the command line, in one line with exit status 2, before the campaign runs or its
    report is touched; over the software bus it is taken."""
    from bench.campaigns import case_names

    assert case_names.NEEDS_SOFTWARE_SPI == {}
    campaign.campaign_tasks(case_names.FAULT_EXPECTED, [SCENE], [0], "rtl")  # every fault taken
    monkeypatch.setitem(case_names.NEEDS_SOFTWARE_SPI, "unplug_replug", "hot-plugging (say)")
    with pytest.raises(ValueError, match=r"^unplug_replug needs the software SPI bus: hot-plugging \(say\)\. Run it "
                                         r"with --spi software, and the others over the RTL with --faults "
                                         r"none,cs_glitch$"):
        campaign.campaign_tasks(["none", "unplug_replug", "cs_glitch"], [SCENE], [0], "rtl")
    assert [t.spi for t in campaign.campaign_tasks(["unplug_replug"], [SCENE], [0, 1], "software")] == ["software"] * 2
    assert [t.spi for t in campaign.campaign_tasks(["none"], [SCENE], [0], "rtl")] == ["rtl"]
    with pytest.raises(ValueError, match=r"spi = 'verilog': one of software, rtl"):
        campaign.campaign_tasks(["none"], [SCENE], [0], "verilog")

    def ran(*args, **kw):
        raise AssertionError("the campaign ran with a fault the RTL cannot carry")

    monkeypatch.setattr(campaign, "run_campaign", ran)
    report = tmp_path / "c.xml"
    status, out, err = invoke(["campaign", "--spi", "rtl", "--scenes", SCENE, "--junit", str(report)], capsys)
    assert status == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert "unplug_replug needs the software SPI bus" in err and "--spi software" in err
    assert "--faults none,parity_errors,miso_stuck,brownout_reset,cs_glitch" in err
    assert list(tmp_path.iterdir()) == []  # no report, no lock left


@pytest.mark.unit
def test_results_over_two_buses_make_no_single_report(tmp_path):
    """A report names one bus: results from both are refused (ValueError naming them) rather than reported as one;
    results from before the bus was recorded count as the software bus's."""
    results = [{"fault": "none", "scene": SCENE, "seed": 0, "expected": "-", "passed": True, "problem": None,
                "seconds": 0.1, **extra} for extra in ({"spi": "rtl"}, {})]
    with pytest.raises(ValueError, match="results over SPI buses rtl, software: a report holds one campaign"):
        campaign.write_junit(results, tmp_path / "c.xml")
    assert campaign.summary(results[1:]).splitlines()[0].endswith("(SPI bus: software)")


@pytest.mark.rtl
@pytest.mark.firmware
def test_a_case_runs_over_the_bus_its_task_names(monkeypatch):
    """A task's bus reaches the bench its case builds (the bench's board is then the RTL's), for either bus."""
    from bench.hosts import bridge

    built = []

    class Spy(bridge.FirmwareBench):
        def __init__(self, *a, **kw):
            super().__init__(*a, **kw)
            built.append((kw.get("spi"), type(self.board.bus).__name__))

    monkeypatch.setattr(bridge, "FirmwareBench", Spy)
    for spi in ("rtl", "software"):
        result = campaign.run_case_task(campaign.CaseTask("none", SCENE, 0, spi))
        assert result["passed"] and result["spi"] == spi
    assert built == [("rtl", "RtlBus"), ("software", "Bus")]


@pytest.mark.unit
def test_an_rtl_harness_that_does_not_build_is_one_line_and_an_unfinished_report(monkeypatch, capsys, tmp_path):
    """campaign --spi rtl builds the C++ harness once before any case: a build that fails (no Verilator, a compiler
    error) is the bench's error, naming the harness, with its diagnostics and exit status 2 (no traceback), and the --junit report says the campaign could not run, over the
    RTL — an earlier campaign's passing report left there would be published as this one's. (The harness's error is
    a RuntimeError, not the bench's own: it ended the command in a traceback and left the earlier report.)"""
    from emulator.rtl import harness

    def no_build(self):
        raise harness.HarnessError("building the harness failed:\n%Error: verilator: not found")

    monkeypatch.setattr(harness.Harness, "ensure_built", no_build)
    report = tmp_path / "c.xml"
    campaign.write_junit([{"fault": "none", "scene": SCENE, "seed": 0, "expected": "-", "passed": True,
                           "problem": None, "seconds": 0.1}], report)  # an earlier campaign's, passing
    status, out, err = invoke(["campaign", "--spi", "rtl", "--faults", "none", "--scenes", SCENE, "--junit",
                               str(report), "--quiet"], capsys)
    assert status == 2 and "Traceback" not in err, err
    said = err.split("error: ", 1)[1]  # (the line after the cases' count; the build's diagnostics follow it)
    assert said.startswith("--spi rtl: the RTL harness could not be built") and "verilator: not found" in said, err
    suite = ET.parse(report).getroot()
    assert suite.get("errors") == "1" and suite.find("testcase").get("name") == "unfinished"
    assert [(p.get("name"), p.get("value")) for p in suite.findall("properties/property")] == [("spi", "rtl")]
    assert "the campaign could not run" in suite.find("testcase/error").get("message")


@pytest.mark.rtl
@pytest.mark.firmware
def test_a_scene_files_cases_run_over_the_rtl_with_its_sensor_1(monkeypatch, tmp_path, capsys):
    """``campaign --spi rtl --scenes grip.toml``: a scene file asking for the RTL (``host.spi = "rtl"``) is taken
    over the RTL, and its case's bench is the RTL's with sensor 1 of the scene (its unit's parameter, its press) —
    in process, where the bench can be looked at; then the command over a LocalCluster worker: the case passes and
    the report names it by the file over the RTL."""
    from bench.campaigns.scene_files import campaign_scene
    from bench.hosts import bridge
    from bench.tests.test_campaign_scene_files import GRIP

    scene = tmp_path / "grip.toml"
    scene.write_text(GRIP + "\n[host]\nspi = \"rtl\"\n")
    built = []

    class Spy(bridge.FirmwareBench):
        def __init__(self, *a, **kw):
            super().__init__(*a, **kw)
            s1 = self.board.sensors[1]
            built.append((type(self.board.bus).__name__, s1.params.inflation_volume_mL,
                          [type(st).__name__ for st in s1.stimuli]))

    monkeypatch.setattr(bridge, "FirmwareBench", Spy)
    result = campaign.run_case_task(campaign.CaseTask("none", campaign_scene(str(scene), ["none"], "rtl"), 0, "rtl"))
    assert result["passed"], result["problem"]
    assert built == [("RtlBus", 0.6, ["Press"])]
    monkeypatch.undo()
    report = tmp_path / "c.xml"
    status, out, err = invoke(["campaign", "--spi", "rtl", "--faults", "cs_glitch", "--scenes", scene, "--workers",
                               "1", "--quiet", "--junit", report], capsys)
    assert status == 0, out + err
    suite = ET.parse(report).getroot()
    assert [(p.get("name"), p.get("value")) for p in suite.findall("properties/property")][0] == ("spi", "rtl")
    assert [(c.get("name"), c.find("failure")) for c in suite.iter("testcase")] == [("grip.toml[seed=0]", None)]
