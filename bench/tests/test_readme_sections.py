"""README statements of the sections the earlier audits left unguarded (third README audit): the noise budget as
printed, the shipped scenes and what each one does, the chunk a signal stops a run at, and the 600 simulated s up
to which a run keeps its samples in memory and writes its exports."""

import math
import re
import tomllib

import pytest

from bench.cli import main as cli
from bench.paths import FIXTURES, REPO
from bench.reporting.session import run_to_folder
from bench.running.runner import run_scene
from bench.scenes.scene import load_scene, parse_scene
from bench.tests.test_run_review import _signal_at_first_chunk

pytestmark = pytest.mark.unit
README = (REPO / "README.md").read_text(encoding="utf-8")
SCENES = FIXTURES / "scenes"


# --- Noise budget (`biotac-bench noise-budget`) -----------------------------------------------------------------

def _readme_budget() -> list[str]:
    """The README's printed budget, its one `E1..E19` row (README: "the command prints all 19") expanded."""
    block = re.search(r"```\n(PAC noise budget .*?)\n```", README, flags=re.S).group(1).splitlines()
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


def test_the_adc_input_noise_is_enob_11_1_less_quantization():
    """README: the ADC's 0.45 LSB is a 12-bit ENOB of 11.1 less quantization: 2^(12 − 11.1)/√12 LSB in
    quadrature minus 1/√12 LSB (0.455 LSB; the budget's reference share takes it to 0.45)."""
    from emulator.params import SensorParams

    total = 2 ** (12 - 11.1) / math.sqrt(12)
    assert SensorParams().adc_noise_rms_bits == pytest.approx(math.sqrt(total**2 - 1 / 12), abs=0.01)


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


def test_the_three_fingers_scene_is_the_readmes_grasp():
    """README, Several fingers: thumb (unit 17) at 0.5 s with 2 N, index (unit 18) at 0.9 s with 1.2 N, the middle
    finger lands at 1.3 s (0.8 N) and slips 8 mm over acrylic."""
    from bench.textures.library import texture

    grasp = _scene("grasp_three_fingers")
    assert grasp["sensor"]["unit"] == 17 and [(s["index"], s["unit"]) for s in grasp["sensors"]][0] == (2, 18)
    thumb, index = _stimuli("grasp_three_fingers", "touch")
    assert (thumb["sensor"], thumb["start_s"], thumb["force_N"]) == (1, 0.5, 2.0)
    assert (index["sensor"], index["start_s"], index["force_N"]) == (2, 0.9, 1.2)
    assert {thumb["material"], index["material"]} == {"acrylic"}
    middle, = _stimuli("grasp_three_fingers", "slide")
    assert middle["sensor"] == 3 and middle["start_s"] + middle["approach_s"] == pytest.approx(1.3)
    assert (middle["force_N"], middle["distance_mm"]) == (0.8, 8.0)
    assert texture(middle["texture"]).material == "acrylic"


# --- What a run writes: the chunk a signal stops at, and the 600 s ------------------------------------------------

def test_a_signal_stops_the_run_at_the_next_4_simulated_s(tmp_path, monkeypatch):
    """README, Interruption: Ctrl-C stops the run at the next chunk (4 simulated s) — a run into a folder, as
    `biotac-bench run` makes it, with its default chunk."""
    _signal_at_first_chunk(monkeypatch)
    sc = parse_scene({"scene": {"name": "w", "duration_s": 10.0}, "host": {"sequence": ["PDC"]}})
    res = run_to_folder(sc, tmp_path / "o", plots=False, progress=False)
    assert (res.exit_code, res.record["status"], res.record["simulated_s"]) == (130, "interrupted", 4.0)


def _long(duration_s: float):
    """A quiet scene of ``duration_s`` simulated s, cheap to run (PDC at 100 Hz, the fast profile)."""
    return parse_scene({"scene": {"name": "long", "duration_s": duration_s, "fidelity": "fast"},
                        "host": {"sequence": ["PDC"], "slot_rate_Hz": 100.0}})


@pytest.mark.parametrize("duration_s, kept", [(600.0, True), (600.5, False)])
def test_run_scene_keeps_every_sample_for_scenes_up_to_600_s(duration_s, kept):
    """README: `run_scene(scene)` keeps every sample in `Recording.channels` for scenes up to 600 s; longer ones
    keep the summary only."""
    rec = run_scene(_long(duration_s), progress=False, chunk_s=100.0)
    assert rec.simulated_s == duration_s
    assert (len(rec.channels["PDC"].codes) if kept else len(rec.channels)) == (60000 if kept else 0)  # 100 Hz × 600 s


@pytest.mark.parametrize("duration_s, exported", [(600.0, True), (600.5, False)])
def test_exports_are_written_for_runs_up_to_600_s(tmp_path, duration_s, exported):
    """README: the exports (codes.npz, samples.csv) are written for runs up to 600 simulated s; a longer run keeps
    only samples.h5 and says so in report.md and record.json (`skipped_outputs`)."""
    res = run_to_folder(_long(duration_s), tmp_path / "o", csv=True, plots=False, progress=False)
    assert res.exit_code == 0
    exports = {"codes.npz", "samples.csv"}
    written = {p.name for p in (tmp_path / "o").iterdir()}
    assert (exports <= written) is exported and (exports & written == set()) is not exported
    assert "samples.h5" in written
    skipped = res.record.get("skipped_outputs", {})
    assert set(skipped) == (set() if exported else exports)
    report = (tmp_path / "o" / "report.md").read_text()
    assert all(("600 simulated s" in skipped[n] and f"`{n}` not written" in report) for n in skipped)


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


def test_the_reference_profile_slides_at_the_readmes_resolution():
    """README: reference's sliding is 2.5 µm textures, 16 patch radii, friction ×4, ridge-resolved fingerprints."""
    from emulator.fidelity import profile

    ref = profile("reference")
    assert (ref.sliding_dx_m, ref.patch_radii, ref.friction_substeps, ref.ridges) == (2.5e-6, 16, 4, "resolved")
