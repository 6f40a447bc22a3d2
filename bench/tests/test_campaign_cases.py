"""Every case of the default fault campaign (9 faults × 4 scenes, seed 0) through the bridge firmware, a pty and the
host driver passes — and every check that can tell a fault from its absence fails on the same bench without the
fault, so a case cannot pass because nothing happened.  ``none`` and ``cs_glitch`` expect the host to see nothing
(a healthy link; a chip-select window with no clock edges is ignored): ``none`` has no fault to miss, and
``cs_glitch`` also needs the bus's trace of its glitches (sensor 1's port counts them), so a glitch dropped on the
way fails it, on either SPI bus; a case whose scheduled actions never happened fails for that.  The fluid leak's
negatives are in test_campaign_leak.py."""

from __future__ import annotations

import re

import pytest

from bench.campaigns import faults as campaign
from bench.campaigns.case_names import FAULT_EXPECTED, SCENE_DESCRIPTIONS
from bench.campaigns.faults import FaultCase, run_case

pytestmark = pytest.mark.unit


def test_the_default_campaign_has_36_cases_and_every_one_passes():
    tasks = campaign.campaign_tasks(FAULT_EXPECTED, SCENE_DESCRIPTIONS, [0])
    assert len(tasks) == 36  # README: "36 cases"
    failed = [(t.fault, t.scene, r["problem"]) for t in tasks
              if not (r := run_case(campaign.FAULTS[t.fault], t.scene, t.seed))["passed"]]
    assert not failed, failed


@pytest.mark.parametrize("fault, words", [
    ("unplug_replug", "sensor 2 was not lost and found again"),
    ("parity_errors", "bad parity was not flagged"),
    ("miso_stuck", "the stuck sensor is still streamed"),
    ("brownout_reset", "no error word reached the host"),
    ("serial_corruption", "corruption went unnoticed"),
    ("serial_loss", "corruption went unnoticed"),
])
def test_each_check_fails_without_its_fault(fault, words):
    """The same bench (sensor count) without the fault's schedule or line errors: the check must object."""
    kw, _, check = campaign.FAULT_CASES[fault]
    healthy = FaultCase(f"{fault} without the fault", "—", {k: v for k, v in kw.items() if k == "n_sensors"}, [],
                        check)
    result = run_case(healthy, "rest", 0)
    assert not result["passed"] and words in result["problem"], result


def test_a_brownout_inside_a_frame_loses_exactly_the_pending_result():
    """The brown-out lands between a slot's sampling command and its read: that read gets an error word (flagged,
    counted by the firmware), the sensor stays on the bus."""
    seen = {}

    def record(frames, status, stats):
        seen.update(bad=sum(int((f.status != 0).sum()) for f in frames), error_words=status.error_words,
                    mask=frames[-1].sensor_mask)

    kw, schedule, _ = campaign.FAULT_CASES["brownout_reset"]
    run_case(FaultCase("brownout", "—", kw, schedule, record), "taps", 0)
    assert seen == {"bad": 1, "error_words": 1, "mask": 0b01}


def test_a_fault_whose_actions_never_happen_fails_the_case():
    """A case whose fault is scheduled after the stream ends checks nothing: it fails, saying so (this is what keeps
    ``cs_glitch``, whose correct reaction is that nothing is seen, from passing without a glitch)."""
    late = FaultCase("late glitch", "—", {}, [(100.0, lambda b: b.glitch(1))], campaign.FAULT_CASES["cs_glitch"][2])
    result = run_case(late, "rest", 0)
    assert not result["passed"] and "1 of the fault's scheduled actions never happened" in result["problem"]


@pytest.mark.parametrize("spi", ["software", pytest.param("rtl", marks=[pytest.mark.rtl, pytest.mark.firmware])])
def test_the_glitch_case_passes_only_with_its_glitches_on_the_bus(spi):
    """cs_glitch's correct reaction shows the host nothing, so a glitch lost on the way would leave a healthy link
    that passes: with its glitches the case passes; with every other one of its schedule's actions doing nothing
    it fails, naming how many empty chip-select windows sensor 1 saw and how many the case makes — over either SPI
    bus."""
    import dataclasses

    glitch = campaign.FAULTS["cs_glitch"]
    result = run_case(glitch, "rest", 0, spi=spi)
    assert result["passed"], result
    half = dataclasses.replace(glitch, schedule=[(dt, act if k % 2 else lambda b: None)
                                                 for k, (dt, act) in enumerate(glitch.schedule)])
    result = run_case(half, "rest", 0, spi=spi)
    assert not result["passed"] and result["problem"].startswith(
        f"sensor 1 saw {campaign.CS_GLITCHES // 2} chip-select windows with no clock edges; the case glitches it "
        f"{campaign.CS_GLITCHES} times"), result


def test_a_fault_that_silences_the_stream_fails_the_case_saying_how_many_frames_came():
    """Unplugging a bench's only sensor stops the firmware's frames: with a check that accepts anything, the case
    still fails, naming the frames that arrived (fewer than half the 150 asked for) — a silenced stream is never a
    pass."""
    silenced = FaultCase("only sensor unplugged", "—", {}, [(0.1, lambda b: b.unplug(1))],
                         lambda frames, status, stats: None)
    result = run_case(silenced, "rest", 0)
    assert not result["passed"] and re.fullmatch(r"only \d+ frames arrived", result["problem"]), result
    assert int(result["problem"].split()[1]) < 75


def test_a_code_past_12_bits_from_the_driver_fails_the_case(monkeypatch):
    """A driver fault stood in for: the real driver's frames, one clean PAC code among them raised to 4096.  A case
    on a healthy link then fails for out-of-range data; without the change it passes (test_the_default_campaign…)."""
    import numpy as np

    from bench.hosts.driver import BridgeDriver
    from emulator.channels import PAC

    real = BridgeDriver.frames

    def frames(self, *args, **kwargs):
        for k, frame in enumerate(real(self, *args, **kwargs)):
            if k == 20:
                frame.codes[np.flatnonzero(frame.channels == PAC)[0], 0] = 4096
            yield frame

    monkeypatch.setattr(BridgeDriver, "frames", frames)
    result = run_case(campaign.FAULTS["none"], "rest", 0)
    assert not result["passed"] and result["problem"] == "out-of-range data reached the caller", result


def test_a_brownout_lands_whenever_it_is_due():
    """A reset due outside a frame's sequence (the firmware's once-a-second detection, a delay) acts at the next HAL
    call, not at the next frame; inside a sequence it never splits a window held open on one sensor; a reset at no
    instant is refused."""
    from bench.hosts.cosim import VirtualBoard, default_sensors

    board = VirtualBoard(default_sensors(1))
    with pytest.raises(ValueError, match="finite instant"):
        board.reset_at(1, float("nan"))
    resets = []
    board.bus.ports[1].reset = lambda: resets.append(board.t)
    board.reset_at(1, 0.5e-3)
    board.delay_us(None, 400)
    assert resets == [] and board.resets
    board.delay_us(None, 200)  # past the instant: applied at this call
    assert resets == [pytest.approx(0.6e-3)] and not board.resets


def test_events_and_resets_scheduled_out_of_order_each_act_at_their_own_time():
    """A fault campaign's schedule need not be sorted: actions and resets given latest first act at their own
    instants, earliest first, each within the HAL call (here 100 µs delays) that passes it."""
    from bench.hosts.cosim import VirtualBoard, default_sensors

    board = VirtualBoard(default_sensors(1))
    acted, resets = [], []
    board.bus.ports[1].reset = lambda: resets.append(board.t)
    board.at(1.0e-3, lambda b: acted.append(("late", b.t)))
    board.at(0.2e-3, lambda b: acted.append(("early", b.t)))
    board.reset_at(1, 0.9e-3)
    board.reset_at(1, 0.3e-3)
    for _ in range(12):
        board.delay_us(None, 100)
    assert [name for name, _ in acted] == ["early", "late"]
    for when, due in zip([t for _, t in acted] + resets, (0.2e-3, 1.0e-3, 0.3e-3, 0.9e-3)):
        assert due - 1e-12 <= when <= due + 100e-6 + 1e-12  # within the HAL call (100 µs) that passes it

def test_a_reset_due_inside_a_held_window_waits_for_it_to_close():
    """A sampling command, then a 32-bit read held over two words: a reset due between the two words acts after
    the window (here: the sequence's end, at the firmware's next HAL call), so the read is the unsplit one's."""
    import ctypes as C

    import numpy as np

    from bench.hosts.cosim import BtWord, VirtualBoard, default_sensors
    from emulator.spi import protocol as proto
    from emulator.spi.model import SELECT_CODE

    def run(reset):
        board = VirtualBoard(default_sensors(1, seed=3))
        words = (BtWord * 3)((0, SELECT_CODE[1], 0, int(proto.sample_command(1)) << 8),
                             (60_000, SELECT_CODE[1], 1, 0), (64_000, SELECT_CODE[1], 0, 0))
        if reset:
            board.reset_at(1, board.t + 62e-6)
        miso = (C.c_uint16 * 3)()
        board.spi_sequence(None, words, miso, 3)
        return list(miso), board.resets

    (plain, _), (with_reset, pending) = run(False), run(True)
    assert with_reset == plain and np.any(plain) and pending == [(pytest.approx(62e-6), 1)]


# --- every clause of each check, on hand-made frames (a mutation hunt: only each check's first clause was tested) ---
def _frames(*masks, bad=0, flag=1):
    """Frames with these sensor masks; the first ``bad`` of them carry one sample of status ``flag``."""
    import numpy as np
    from types import SimpleNamespace

    return [SimpleNamespace(sensor_mask=m, status=np.array([[flag if k < bad else 0], [0]])) for k, m in
            enumerate(masks)]


def _status(**counts):
    from types import SimpleNamespace

    return SimpleNamespace(**{"losses": 1, "finds": 1, "parity_errors": 1, "error_words": 1, **counts})


def _stats(**counts):
    from types import SimpleNamespace

    return SimpleNamespace(**{"crc_errors": 0, "dropped_frames": 0, **counts})


@pytest.mark.parametrize("check, frames, status, stats, words", [
    ("_mask_returns", _frames(0b11, 0b01, 0b01), _status(), _stats(), "not lost and found again"),
    ("_mask_returns", _frames(0b11, 0b01, 0b11), _status(losses=0), _stats(), "no loss/find"),
    ("_mask_returns", _frames(0b11, 0b01, 0b11), _status(finds=0), _stats(), "no loss/find"),
    ("_flags_parity", _frames(0b01, bad=1), _status(parity_errors=0), _stats(), "bad parity was not flagged"),
    ("_survives_reset", _frames(0b01, 0b01, 0b01, bad=3, flag=2), _status(), _stats(), "3 bad samples"),
    ("_survives_reset", _frames(0b01, 0b00, bad=1, flag=2), _status(), _stats(), "the reset sensor was dropped"),
    ("_survives_reset", _frames(0b01, bad=1, flag=2), _status(error_words=0), _stats(), "no error word"),
    ("_clean", _frames(0b01, bad=1), _status(), _stats(), "1 flagged samples"),
    ("_clean", _frames(0b01), _status(), _stats(dropped_frames=2), "2 dropped frames"),
])
def test_every_clause_of_a_check_objects_on_its_own(check, frames, status, stats, words):
    problem = getattr(campaign, check)(frames, status, stats)
    assert problem is not None and words in problem, problem


@pytest.mark.parametrize("check, frames", [("_mask_returns", _frames(0b11, 0b01, 0b11)),
                                           ("_flags_parity", _frames(0b01, bad=1)),
                                           ("_survives_reset", _frames(0b01, 0b01, bad=2, flag=2)),
                                           ("_clean", _frames(0b01, 0b01))])
def test_the_same_checks_pass_what_the_fault_should_look_like(check, frames):
    assert getattr(campaign, check)(frames, _status(), _stats()) is None


def test_the_junit_report_counts_its_failures(tmp_path):
    import xml.etree.ElementTree as ET

    results = [{"fault": "none", "scene": s, "seed": 0, "expected": "-", "passed": s != "taps", "problem": "x",
                "seconds": 0.5} for s in ("rest", "taps", "sphere_drops")]
    campaign.write_junit(results, tmp_path / "c.xml")
    suite = ET.parse(tmp_path / "c.xml").getroot()
    assert suite.get("tests") == "3" and suite.get("failures") == "1" == str(len(suite.findall(".//failure")))


# --- the other checks' clauses, the summary table and the task list (a second mutation hunt) ---------------------
@pytest.mark.parametrize("check, frames, stats, words", [
    ("_clean", _frames(0b01), _stats(crc_errors=1), "1 CRC errors"),
    ("_resyncs", _frames(0b01), _stats(), "corruption went unnoticed"),
    ("_drops_sensor", _frames(0b11, 0b11), _stats(), "the stuck sensor is still streamed"),
    ("_drops_sensor", _frames(0b11, 0b01, 0b11), _stats(), "the stuck sensor is still streamed"),  # back again
])
def test_more_clauses_object_on_their_own(check, frames, stats, words):
    problem = getattr(campaign, check)(frames, _status(), stats)
    assert problem is not None and words in problem, problem


@pytest.mark.parametrize("check, frames, stats", [
    ("_resyncs", _frames(0b01), _stats(crc_errors=1)),  # either sign of a noticed corruption is enough
    ("_resyncs", _frames(0b01), _stats(dropped_frames=1)),
    ("_drops_sensor", _frames(0b11, 0b11, 0b01), _stats()),  # streamed until it stuck, then dropped
])
def test_those_checks_pass_what_the_fault_should_look_like(check, frames, stats):
    assert getattr(campaign, check)(frames, _status(), stats) is None


def test_the_summary_says_pass_or_fail_per_case_and_counts_them():
    results = [{"fault": "none", "scene": s, "seed": 3, "expected": "a healthy link", "passed": s != "taps",
                "problem": "2 bad samples" if s == "taps" else None, "seconds": 0.1} for s in ("rest", "taps", "press")]
    lines = campaign.summary(results).splitlines()
    assert lines[1].split()[3:] == ["PASS", "a", "healthy", "link"]
    assert lines[2].split()[3:] == ["FAIL", "2", "bad", "samples"]  # a failure shows its problem, not the hope
    assert lines[-1] == "2 passed, 1 failed"


def test_the_summary_columns_are_as_wide_as_their_longest_entry():
    """A scene file's long name, a long fault name and a five-digit seed keep every line's columns aligned (the
    scene column was 13 wide: grip.toml[seed=K]'s file names pushed their lines' results right), and a problem of
    several lines (a build's diagnostics) stays on its case's line."""
    scenes = ("rest", "a_scene_file_with_a_long_name.toml", "taps")
    results = [{"fault": f, "scene": s, "seed": seed, "expected": "as expected", "passed": s != "taps",
                "problem": "no build:\n  error: x\n" if s == "taps" else None, "seconds": 0.1}
               for f, seed in (("none", 7), ("serial_corruption", 12345)) for s in scenes]
    lines = campaign.summary(results).splitlines()
    assert len(lines) == len(results) + 2
    header, rows = lines[0], lines[1:-1]
    for r, row in zip(results, rows):
        scene_at = row.index(f" {r['scene']} ") + 1
        seed_ends = row.index(f" {r['seed']}  ", scene_at + len(r["scene"])) + 1 + len(str(r["seed"]))
        assert row.startswith(f"{r['fault']} ") and scene_at == header.index(" scene ") + 1, lines
        assert seed_ends == header.index(" seed ") + 5 and row.index("PASS" if r["passed"] else "FAIL") == \
            header.index(" result ") + 1, lines
    assert rows[2].endswith("FAIL    no build: / error: x")


def test_the_junit_failure_carries_the_problem_and_what_was_expected(tmp_path):
    import xml.etree.ElementTree as ET

    results = [{"fault": "parity_errors", "scene": "rest", "seed": 0, "expected": "flagged", "passed": False,
                "problem": "bad parity was not flagged", "seconds": 0.5}]
    campaign.write_junit(results, tmp_path / "c.xml")
    (failure,) = ET.parse(tmp_path / "c.xml").getroot().findall(".//failure")
    assert failure.get("message") == "bad parity was not flagged" and failure.text == "expected: flagged"


def test_the_task_list_is_every_fault_scene_and_seed_and_refuses_an_empty_or_unknown_name():
    tasks = campaign.campaign_tasks(["none", "cs_glitch"], ["rest", "taps"], [5, 6])
    assert [(t.fault, t.scene, t.seed) for t in tasks] == [
        (f, s, seed) for f in ("none", "cs_glitch") for s in ("rest", "taps") for seed in (5, 6)]
    for empty in (([], ["rest"], [0]), (["none"], [], [0]), (["none"], ["rest"], [])):
        with pytest.raises(ValueError, match="vacuously"):
            campaign.campaign_tasks(*empty)
    with pytest.raises(ValueError, match="unknown fault or scene: nope, nowhere"):
        campaign.campaign_tasks(["none", "nope"], ["rest", "nowhere"], [0])


def test_the_campaign_help_says_what_a_stopped_campaign_leaves_in_its_report():
    """A campaign stopped by Ctrl-C or SIGTERM writes a --junit report with one error (so that a CI step publishing
    reports shows the stop); --help still said it "writes no report"."""
    from bench.cli.campaigns import CAMPAIGN_HELP

    text = " ".join(CAMPAIGN_HELP.split())
    assert "writes no report" not in text
    assert "report holds one error saying it was stopped" in text
