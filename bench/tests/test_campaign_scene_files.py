"""Your own scenes in the fault campaign (``campaign --scenes my_scene.toml``): a real campaign over a scene file of
the test's own, its cases named by the file and seed with the same verdicts for 1 and 2 workers; sensor 1 built
from the scene; each thing the campaign cannot honour refused in one line naming the file and the field, before
anything runs, with the --junit report saying why; and every example of ``campaign --help`` parses."""

import xml.etree.ElementTree as ET

import pytest

from bench.campaigns import faults as campaign
from bench.campaigns.scene_files import CASE_FRAMES, LEAK_TAIL_FRAMES, SceneRefused, campaign_scene, quiet_start_s
from bench.cli import main as cli
from bench.cli.campaigns import CAMPAIGN_HELP

pytestmark = pytest.mark.unit

#: a 1 s scene: sensor 1 of a unit of its own with a parameter on top, pressed 1 N from 0.3 s
GRIP = """\
[scene]
name = "grip"
duration_s = 1.0
seed = 99

[sensor]
inflation_volume_mL = 0.6

[[stimulus]]
kind = "press"
start_s = 0.3
force_N = 1.0
ramp_s = 0.1
hold_s = 0.2
"""


#: GRIP on the nominal sensor (fault fluid_leak predicts the nominal sensor's leak)
NOMINAL_GRIP = GRIP.replace("[sensor]\ninflation_volume_mL = 0.6\n", "")


def _scene(tmp_path, text: str = GRIP, name: str = "grip.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_scene_file_gives_every_fault_case_its_sensor_1_and_the_campaigns_seed(tmp_path):
    cs = campaign_scene(str(_scene(tmp_path)), ["unplug_replug"], "software")
    sensors = cs.sensors(2, seed=5)
    assert sensors[1].params.inflation_volume_mL == 0.6 and sensors[1].seed == 5  # the campaign's seed, not 99
    assert [type(st).__name__ for st in sensors[1].stimuli] == ["Press"] and sensors[1].stimuli[0].start_s == 0.3
    assert sensors[2].stimuli == () and sensors[2].params.inflation_volume_mL == 0.6  # sensor 1's twin, at rest
    leaking = cs.sensors(1, seed=5, faults={"fluid_leak_mL_per_min": 6.0})[1]
    assert leaking.faults == {"fluid_leak_mL_per_min": 6.0}
    assert cs.label == "grip.toml" and cs.frames == CASE_FRAMES  # a short scene: a built-in scene's case
    # a failed task's message names it by file, not by the scene's whole text
    assert repr(cs) == f"CampaignScene(label='grip.toml', path={str(tmp_path / 'grip.toml')!r})"
    long = campaign_scene(str(_scene(tmp_path, GRIP.replace("duration_s = 1.0", "duration_s = 3.0"), "long.toml")),
                          ["none"], "software")
    assert long.frames == 300 + LEAK_TAIL_FRAMES  # the whole scene, and the leak check's frames at rest after it


def test_the_at_rest_check_ends_at_the_scene_files_first_stimulus(tmp_path):
    """``none`` reads every frame before the scene's first stimulus as the sensor at rest: a press at 0.2 s passes
    only when the check stops there (the scene's stimuli, not a built-in scene's), and the case passes."""
    early = GRIP.replace("start_s = 0.3", "start_s = 0.2")
    cs = campaign_scene(str(_scene(tmp_path, early)), ["none"], "software")
    r = campaign.run_case(campaign.FAULTS["none"], cs, 0)
    assert r["passed"], r["problem"]
    assert r["scene"] == "grip.toml" and r["scene_file"] == str(tmp_path / "grip.toml")


def test_a_scene_files_case_streams_the_whole_scene_and_the_leak_checks_frames_after_it(tmp_path):
    """fluid_leak reads the resting PDC in the case's last frames: in a 2 s scene pressed from 1.2 to 1.6 s they
    fall in the press if the case stops after a built-in scene's 150 frames (1.5 s), after it if the case streams
    the whole scene."""
    late = NOMINAL_GRIP.replace("duration_s = 1.0", "duration_s = 2.0").replace("start_s = 0.3", "start_s = 1.2")
    cs = campaign_scene(str(_scene(tmp_path, late)), ["fluid_leak"], "software")
    r = campaign.run_case(campaign.FAULTS["fluid_leak"], cs, 0)
    assert r["passed"], r["problem"]


def test_a_campaign_over_a_scene_file_names_its_cases_by_file_and_seed_alike_for_1_and_2_workers(tmp_path, capsys):
    scene = _scene(tmp_path, NOMINAL_GRIP)
    argv = ["campaign", "--faults", "serial_loss,fluid_leak", "--scenes", f"{scene},rest", "--seeds", "2", "--quiet"]
    reports = []
    for workers in ("1", "2"):
        report = tmp_path / f"c{workers}.xml"
        assert cli.main(argv + ["--workers", workers, "--junit", str(report)]) == 0, capsys.readouterr()
        reports.append(ET.parse(report).getroot())
    cases = [[(c.get("classname"), c.get("name"), c.find("failure")) for c in r.iter("testcase")] for r in reports]
    assert cases[0] == cases[1] == [(f"campaign.{f}", f"{s}[seed={k}]", None) for f in ("serial_loss", "fluid_leak")
                                    for s in ("grip.toml", "rest") for k in (0, 1)]
    out = next(c for c in reports[0].iter("testcase") if c.get("name") == "grip.toml[seed=1]").find("system-out").text
    assert out.startswith(f"fault serial_loss in scene grip.toml ({scene}), seed 1,")
    # --seed K reruns one case by the name the report gives
    assert cli.main(["campaign", "--faults", "serial_loss", "--scenes", str(scene), "--seed", "1", "--quiet",
                     "--workers", "1", "--junit", str(tmp_path / "again.xml")]) == 0
    again = ET.parse(tmp_path / "again.xml").getroot()
    assert [c.get("name") for c in again.iter("testcase")] == ["grip.toml[seed=1]"]


#: (what the scene file changes in GRIP, the faults, the field its refusal names)
REFUSED = [
    ("[[stimulus]]\nkind = \"tap\"\nat_s = 0.5\npeak_N = 0.5\nsensor = 2\n", "cs_glitch", "describes 2 sensors"),
    ("[faults]\nelectrode_open = [3]\n", "cs_glitch", "[faults] / [sensor.faults] electrode_open"),
    ("", "cs_glitch", "scene.duration_s = 31: a campaign case streams at most 30 s"),
    ("[host]\nspi = \"rtl\"\n", "cs_glitch", "host.spi = 'rtl': the campaign runs over --spi software"),
    ("[host]\nsequence = [\"PAC\", \"PDC\"]\n", "cs_glitch", "host.sequence:"),
    ("[host]\nslot_rate_Hz = 2200\n", "cs_glitch", "host.slot_rate_Hz = 2200"),
    ("[[stimulus]]\nkind = \"tap\"\nat_s = 0.1\npeak_N = 0.5\n", "none",
     f"(Tap at 0.1 s) comes before {quiet_start_s('none'):g} s: fault none"),
    ("[[stimulus]]\nkind = \"tap\"\nat_s = 0.15\npeak_N = 0.5\n", "fluid_leak",
     f"(Tap at 0.15 s) comes before {quiet_start_s('fluid_leak'):g} s: fault fluid_leak"),
    ("[[stimulus]]\nkind = \"ambient_step\"\nat_s = 0.5\ntemperature_C = 30\n", "fluid_leak",
     "AmbientStep change the sensor for good"),
    ("", "fluid_leak", "[sensor] unit / parameters: fault fluid_leak"),
]


@pytest.mark.parametrize("extra, faults, field", REFUSED, ids=[r[2][:24] for r in REFUSED])
def test_what_the_campaign_cannot_honour_is_refused_naming_the_file_and_the_field(tmp_path, extra, faults, field):
    text = GRIP + extra
    if "duration_s = 31" in field:
        text = text.replace("duration_s = 1.0", "duration_s = 31.0")
    path = _scene(tmp_path, text)
    with pytest.raises(SceneRefused) as e:
        campaign_scene(str(path), faults.split(","), "software")
    assert str(e.value).startswith(f"--scenes {path}: the campaign cannot run it: ") and "\n" not in str(e.value)
    assert field in str(e.value)


def test_a_fault_that_needs_no_rest_takes_an_early_stimulus(tmp_path):
    early = NOMINAL_GRIP.replace("start_s = 0.3", "start_s = 0.05")
    assert campaign_scene(str(_scene(tmp_path, early)), ["cs_glitch", "serial_loss"], "software").label == "grip.toml"


def test_a_bad_scene_file_stops_the_campaign_in_one_line_before_anything_runs_and_its_report_says_why(tmp_path,
                                                                                                   capsys):
    bad = _scene(tmp_path, GRIP + "[faults]\nelectrode_open = [3]\n", "bad.toml")
    report = tmp_path / "c.xml"
    assert cli.main(["campaign", "--faults", "none", "--scenes", f"rest,{bad}", "--junit", str(report),
                     "--quiet"]) == 2
    captured = capsys.readouterr()
    errors = [line for line in captured.err.splitlines() if line.startswith("error:")]
    assert errors == [f"error: --scenes {bad}: the campaign cannot run it: [faults] / [sensor.faults] electrode_open: "
                      "the campaign injects its own faults and checks what each does alone; leave the scene's out"]
    assert captured.out == ""  # no case ran: no summary
    error = ET.parse(report).getroot().find("testcase/error")
    assert error.get("type") == "unfinished" and f"the campaign could not run: --scenes {bad}:" in error.get("message")


@pytest.mark.parametrize("scenes, said", [
    ("taps,{d}/grip.toml,{d}/sub/grip.toml", "both name their cases grip.toml[seed=K]"),
    ("{d}/nothere.toml", "nothere.toml: cannot read the file: No such file or directory"),
    ("{d}/broken.toml", "broken.toml: "),
    ("{d}/sub/", "sub/: cannot read the file: Is a directory"),  # (a CI step's variable left empty: "ci/$SCENE")
    ("{d}/empty.toml", "empty.toml: the file is empty"),
    ("{d}/binary.toml", "binary.toml: the file holds a NUL byte at line 1, column 1: not a text file"),
])
def test_scene_files_that_cannot_be_read_or_share_a_case_name_are_refused(tmp_path, capsys, scenes, said):
    _scene(tmp_path, NOMINAL_GRIP)
    (tmp_path / "sub").mkdir()
    _scene(tmp_path / "sub", NOMINAL_GRIP)
    _scene(tmp_path, "[scene]\nname = 'broken'\nduration_s = -1\n", "broken.toml")
    _scene(tmp_path, "", "empty.toml")
    (tmp_path / "binary.toml").write_bytes(b"\x00\x01\xff")
    assert cli.main(["campaign", "--scenes", scenes.format(d=tmp_path), "--junit", str(tmp_path / "c.xml"),
                     "--quiet"]) == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and said in errors[0], errors


def test_a_bare_shipped_scene_name_is_refused_with_how_to_give_it(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["campaign", "--scenes", "press_hold"])
    err = capsys.readouterr().err
    assert e.value.code == 2
    assert "unknown press_hold" in err and "press_hold.toml" in err and len(err.strip().splitlines()) == 1


def test_every_example_in_the_campaign_help_parses():
    examples = [line.split("#")[0].split()[1:] for line in CAMPAIGN_HELP.splitlines()
                if line.strip().startswith("biotac-bench campaign")]
    assert len(examples) >= 7 and any(".toml" in " ".join(e) for e in examples)
    parser = cli.build_parser()
    for argv in examples:
        assert parser.parse_args(argv).command == "campaign"
