"""README statements the earlier audits left unguarded (third README audit): the noise budget as printed, the
shipped scenes and what each one does, the hostile corpus's size, the pytest plugin's keyword table, and the fidelity
profiles as a sensor runs them."""

import re
import tomllib

import pytest

from bench.cli import main as cli
from bench.paths import FIXTURES, REPO
from bench.scenes.scene import load_scene

pytestmark = pytest.mark.unit
README = (REPO / "README.md").read_text(encoding="utf-8")
SCENES = FIXTURES / "scenes"


# --- Noise budget (`biotac-bench noise-budget`) -----------------------------------------------------------------

def _readme_budget() -> list[str]:
    """The README's printed budget, its one `E1..E19` row (README: "the command prints all 19") expanded."""
    block = re.search(r"```\n(unit nominal .*?\nPAC noise budget .*?)\n```", README, flags=re.S).group(1).splitlines()
    out = []
    for line in block:
        if line.startswith("E1..E19 "):
            out += [f"{f'E{n}':<8s}{line[len('E1..E19 '):]}" for n in range(1, 20)]
        else:
            out.append(line)
    return out


def test_the_readmes_noise_budget_is_what_the_command_prints(capsys):
    """README, Noise budget: every figure and note of the printed budget is the command's own output, line for
    line (PAC sources in µV RTI / Pa / bits, each quiet channel's LSB RMS), the electrodes one row each."""
    assert cli.main(["noise-budget"]) == 0
    printed = capsys.readouterr().out.rstrip("\n").splitlines()
    assert printed == _readme_budget()
    assert [line.split()[0] for line in printed if re.match(r"E\d", line)] == [f"E{n}" for n in range(1, 20)]


# --- Scenes: the shipped ones -----------------------------------------------------------------------------------

def _scene(name: str) -> dict:
    return tomllib.loads((SCENES / f"{name}.toml").read_text(encoding="utf-8"))


def _stimuli(name: str, kind: str) -> list[dict]:
    return [s for s in _scene(name).get("stimulus", []) if s["kind"] == kind]


def test_the_readmes_shipped_scenes_are_the_shipped_scenes(capsys):
    """README, Scenes: "Shipped: `rest`, `taps`, …" names every scene `biotac-bench scenes` lists, and no other."""
    shipped = re.search(r"^Shipped: (.*?)`biotac-bench run --help`", README, flags=re.S | re.M).group(1)
    named = set(re.findall(r"`(\w+)`", shipped))
    assert cli.main(["scenes"]) == 0
    listed = {line.split()[0] for line in capsys.readouterr().out.splitlines() if not line.startswith(" ")}
    assert named == listed == {p.stem for p in SCENES.glob("*.toml")}


def test_each_shipped_scene_does_what_the_readme_says():
    """README, Scenes: the parenthesis after each shipped scene's name, checked against the scene file."""
    sweep, = _stimuli("vibration_sweep", "vibration")  # 10–900 Hz at 1 µm
    assert (sweep["f_start_Hz"], sweep["f_stop_Hz"], sweep["amplitude_um"]) == (10.0, 900.0, 1.0)
    presses = _stimuli("presses_grid", "touch")  # 1 N presses on 12 places
    assert len(presses) == 12 and {p["force_N"] for p in presses} == {1.0}
    assert len({(p["x_mm"], p["angle_deg"]) for p in presses}) == 12
    ramp, = _stimuli("grasp_ramp", "touch")  # to 5 N with shear
    assert ramp["force_N"] == 5.0 and ramp["tangential_N"] > 0
    assert [t["material"] for t in _stimuli("thermal_contacts", "touch")] == ["aluminum", "glass", "wood",
                                                                              "polystyrene foam"]
    assert len(_stimuli("power_on", "power_on")) == 1  # warm-up
    step, = _stimuli("ambient_step", "ambient_step")  # room 25 → 15 °C
    assert step["temperature_C"] == 15.0
    assert load_scene(SCENES / "ambient_step.toml").params.ambient_temperature_C == 25.0
    leak = _scene("fluid_leak")  # a 1 mL/min leak from 2 s; the same 1 N press each time
    assert (leak["faults"]["fluid_leak_mL_per_min"], leak["faults"]["fluid_leak_start_s"]) == (1.0, 2.0)
    press, = _stimuli("fluid_leak", "press")
    assert press["force_N"] == 1.0 and len(press["start_s"]) == 3 and min(press["start_s"]) < 2.0
    for name, ridges in (("sandpaper_fingerprints", True), ("sandpaper_smooth", False)):  # 60 grit, 0.5 N, 1 cm/s
        slide, = _stimuli(name, "slide")
        assert (slide["texture"], slide["force_N"], slide["velocity_mm_per_s"]) == ("60-grit sandpaper", 0.5, 10)
        assert _scene(name)["skin"]["fingerprints"] is ridges
    from bench.rigs.texture_rig import movement_grid

    sweep = _stimuli("movement_sweep", "slide")  # the 36 movements of D eqs 6.20–6.21 on linen paper
    assert {s["texture"] for s in sweep} == {2}
    given = [x for s in sweep for x in (s["force_N"], s["velocity_mm_per_s"])]
    assert given == pytest.approx([x for m in movement_grid() for x in (m.force_N, 1e3 * m.velocity_m_per_s)], abs=1e-3)
    first, fresh, second = _scene("skin_wear")["stimulus"]  # 20 high-power slides, a fresh skin, 3 more
    assert (len(first["start_s"]), fresh["kind"], len(second["start_s"])) == (20, "replace_skin", 3)
    from bench.experiments.exploration import movement_grid as grid

    g = grid()  # high power: D's grid movement the pilot leaves out for its wear (1.26 N at 6.31 cm/s, level 10)
    high = [(f, 1e3 * v) for f, v, h in zip(g["force_N"], g["velocity_m_s"], g["high_power"]) if h]
    assert all(s["force_N"] == first["force_N"] and s["velocity_mm_per_s"] == first["velocity_mm_per_s"]
               for s in (first, second))
    assert any(first["force_N"] == pytest.approx(f, abs=0.01)
               and first["velocity_mm_per_s"] == pytest.approx(v, abs=0.1) for f, v in high)


def test_the_readme_counts_the_hostile_corpus_as_it_is():
    """README, Scenes: "The corpus in `fixtures/hostile/` (N scene files in M cases, K command lines)": the files in
    `scenes/`, the entries of `scenes.json` (a few are paths that are not files) and those of `cli.json`."""
    import json

    files, cases, lines = map(int, re.search(r"`fixtures/hostile/` \((\d+) scene files in (\d+) cases, (\d+) command "
                                              r"lines\)", README).groups())
    hostile = FIXTURES / "hostile"
    assert files == sum(1 for p in (hostile / "scenes").iterdir() if p.is_file())
    assert cases == len(json.loads((hostile / "scenes.json").read_text(encoding="utf-8"))["scenes"])
    assert lines == len(json.loads((hostile / "cli.json").read_text(encoding="utf-8"))["invocations"])


# --- Firmware and host stacks: the pytest plugin's keywords -------------------------------------------------------

def _readme_keyword_table() -> dict[str, set[str]]:
    """The README's fixture table: {row name: the keywords (backticked) it lists}."""
    table = re.search(r"^\s*\| fixture \| keywords \|\n(.*?)\n\n", README, flags=re.S | re.M).group(1)
    rows = {}
    for line in table.splitlines()[1:]:  # past the |---| rule
        name, words = line.strip().strip("|").split("|")
        rows[name.strip()] = set(re.findall(r"`(\w+)`", words))
    return rows


def _takes(factory) -> set[str]:
    """The keywords a factory fixture takes, as its refusal of an unknown one lists them."""
    with pytest.raises(pytest.fail.Exception) as e:
        factory(no_such_keyword=1)
    return set(str(e.value).split("; it takes ")[1].split(", "))


def test_the_plugins_fixtures_take_the_keywords_the_readme_lists(biotac_sensor, biotac_bridge, biotac_cheetah):
    """README, pytest plugin: the table of each factory's keywords is what each one takes — no more, no fewer."""
    rows = _readme_keyword_table()
    every, shared = rows["all three"], rows["`biotac_bridge`, `biotac_cheetah`"]
    assert _takes(biotac_sensor) == every | rows["`biotac_sensor`"]
    assert _takes(biotac_bridge) == every | shared | rows["`biotac_bridge` only"]
    assert _takes(biotac_cheetah) == every | shared | rows["`biotac_cheetah` only"]


def test_biotac_sensor_hands_its_sensor_options_to_the_sensor(biotac_sensor):
    """README: the sensor options `block_s` (s) and `record_signals` reach the emulated sensor."""
    sensor = biotac_sensor(block_s=0.5, record_signals=("normal_force_N",)).sensor
    assert sensor.block_n == round(0.5 * sensor.fs) and sensor.record_signals == ("normal_force_N",)


# --- What accuracy costs in time: the profiles ------------------------------------------------------------------

@pytest.mark.parametrize("name, grid_Hz, discretization, electrodes_Hz, second_order", [
    ("fast", 4400.0, "bilinear", 250.0, False),
    ("default", 8800.0, "prewarped", 500.0, False),
    ("reference", 70400.0, "prewarped", 2000.0, True)])
def test_each_profile_runs_the_grid_and_effects_the_readme_gives(name, grid_Hz, discretization, electrodes_Hz,
                                                                 second_order):
    """README: `fast` (4.4 kHz grid, plain bilinear, electrodes at 250 Hz), `default` (8.8 kHz, every corner
    prewarped, electrodes at 500 Hz), `reference` (70.4 kHz, prewarped, electrodes at 2 kHz, plus the duct resonance
    and second-stage noise) — as a sensor built on each profile runs them."""
    from emulator.sensor import Sensor
    from emulator.transducer import Bridge

    sensor = Sensor(channels_read=["PAC", "E1"], fidelity=name)
    bridge, = [e for e in sensor.graph.effects if isinstance(e, Bridge)]
    assert (sensor.fs, sensor.fidelity.discretization, sensor.electrodes.rate_Hz) == (grid_Hz, discretization,
                                                                                      electrodes_Hz)
    assert (bridge.duct is not None, "stage2_noise" in {e.name for e in sensor.graph.effects}) == (second_order,) * 2

