"""Property-based: scenes drawn over the scene validator's whole ranges run through the public API
(:func:`bench.scenes.scene.parse_scene` → :func:`bench.running.runner.run_scene`) and, whatever they hold, every run

* ends ``ok`` (a NaN or Inf reaching the ADC raises, naming the node, and fails the run), with every sample's
  status ok and every code within 0..4095;
* gives the same codes for blocks of 4410, 441 and — for scenes of at most 2640 grid samples — 1 sample: physics
  blocks of that many grid samples (``run_scene(block_s=...)``) read by the host that many slots at a time
  (``chunk_s``);
* gives the same codes for the same seed twice, and other noise for another seed.

Drawn: taps and presses (0 to 50 N, 1 ms to 10 s, placed or not), every sphere of D Table 5-2 from 1 mm to 10 m,
vibration tones and sweeps and pressure calibrations over every allowed frequency and amplitude, thermal contacts
at the object and room temperature extremes with power-on and heater failure, two to five fingers on one bus
(random units, either variant, sensor faults), and slides over the whole texture library on skins from new to worn
flat.  Every scene also draws sensor 1's unit (nominal or a random seed) and variant.  The examples are
derandomized (the same every run) so that a failure is reproducible; the whole module takes about 30 s on one
core.  Last, every ranged field the validator knows, set just outside its range, is refused with the file, the
field, the value and the range, and nothing else.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from bench import tomlfile
from bench.errors import SceneError
from bench.running.runner import run_scene
from bench.scenes.scene import _STIMULUS_FIELDS, MAX_DURATION_S, load_scene, parse_scene
from bench.textures.library import load_library
from bench.textures.properties import BACKGROUND_GUARD_S, MEASURE_LEAD, MEASURE_TAIL
from emulator.channels import VARIANTS, variant
from emulator.electrodes import CORE_RADIUS_MM, SKIN_BASE_X_MM
from emulator.fidelity import PROFILES
from emulator.params import PARAMETER_FIELDS, SensorParams
from emulator.sliding import SlidingContact
from emulator.stimuli import PLACED_CONTACT_MIN_STEPS, SPHERES, TOUCH_STATIC_FRICTION
from emulator.thermal import MATERIALS
from emulator.units import MAX_UNIT_SEED

#: an overflow or an invalid operation anywhere on the way (numpy's RuntimeWarning) fails the test: a NaN or Inf must
#: not even arise inside the model, let alone reach an ADC
pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

#: grid samples per physics block; the last only for scenes of at most :data:`ONE_SAMPLE_MAX` grid samples
BLOCKS = (4410, 441, 1)
ONE_SAMPLE_MAX = 2640
#: a channel read at least this often is compared between seeds (with ~0.5 LSB of noise per conversion, two seeds
#: giving 50 equal codes is a chance below 1e-10)
NOISE_SAMPLES = 50
#: the profiles drawn (the reference profile costs ~10× more per simulated second: its own tests cover it)
DRAWN_PROFILES = ("fast", "default")
#: each example runs its scene five times or more: a failing one is reported as drawn, not shrunk (shrinking one took
#: five minutes)
RUN = settings(max_examples=6, deadline=None, derandomize=True, phases=(Phase.explicit, Phase.generate),
               report_multiple_bugs=False, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def _codes(scene, block_n: int) -> dict:
    """Every sensor's codes by (sensor, channel) from ``run_scene`` in physics blocks of ``block_n`` grid samples
    and host reads of ``block_n`` slots (the electrodes and the thermal network compute as far as the host has
    read), after checking the run ended ok with every sample's status ok and every code within 0..4095."""
    rec = run_scene(scene, progress=False, block_s=block_n / PROFILES[scene.fidelity].grid_Hz,
                    chunk_s=block_n / scene.slot_rate_Hz)
    assert rec.status == "ok", rec.error
    out = {}
    for k, r in [(1, rec), *sorted(rec.sensors.items())]:
        assert r.status == "ok", (k, r.error)
        for name, ch in r.channels.items():
            assert ch.codes.size > 0 and ch.codes.dtype == np.uint16, (k, name)
            assert np.all(ch.status == 0), (k, name, np.unique(ch.status))
            assert ch.codes.max() <= 4095, (k, name)
            out[k, name] = ch.codes
    return out


def _holds_the_properties(data: dict) -> None:
    """Parse ``data`` (a scene as its TOML's tables) and check every property of the module's docstring."""
    scene = parse_scene(data, source="<drawn scene>")
    grid_samples = scene.duration_s * PROFILES[scene.fidelity].grid_Hz
    blocks = [n for n in BLOCKS if n > 1 or grid_samples <= ONE_SAMPLE_MAX]
    first = _codes(scene, blocks[0])
    for n in blocks[1:]:
        got = _codes(scene, n)
        for key, codes in first.items():
            assert np.array_equal(got[key], codes), f"{key}: blocks of {n} grid samples differ from {blocks[0]}"
    again = _codes(scene, blocks[0])
    for key, codes in first.items():
        assert np.array_equal(again[key], codes), f"{key}: the same seed gave other codes"
    other = _codes(parse_scene({**data, "scene": {**data["scene"], "seed": (scene.seed + 1) % 2**63}}), blocks[0])
    for key, codes in first.items():
        railed = all(np.all((c == 0) | (c == 4095)) for c in (codes, other[key]))
        if codes.size >= NOISE_SAMPLES and not railed:
            assert not np.array_equal(other[key], codes), f"{key}: another seed gave the same noise"


@pytest.mark.unit
@pytest.mark.parametrize("block_s", [2.0, 0.5, 1 / 8800])
def test_run_scene_computes_every_sensors_physics_in_the_blocks_it_is_given(block_s):
    """``run_scene(block_s=...)`` reaches every sensor of the scene: each computes its grid in blocks of that many
    seconds (a 0.1 s scene costs its effects one whole block of 2 s or 0.5 s, and only its own 0.1 s in blocks of one
    grid sample), and refuses a block that is not a finite positive duration, by name."""
    scene = parse_scene({"scene": {"name": "blocks", "duration_s": 0.1}, "sensors": [{"index": 2}]})
    rec = run_scene(scene, progress=False, block_s=block_s)
    grid_Hz = PROFILES[scene.fidelity].grid_Hz
    computed = max(block_s, scene.duration_s) * grid_Hz
    for k, r in ((1, rec), (2, rec.sensors[2])):
        assert r.status == "ok", r.error
        samples = {e["name"]: e["samples"] for e in r.effects if e["samples"]}
        assert samples and all(abs(n - computed) <= 1 for n in samples.values()), (k, samples)
    refused = run_scene(scene, progress=False, block_s=0.0)
    assert refused.status == "failed" and "block_s = 0.0: must be a finite number > 0" in refused.error


# --- what a scene is drawn from -----------------------------------------------------------------------------------


def _log_uniform(lo: float, hi: float):
    """Values from ``lo`` to ``hi`` spread evenly in their logarithm (both ends drawn now and then)."""
    return st.one_of(st.sampled_from([lo, hi]), st.floats(math.log(lo), math.log(hi)).map(
        lambda x: min(max(math.exp(x), lo), hi)))


@st.composite
def _unit(draw):
    """A sensor unit: nominal, or a random unit's seed (manufacturing spreads drawn from it)."""
    return draw(st.one_of(st.just("nominal"), st.integers(0, MAX_UNIT_SEED)))


@st.composite
def _scene(draw, duration_s: float, stimuli: list, fidelity: str | None = None, **tables) -> dict:
    """A scene's tables: [scene] with a drawn seed and profile (``fidelity`` if given), [sensor] with a drawn
    unit and variant (unless ``tables`` gives one), the ``stimuli`` and any other ``tables``."""
    sensor = tables.pop("sensor", None) or {"unit": draw(_unit()), "variant": draw(st.sampled_from(VARIANTS))}
    return {"scene": {"name": "drawn", "duration_s": round(duration_s, 6), "seed": draw(st.integers(0, 2**63 - 1)),
                      "fidelity": fidelity or draw(st.sampled_from(DRAWN_PROFILES))},
            "sensor": sensor, "stimulus": stimuli, **tables}


@st.composite
def _place(draw, variant_name: str) -> dict:
    """Where a contact is: an electrode of the variant, or x_mm + angle_deg on the skin free to move (the nail's
    skin is tethered: refused), with an indenter of any radius the validator allows."""
    half = SensorParams().free_skin_half_angle_deg
    if draw(st.booleans()):
        where = {"electrode": f"E{draw(st.integers(1, variant(variant_name).n_electrodes))}"}
    else:
        where = {"x_mm": draw(st.floats(SKIN_BASE_X_MM, CORE_RADIUS_MM)), "angle_deg": draw(st.floats(-half, half))}
    return {**where, "indenter_radius_mm": draw(st.floats(0.1, 15.0))}


def _shortest_placed_s(fidelity: str) -> float:
    """The shortest placed contact (start to end, s) the validator allows at ``fidelity``: two steps of the
    electrodes' model."""
    return PLACED_CONTACT_MIN_STEPS / PROFILES[fidelity].electrode_rate_Hz


@st.composite
def _taps_and_presses(draw) -> dict:
    """One to three taps or presses of 0 to 50 N, from 1 ms to 10 s (a press: 1 ms to 5 s ramps, 0 to 5 s hold),
    placed on the finger or not, one after another."""
    fidelity = draw(st.sampled_from(DRAWN_PROFILES))
    unit, var = draw(_unit()), draw(st.sampled_from(VARIANTS))
    shortest_placed_s = _shortest_placed_s(fidelity)
    t, stimuli = 0.01, []
    for _ in range(draw(st.integers(1, 3))):
        place = draw(st.one_of(st.just({}), _place(var)))
        shortest = shortest_placed_s if place else 1e-3
        if draw(st.booleans()):
            duration = draw(st.one_of(_log_uniform(shortest, 0.05), _log_uniform(shortest, 10.0)))
            stimuli.append({"kind": "tap", "at_s": t, "peak_N": draw(st.floats(0.0, 50.0)), "duration_s": duration,
                            **place})
        else:
            ramp = draw(_log_uniform(max(shortest / 2, 1e-3), 5.0))
            hold = draw(st.one_of(st.just(0.0), _log_uniform(1e-3, 5.0)))
            stimuli.append({"kind": "press", "start_s": t, "force_N": draw(st.floats(0.0, 50.0)), "ramp_s": ramp,
                            "hold_s": hold, **place})
            duration = 2 * ramp + hold
        t += duration + draw(st.floats(0.0, 0.05))
    return draw(_scene(t + 0.02, stimuli, fidelity, sensor={"unit": unit, "variant": var}))


@st.composite
def _sphere_drops(draw) -> dict:
    """Every sphere of D Table 5-2 dropped once, each from its own height (1 mm to 10 m, the validator's range),
    20 ms apart, in a drawn order."""
    names = draw(st.permutations(sorted(SPHERES)))
    stimuli = [{"kind": "sphere_drop", "at_s": 0.01 + 0.02 * i, "sphere": name,
                "height_m": draw(st.one_of(st.sampled_from([1e-3, 10.0]), st.floats(1e-3, 10.0)))}
               for i, name in enumerate(names)]
    return draw(_scene(0.01 + 0.02 * len(names) + 0.05, stimuli))


def _top_Hz(fidelity: str) -> float:
    """The highest frequency a scene at ``fidelity`` may vibrate at (Hz): 3000 Hz, below 0.45 × its grid."""
    return min(3000.0, math.nextafter(0.45 * PROFILES[fidelity].grid_Hz, 0.0))


@st.composite
def _vibrations(draw) -> dict:
    """A tone or a log sweep (either way) of 0 to 1000 µm anywhere from 1 Hz to the top the profile computes, then
    a pressure calibration (-100 to 200 kPa offset, 0 to 100 kPa sinusoid at any allowed frequency)."""
    fidelity = draw(st.sampled_from(DRAWN_PROFILES))
    frequency = st.one_of(st.sampled_from([1.0, _top_Hz(fidelity)]), st.floats(1.0, _top_Hz(fidelity)))
    duration = draw(_log_uniform(1e-3, 0.3))
    vibration = {"kind": "vibration", "start_s": 0.01, "duration_s": duration,
                 "amplitude_um": draw(st.one_of(st.sampled_from([0.0, 1000.0]), _log_uniform(1e-6, 1000.0))),
                 "fade_s": draw(st.floats(0.0, duration / 2))}
    if draw(st.booleans()):
        vibration["frequency_Hz"] = draw(frequency)
    else:
        vibration["f_start_Hz"], vibration["f_stop_Hz"] = draw(frequency), draw(frequency)
    t = 0.02 + duration
    pressure_s = draw(_log_uniform(1e-3, 0.2))
    amplitude = draw(st.one_of(st.sampled_from([0.0, 1e5]), st.floats(0.0, 1e5)))
    pressure = {"kind": "pressure", "start_s": t, "duration_s": pressure_s,
                "offset_kPa": draw(st.floats(-100.0, 200.0)), "amplitude_Pa": amplitude,
                "frequency_Hz": draw(frequency) if amplitude > 0 else 0.0,
                "fade_s": draw(st.floats(0.0, pressure_s / 2))}
    return draw(_scene(t + pressure_s + 0.02, [vibration, pressure], fidelity))


@st.composite
def _thermal_contacts(draw) -> dict:
    """Power-on, a room temperature step (-20 to 60 °C), a touch of any material at -40 to 120 °C (or the room's)
    with a shear up to the static friction, and perhaps the heaters failing during it."""
    var, fidelity = draw(st.sampled_from(VARIANTS)), draw(st.sampled_from(DRAWN_PROFILES))
    force = draw(st.floats(0.0, 50.0))
    most = min(20.0, TOUCH_STATIC_FRICTION * force)
    ramp = draw(_log_uniform(max(_shortest_placed_s(fidelity) / 2, 1e-3), 0.05))
    touch = {"kind": "touch", "start_s": 0.02, "force_N": force, "ramp_s": ramp,
             "hold_s": draw(st.floats(0.0, 0.15)), **draw(_place(var)),
             "tangential_N": draw(st.floats(-most, most)), "shear_angle_deg": draw(st.floats(-180.0, 180.0)),
             "material": draw(st.sampled_from(sorted(MATERIALS)))}
    if draw(st.booleans()):
        touch["object_temperature_C"] = draw(st.one_of(st.sampled_from([-40.0, 120.0]), st.floats(-40.0, 120.0)))
    stimuli = [touch, {"kind": "ambient_step", "at_s": draw(st.floats(0.0, 0.2)),
                       "temperature_C": draw(st.one_of(st.sampled_from([-20.0, 60.0]), st.floats(-20.0, 60.0)))}]
    if draw(st.booleans()):
        stimuli.append({"kind": "power_on", "at_s": 0.0})
    if draw(st.booleans()):
        stimuli.append({"kind": "heater_failure", "at_s": draw(st.floats(0.0, 0.25))})
    return draw(_scene(0.3, stimuli, fidelity, sensor={"unit": draw(_unit()), "variant": var}))


@st.composite
def _faults(draw, n_electrodes: int) -> dict:
    """Sensor faults: open and shorted electrodes (never both), the multiplexer stuck, the thermistor open or
    shorted, the heaters dead, a fluid leak of up to 60 mL/min — each drawn or not."""
    electrodes = draw(st.lists(st.integers(1, n_electrodes), unique=True, max_size=4))
    cut = draw(st.integers(0, len(electrodes)))
    faults = {"electrode_open": electrodes[:cut], "electrode_short": electrodes[cut:]}
    if draw(st.booleans()):
        faults["mux_stuck"] = draw(st.integers(1, n_electrodes))
    if draw(st.booleans()):
        faults["thermistor"] = draw(st.sampled_from(["open", "short"]))
    faults["heater_failed"] = draw(st.booleans())
    if draw(st.booleans()):
        faults["fluid_leak_mL_per_min"] = draw(st.floats(0.0, 60.0))
        faults["fluid_leak_start_s"] = draw(st.floats(0.0, 0.2))
    return {k: v for k, v in faults.items() if v != []}


@st.composite
def _fingers(draw) -> dict:
    """Two to five fingers on one bus, each its own random unit and variant with its own faults, each tapped,
    touched or hit by a sphere at its own time (a finger may also feel nothing)."""
    n = draw(st.integers(2, 5))
    units = draw(st.lists(st.integers(0, MAX_UNIT_SEED), min_size=n, max_size=n, unique=True))
    variants = [draw(st.sampled_from(VARIANTS)) for _ in range(n)]
    tables = [{"unit": units[k], "variant": variants[k],
               "faults": draw(_faults(variant(variants[k]).n_electrodes))} for k in range(n)]
    stimuli = []
    for k in range(1, n + 1):
        kind = draw(st.sampled_from(["tap", "touch", "sphere_drop", None]))
        at = draw(st.floats(0.0, 0.1))
        if kind == "tap":
            stimuli.append({"kind": "tap", "sensor": k, "at_s": at, "peak_N": draw(st.floats(0.0, 50.0)),
                            "duration_s": draw(_log_uniform(1e-3, 0.1))})
        elif kind == "touch":
            stimuli.append({"kind": "touch", "sensor": k, "start_s": at, "force_N": draw(st.floats(0.0, 50.0)),
                            "ramp_s": 0.02, "hold_s": 0.05, **draw(_place(variants[k - 1]))})
        elif kind == "sphere_drop":
            stimuli.append({"kind": "sphere_drop", "sensor": k, "at_s": at, "sphere": draw(st.sampled_from(
                sorted(SPHERES))), "height_m": draw(st.floats(1e-3, 10.0))})
    return draw(_scene(0.25, stimuli, sensor=tables[0],
                       sensors=[{"index": k + 1, **tables[k]} for k in range(1, n)]))


#: the textures a slide may name: the whole shipped library (and its test surfaces), by number
TEXTURES = sorted(load_library())


@st.composite
def _slides(draw) -> dict:
    """Two or three trials over one drawn texture (any force, speed and stroke the validator allows that slide
    0.05–0.25 s) on a skin from new to worn flat, with a wear coefficient up to 1 (a trial can wear it to 0)."""
    measured = 1.0 - MEASURE_LEAD - MEASURE_TAIL
    shortest_s = 2.0 / SlidingContact.LOG_RATE_HZ / measured  # the properties' shortest slide, as validated
    velocity = draw(_log_uniform(0.1, 500.0))
    accel = draw(_log_uniform(1e-3, 0.02))
    slide_s = draw(st.floats(max(shortest_s, 2 * accel) * 1.01, 0.25))  # the stroke holds the ramps at least
    distance = max(0.1, velocity * (slide_s - accel))
    hold = draw(st.floats(2 * BACKGROUND_GUARD_S * 1.01, 0.15))
    trial = {"kind": "slide", "texture": draw(st.sampled_from(TEXTURES)), "force_N": draw(_log_uniform(0.01, 20.0)),
             "velocity_mm_per_s": velocity, "distance_mm": distance, "approach_s": 0.005, "hold_s": hold,
             "accel_s": accel, "lift_s": 0.005}
    span = 0.005 + hold + distance / velocity + accel + 0.005
    trial["start_s"] = [0.01 + i * (span + 0.01) for i in range(draw(st.integers(2, 3)))]
    skin = {"wear_coefficient": draw(st.one_of(st.sampled_from([0.0, 1.0]), _log_uniform(1e-7, 1.0)))}
    if draw(st.booleans()):
        skin["ridge_height_um"] = draw(st.one_of(st.just(0.0), st.floats(0.0, 200.0)))
    else:
        skin["fingerprints"] = draw(st.booleans())
    return draw(_scene(trial["start_s"][-1] + span + 0.01, [trial], skin=skin))


# --- the properties --------------------------------------------------------------------------------------------


@pytest.mark.stability
@RUN
@given(_taps_and_presses())
def test_taps_and_presses_keep_every_property(data):
    _holds_the_properties(data)


@pytest.mark.stability
@RUN
@given(_sphere_drops())
def test_every_sphere_from_any_height_keeps_every_property(data):
    _holds_the_properties(data)


@pytest.mark.stability
@RUN
@given(_vibrations())
def test_vibrations_sweeps_and_pressures_keep_every_property(data):
    _holds_the_properties(data)


@pytest.mark.stability
@RUN
@given(_thermal_contacts())
def test_thermal_contacts_at_the_temperature_extremes_keep_every_property(data):
    _holds_the_properties(data)


@pytest.mark.stability
@RUN
@given(_fingers())
def test_several_fingers_of_random_units_and_both_variants_keep_every_property(data):
    _holds_the_properties(data)


@pytest.mark.stability
@RUN
@given(_slides())
def test_slides_over_any_texture_on_skins_worn_to_nothing_keep_every_property(data):
    _holds_the_properties(data)


# --- just outside the ranges ---------------------------------------------------------------------------------------

#: a valid stimulus of each kind (several where fields exclude each other: a place by x_mm + angle_deg, a drop by
#: mass_mg + diameter_mm, a sweep); a field is tried on the first of its kind that has it, else on the first
STIMULUS_BASES = {
    "tap": [{"at_s": 1.0, "peak_N": 1.0},
            {"at_s": 1.0, "peak_N": 1.0, "x_mm": -5.0, "angle_deg": 0.0, "indenter_radius_mm": 3.0}],
    "press": [{"start_s": 1.0, "force_N": 1.0},
              {"start_s": 1.0, "force_N": 1.0, "x_mm": -5.0, "angle_deg": 0.0, "indenter_radius_mm": 3.0}],
    "sphere_drop": [{"at_s": 1.0, "sphere": "1 mm steel bearing", "height_m": 0.07},
                    {"at_s": 1.0, "mass_mg": 4.0, "diameter_mm": 1.0}],
    "vibration": [{"start_s": 1.0, "duration_s": 1.0, "amplitude_um": 1.0, "frequency_Hz": 100.0, "fade_s": 0.01},
                  {"start_s": 1.0, "duration_s": 1.0, "amplitude_um": 1.0, "f_start_Hz": 10.0, "f_stop_Hz": 900.0}],
    "pressure": [{"start_s": 1.0, "duration_s": 1.0, "offset_kPa": 1.0, "amplitude_Pa": 1.0, "frequency_Hz": 10.0,
                  "fade_s": 0.01}],
    "touch": [{"start_s": 1.0, "force_N": 1.0, "electrode": "E9", "indenter_radius_mm": 3.0, "tangential_N": 0.1,
               "shear_angle_deg": 0.0, "material": "aluminum", "object_temperature_C": 30.0},
              {"start_s": 1.0, "force_N": 1.0, "x_mm": -5.0, "angle_deg": 0.0}],
    "power_on": [{"at_s": 1.0}],
    "ambient_step": [{"at_s": 1.0, "temperature_C": 20.0}],
    "heater_failure": [{"at_s": 1.0}],
    "replace_skin": [{"at_s": 1.0}],
    "slide": [{"start_s": 1.0, "texture": "T2", "force_N": 0.5, "velocity_mm_per_s": 10.0, "distance_mm": 10.0,
               "start_position_mm": 10.0}],
}
EDGE = {"scene": {"name": "edge", "duration_s": MAX_DURATION_S}}  # long enough for every stimulus's range
RANGE = re.compile(r"(?:allowed range is |\((?:[^()]*, )?)(\S+) to ([^\s)]+)")


def _with(where: tuple, value) -> dict:
    """:data:`EDGE` with ``value`` at ``where``: ("stimulus", kind, field), (table, field) or ("sensors", field)."""
    if where[0] == "stimulus":
        kind, name = where[1:]
        bases = STIMULUS_BASES[kind]
        base = next((b for b in bases if name in b), bases[0])
        return {**EDGE, "stimulus": [{"kind": kind, **base, name: value}]}
    if where[0] == "sensors":
        return {**EDGE, "sensors": [{"index": 2, where[1]: value}]}
    table, name = where
    return {**EDGE, table: {**EDGE.get(table, {}), name: value}}


def _field(where: tuple) -> str:
    """The field as the validator names it (``stimulus[0].peak_N``, ``host.slot_rate_Hz``, ``sensors[0].index``)."""
    return {"stimulus": "stimulus[0]", "sensors": "sensors[0]"}.get(where[0], where[0]) + "." + where[-1]


def _scene_file(path, data: dict):
    """``data`` written to ``path`` as a scene file (each table inline, as TOML spells it); returns the path."""
    path.write_text("\n".join(f"{k} = {tomlfile.spelled(v, 10**6, note=False)}" for k, v in data.items()) + "\n",
                    encoding="utf-8")
    return path


def _problems(data: dict) -> list[str]:
    try:
        parse_scene(data, "edge.toml")
    except SceneError as e:
        return e.problems
    return []


def _ranged_fields() -> dict:
    """Every field whose value the validator checks against a range, with that range as its message spells it
    ("0.0 to 50.0"): found by giving each field a value far outside (2**70)."""
    candidates = [("stimulus", kind, name) for kind, names in _STIMULUS_FIELDS.items() for name in sorted(names)]
    candidates += [("scene", "duration_s"), ("scene", "seed"), ("host", "slot_rate_Hz"), ("host", "spi_clock_Hz"),
                   ("skin", "ridge_height_um"), ("skin", "wear_coefficient"), ("faults", "fluid_leak_mL_per_min"),
                   ("faults", "mux_stuck"), ("sensors", "index")]
    candidates += [("sensor", name) for name in sorted(PARAMETER_FIELDS)]
    found = {}
    for where in candidates:
        for problem in _problems(_with(where, 2**70)):
            m = RANGE.search(problem)
            if problem.startswith(f"{_field(where)} = ") and m:
                found[where] = f"{m[1]} to {m[2]}"
    return found


RANGED = _ranged_fields()


def _number(text: str):
    """A range's end as its message spells it: a whole number, or a float."""
    return int(text) if re.fullmatch(r"-?\d+", text) else float(text)


def _just_outside(span: str) -> list:
    """Values just outside the range ``span`` ("lo to hi"): the floats next to its ends, and for whole-number ends
    the whole numbers next to them too."""
    lo, hi = (_number(x) for x in span.split(" to "))
    out = [math.nextafter(float(lo), -math.inf), math.nextafter(float(hi), math.inf)]
    return out + ([lo - 1, hi + 1] if isinstance(lo, int) and isinstance(hi, int) else [])


@pytest.mark.unit
def test_the_ranged_fields_found_cover_every_kind_of_input():
    """The search for ranged fields (above) finds what the properties draw from, so the test below cannot pass by
    finding nothing."""
    stimulus_fields = {w[1:] for w in RANGED if w[0] == "stimulus"}
    assert {("tap", "peak_N"), ("tap", "duration_s"), ("press", "force_N"), ("press", "ramp_s"),
            ("sphere_drop", "height_m"), ("vibration", "frequency_Hz"), ("vibration", "amplitude_um"),
            ("vibration", "f_stop_Hz"), ("pressure", "offset_kPa"), ("touch", "object_temperature_C"),
            ("touch", "tangential_N"), ("ambient_step", "temperature_C"), ("slide", "force_N"),
            ("slide", "velocity_mm_per_s")} <= stimulus_fields
    assert {("skin", "ridge_height_um"), ("faults", "fluid_leak_mL_per_min"), ("sensors", "index"),
            ("scene", "duration_s")} <= set(RANGED)
    assert {w[1] for w in RANGED if w[0] == "sensor"} == set(PARAMETER_FIELDS)


@pytest.mark.unit
@pytest.mark.parametrize("where", sorted(RANGED), ids=lambda w: ".".join(w))
def test_a_value_just_outside_its_range_is_refused_naming_file_field_value_and_range(where, tmp_path):
    """Each value just outside a field's range (the next float beyond either end; for whole numbers also the next
    whole number) is refused by the scene file's validator with exactly one problem: the file, then the field and
    the value as the file spells them, and the range ("lo to hi", or "lo..hi" for sensor numbers); the ends themselves
    pass the range check."""
    span = RANGED[where]
    for i, value in enumerate(_just_outside(span)):
        path = _scene_file(tmp_path / f"edge{i}.toml", _with(where, value))
        with pytest.raises(SceneError) as e:
            load_scene(path)
        assert str(e.value).startswith(f"{path}: 1 problem(s):"), str(e.value)
        (problem,) = e.value.problems
        assert problem.startswith(f"{_field(where)} = {tomlfile.spelled(value)}"), problem
        assert span in problem or span.replace(" to ", "..") in problem, problem
    for end in (_number(x) for x in span.split(" to ")):
        assert not [p for p in _problems(_with(where, end)) if p.startswith(f"{_field(where)} = ")
                    and RANGE.search(p)], (where, end)


INSTANTS = sorted(("stimulus", kind, name) for kind, names in _STIMULUS_FIELDS.items() for name in names
                  if name in ("at_s", "start_s")) + [("faults", "fluid_leak_start_s")]


@pytest.mark.unit
@pytest.mark.parametrize("where", INSTANTS, ids=lambda w: ".".join(w))
def test_an_instant_just_outside_the_scene_is_refused_naming_file_field_value_and_range(where, tmp_path):
    """An instant (at_s, start_s, fluid_leak_start_s) lies in [0, duration_s): the float just below 0 and
    duration_s itself are each refused with exactly one problem naming the file, the field, the value and the
    bound it crosses."""
    for value, bound in ((math.nextafter(0.0, -math.inf), "≥ 0 s"), (MAX_DURATION_S, f"duration_s = {MAX_DURATION_S}")):
        data = _with(where, value)
        if where[0] == "faults":  # a leak's start needs its rate
            data["faults"]["fluid_leak_mL_per_min"] = 1.0
        path = _scene_file(tmp_path / "edge.toml", data)
        with pytest.raises(SceneError) as e:
            load_scene(path)
        assert str(e.value).startswith(f"{path}: 1 problem(s):"), str(e.value)
        (problem,) = e.value.problems
        assert problem.startswith(f"{_field(where)} = {tomlfile.spelled(value)}") and bound in problem, problem
