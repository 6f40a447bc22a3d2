"""Sensor units (issue 10.1): a unit is drawn deterministically from documented manufacturing spreads; the nominal
unit is today's sensor exactly; units differ from one another (serial, resting PDC, resting electrode codes); the
published-figure claims of the fast groups hold for the nominal unit and for 10 random units; scenes name units."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bench.scenes.scene import SceneError, parse_scene_text
from bench.tests.cli_runs import run_cli
from emulator import conversions as conv
from emulator.channels import channel_index
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.stimuli import SPHERES
from emulator.units import (DRAWN_FIELDS, ELECTRODE_GAP_SPREAD_MM, NOMINAL_SERIAL, SPAN_LIMIT, derived, seed_of_serial,
                            serial_for, unit)

ELECTRODES = [f"E{n}" for n in range(1, 20)]
RANDOM_UNITS = [3, 17, 101, 4242, 65537, 123456, 777, 2012, 31337, 2**31 - 1]
FAST_GROUPS = ("noise", "scales", "force", "thermal", "electrodes")
#: claims that compare electrodes: they compare each electrode's change in fluid conductance (how far the skin moved
#: over it, whatever gap it rests at: bench/verification/claims/electrodes.py), so they hold for every unit
GAP_SENSITIVE = {"pressing over an electrode moves it most", "a 1 N contact's change stays in the nearest 4 electrodes",
                 "a contact's electrode pattern locates it"}


#: a unit's own thermistor (R25 ±1 %, Beta ±3 %) read through the published conversion (the nominal part's constants)
#: reads off by what its R25 and Beta predict: for a unit this claim is checked against that prediction instead
UNIT_THERMISTOR = "TDC conversion error over 0–70 °C"
TDC_CONVERSION_BAR_C = 0.1  # the claim's own bar: rounding of the published constants, ADC and dither


def read_through_published_conversion_C(bead_C: float, p: SensorParams) -> float:
    """The temperature the published conversion (R25 = 470 kΩ, B = 4025 K) reads for unit ``p``'s thermistor at
    ``bead_C``: ln(R/470 kΩ) = 4025·(1/T' − 1/298.15) with R = R25'·exp(B'·(1/T − 1/298.15))."""
    t = bead_C + 273.15
    ln_r = np.log(p.thermistor_r25_ohm / 470e3) + p.thermistor_beta_K * (1.0 / t - 1.0 / 298.15)
    return 1.0 / (1.0 / 298.15 + ln_r / 4025.0) - 273.15


def skin_movement_depends_on_the_rest() -> bool:
    """True while the electrode model thins each electrode's fluid by a share of its own resting gap (then the skin
    moves farther over a thick-gap electrode for the same contact, and no reading of the codes can compare electrodes
    independently of their rests); False once the skin's movement is the contact's alone."""
    from emulator.electrodes import Contact, electrode_gaps_mm

    p = SensorParams()
    positions = np.array([[0.0, 0.0, -5.0], [0.0, 0.0, -5.0]])
    contact = Contact(np.array([0.0, 0.0, -5.0]), 3.0, lambda t: np.full(np.shape(t), 0.5))
    gaps = electrode_gaps_mm(p, [contact], np.array([0.0]), positions, rest_mm=np.array([1.0, 2.0]))[0]
    moved = gaps - np.array([1.0, 2.0])
    return not np.isclose(moved[0], moved[1], rtol=1e-9, atol=1e-12)


def resting_electrode_codes(p: SensorParams) -> np.ndarray:
    chans = np.array([channel_index(n) for n in ELECTRODES])
    sensor = Sensor(p, [], ELECTRODES, "default", 1, NoiseSources.none())
    return sensor.sample(chans, 0.1 + np.arange(19) * 1e-3)


def test_the_nominal_unit_is_todays_sensor_exactly():
    for which in (None, "nominal", NOMINAL_SERIAL):
        u = unit(which)
        assert u.params == SensorParams() and u.seed is None and u.serial == NOMINAL_SERIAL


def test_a_unit_seed_reproduces_the_unit_bit_for_bit_and_units_differ():
    a, b = unit(17), unit(17)
    assert a == b and a.params == b.params
    assert np.array_equal(resting_electrode_codes(a.params), resting_electrode_codes(b.params))
    others = [unit(s) for s in RANDOM_UNITS]
    assert len({u.serial for u in others}) == len(others) and all(u.serial.startswith("BT") for u in others)
    for name in set(DRAWN_FIELDS) - {"electrode_gap_spread_mm"}:  # every spread is drawn (the gap spread is fixed)
        assert len({getattr(u.params, name) for u in others}) > 1, name
    # the serial stands for its unit; any other "BT" serial seeds its own, reproducible unit
    assert unit(serial_for(17)) == a and seed_of_serial(serial_for(4242)) == 4242
    assert unit("BT-my-finger").params == unit("BT-my-finger").params != SensorParams()


#: each drawn spread as the README documents it: field, "normal" (σ, clipped at 3σ) or "uniform" (± half-width),
#: absolute (the field's nominal plus the draw) or relative (times 1 + the draw), and its size
DOCUMENTED_SPREADS = {
    "inflation_volume_mL": ("normal", "absolute", 0.03), "bridge_offset_V_per_V": ("normal", "absolute", 1.0e-3),
    "bridge_sensitivity_V_per_V_Pa": ("normal", "relative", 0.0025),
    "bridge_offset_drift_V_per_V_K": ("normal", "relative", 0.20), "bridge_span_drift_per_K": ("normal", "relative", 0.20),
    "stage1_bias_V": ("normal", "absolute", 0.010), "stage2_bias_V": ("normal", "absolute", 0.010),
    "thermistor_r25_ohm": ("uniform", "relative", 0.01), "thermistor_beta_K": ("uniform", "relative", 0.03),
    "resonance_Hz": ("normal", "absolute", 5.0)}


def test_the_population_of_units_has_the_documented_spreads_each_drawn_independently():
    """Over 600 units, each drawn field's deviation from nominal: a normal spread has its σ (± 12 %, four standard
    errors of an SD from 600 draws), is centred and clipped at 3σ; a uniform one fills ± its half-width (both ends
    within 10 %) and is centred; no two fields share a draw (|r| < 0.17, four standard errors). The drifts keep the
    nominal part's sign in every unit."""
    n = 600
    nominal = SensorParams()
    units = [unit(s).params for s in range(n)]
    deviations = {}
    for name, (shape, how, size) in DOCUMENTED_SPREADS.items():
        values, base = np.array([getattr(u, name) for u in units]), getattr(nominal, name)
        d = (values - base) if how == "absolute" else (values / base - 1.0)
        deviations[name] = d
        if shape == "normal":
            limit = SPAN_LIMIT if name == "bridge_sensitivity_V_per_V_Pa" else 3.0 * size
            assert abs(d.std() / size - 1.0) < 0.12 and np.abs(d).max() <= limit * (1 + 1e-9), (name, d.std())
            assert abs(d.mean()) < 4.0 * size / np.sqrt(n), (name, d.mean())
        else:
            assert d.min() < -0.9 * size and d.max() > 0.9 * size and np.abs(d).max() <= size, name
            assert abs(d.mean()) < 4.0 * size / np.sqrt(3.0 * n), (name, d.mean())
    r = np.corrcoef(np.array(list(deviations.values())))
    names = list(deviations)
    shared = [(names[i], names[j], round(r[i, j], 3)) for i in range(len(names)) for j in range(i)
              if abs(r[i, j]) > 0.17]
    assert not shared, shared
    for name in ("bridge_offset_drift_V_per_V_K", "bridge_span_drift_per_K"):
        assert all(np.sign(getattr(u, name)) == np.sign(getattr(nominal, name)) for u in units), name


@pytest.mark.parametrize("edge_Hz", [200.0, 350.0])
def test_units_drawn_around_a_base_at_the_published_resonance_range_edge_stay_inside_it(edge_Hz):
    """The module's docstring: a unit's resonance is drawn σ 5 Hz around its base and clipped to the published
    200–350 Hz.  Around a base at either edge about half the draws fall outside: every unit is still drawn (no
    range error) with its resonance clipped to the edge, and the others stay within 3σ (15 Hz) of the base."""
    drawn = np.array([unit(s, base=SensorParams(resonance_Hz=edge_Hz)).params.resonance_Hz for s in range(40)])
    assert np.all((drawn >= 200.0) & (drawn <= 350.0))
    assert np.count_nonzero(drawn == edge_Hz) >= 8  # ~20 expected: the clip, not luck, keeps them inside
    assert np.all(np.abs(drawn - edge_Hz) <= 15.0)


def test_resting_electrode_codes_differ_across_electrodes_and_units():
    nominal = resting_electrode_codes(SensorParams())
    assert len(set(nominal)) <= 2  # identical electrodes at rest (± one code of rounding)
    codes = np.array([resting_electrode_codes(unit(s).params) for s in RANDOM_UNITS])
    per_unit_span = codes.max(axis=1) - codes.min(axis=1)
    assert (per_unit_span > 300).all(), per_unit_span  # each unit's electrodes rest at different codes
    assert len({tuple(c) for c in codes}) == len(RANDOM_UNITS)
    # the spread is sized so resting codes cover roughly 1900–3200 (2nd–98th percentile over units)
    lo, hi = np.percentile(codes, [2, 98])
    assert 1700 < lo < 2300 and 3000 < hi < 3300, (lo, hi, ELECTRODE_GAP_SPREAD_MM)
    # docs/model.md states them for units 0–19: 1900–3152 (a read-back of the spread, to the code)
    first_twenty = np.array([resting_electrode_codes(unit(s).params) for s in range(20)])
    assert np.percentile(first_twenty, [2, 98]) == pytest.approx([1900, 3152], abs=1)


def test_units_move_resting_pdc_within_the_adc_and_keep_the_scales():
    rest = [derived(unit(s).params)["resting_PDC_code"] for s in range(200)]
    nominal = derived(SensorParams())["resting_PDC_code"]
    assert 200 < min(rest) and max(rest) < 1400 and np.std(rest) > 20, (min(rest), max(rest), nominal)
    # README: "Over 500 units: resting PDC 387–1107 (nominal 735), resonance 312–345 Hz, PDC scale 36.70–37.22
    # Pa/bit" (seeds 0..499), to its printed digits
    d = [derived(unit(s).params) for s in range(500)]
    ranges = {k: (min(x[k] for x in d), max(x[k] for x in d))
              for k in ("resting_PDC_code", "resonance_at_inflation_Hz", "PDC_Pa_per_bit")}
    assert [round(v) for v in ranges["resting_PDC_code"]] == [387, 1107] and round(nominal) == 735, ranges
    assert [round(v) for v in ranges["resonance_at_inflation_Hz"]] == [312, 345], ranges
    assert [round(v, 2) for v in ranges["PDC_Pa_per_bit"]] == [36.70, 37.22], ranges
    spans = [unit(s).params.bridge_sensitivity_V_per_V_Pa / SensorParams().bridge_sensitivity_V_per_V_Pa - 1
             for s in range(200)]
    assert max(map(abs, spans)) <= SPAN_LIMIT + 1e-12


@pytest.mark.parametrize("which", [None, *RANDOM_UNITS], ids=lambda w: f"unit-{w or 'nominal'}")
def test_the_fast_claims_hold_for_the_unit(which):
    """noise, scales, force, thermal and electrodes: every claim within its tolerance (about 1 s per unit)."""
    from bench.verification.claims import Bench, run_claims

    claims = run_claims(Bench(params=unit(which).params), FAST_GROUPS)
    names = {c.name for c in claims}
    assert len(claims) > 20
    assert GAP_SENSITIVE <= names, GAP_SENSITIVE - names  # a renamed claim must be looked at again here
    bad = [(c.name, c.measured, c.tolerance) for c in claims
           if not c.ok and (which is None or c.name != UNIT_THERMISTOR)]
    if which is not None:  # the unit's thermistor: the published conversion misreads it by what R25/Beta predict
        tdc = next(c for c in claims if c.name == UNIT_THERMISTOR)
        p = unit(which).params
        off = [abs(float(conv.tdc_to_celsius(code)) - read_through_published_conversion_C(bead, p))
               for bead, code in tdc.details["bead_C_and_mean_code"]]
        assert max(off) <= TDC_CONVERSION_BAR_C, (which, off)
    if bad and which is not None and skin_movement_depends_on_the_rest() and {n for n, _, _ in bad} <= GAP_SENSITIVE:
        pytest.xfail(f"unit {which}: the electrode model thins each electrode's fluid by a share of its own resting "
                     f"gap (emulator/electrodes.electrode_gaps_mm), so the skin moves farther over a thick-gap "
                     f"electrode for the same contact: {bad}")
    assert not bad, f"unit {which}: {bad}"


#: the sensitivity groups: the ring and its move with inflation, the six-sphere detection table (D Table 5-3) and the
#: frequency sensitivity (d_min, the human comparison); the 10 h false-detection run stays with the nominal unit
SENSITIVITY_GROUPS = ("impact", "detection", "vibration")


@pytest.mark.parametrize("which", RANDOM_UNITS, ids=lambda w: f"unit-{w}")
def test_the_sensitivity_claims_hold_for_the_unit(which):
    """impact, detection and vibration on a random unit (its own inflation, so its own resonance): every claim within
    its tolerance, and the one documented deviation (energy vs momentum) still deviates (about 5 s per unit)."""
    from bench.verification.claims import Bench, run_claims

    claims = run_claims(Bench(params=unit(which).params), SENSITIVITY_GROUPS)
    names = {c.name for c in claims}
    assert len(claims) >= 15 and {f"detected: {n}" for n in SPHERES} <= names, sorted(names)
    assert not [(c.name, c.measured, c.tolerance) for c in claims if not c.ok], f"unit {which}"


# --- scenes and the command line ---------------------------------------------------------------------------------

BASE = """
[scene]
name = "u"
duration_s = 0.5
"""


def test_a_scene_names_its_units_and_they_reach_the_sensors():
    from bench.hosts.scene_sensors import sensors_from_scene

    sc = parse_scene_text(BASE + """
[sensor]
unit = 17
inflation_volume_mL = 0.55

[[sensors]]
index = 2
unit = "nominal"

[[sensors]]
index = 3
unit = "BTU0000000000004"
""")
    assert sc.unit == "17" and sc.serial == serial_for(17) and sc.n_sensors == 3
    assert sc.params == unit(17).params.replace(inflation_volume_mL=0.55)  # parameters on top of the unit
    sensors = sensors_from_scene(sc, 4)
    assert sensors[2].params == SensorParams() and sensors[3].params == unit(4).params
    assert sensors[4].params == sc.params  # a sensor the scene does not describe is sensor 1's twin, at rest
    assert [s.serial for s in sensors.values()] == [serial_for(17), None, serial_for(4), None]


@pytest.mark.parametrize("text, needle", [
    ("[sensor]\nunit = -1\n", "sensor.unit = -1: a unit seed 0 to 2147483647"),
    ("[sensor]\nunit = 1.5\n", "sensor.unit = 1.5"),
    ("[sensor]\nunit = \"XX12\"\n", 'sensor.unit = "XX12"'),
    ("[sensor]\nunit = \"BT$$\"\n", 'sensor.unit = "BT$$": a serial number starts with "BT"'),
    ("[sensor]\nvariant = \"biotac-xl\"\n", 'sensor.variant = "biotac-xl": must be one of: biotac, biotac-sp'),
    ("[[sensors]]\nindex = 1\n", "sensors[0].index = 1: sensor 1 is described by the [sensor] table"),
    ("[[sensors]]\nindex = 6\n", "sensors[0].index = 6: allowed range is 2 to 5"),
    ("[[sensors]]\nunit = 3\n", "sensors[0].index is missing"),
    ("[[sensors]]\nindex = 2\n[[sensors]]\nindex = 2\n", "sensors[1].index = 2: sensor 2 is already described by "
                                                       "sensors[0]"),
    ("[sensors]\nindex = 2\n", "must be an array of tables ([[sensors]])"),
    ("[[sensors]]\nindex = 2\ncolour = 1\n", 'sensors[0]: unknown field "colour"'),
    ("[[sensors]]\nindex = 2\ninflation_volume_mL = 9.0\n", "sensors[0].inflation_volume_mL"),
    ("[[stimulus]]\nkind = \"tap\"\nat_s = 0.1\npeak_N = 1.0\nsensor = 7\n", "stimulus[0].sensor = 7: allowed range "
                                                                            "is 1 to 5"),
    ("[[stimulus]]\nkind = \"tap\"\nat_s = 0.1\npeak_N = 1.0\nsensor = \"2\"\n", 'stimulus[0].sensor = "2": must be '
                                                                               "a whole number"),
    ("[[stimulus]]\nkind = \"touch\"\nstart_s = 0.1\nforce_N = 1.0\nelectrode = \"E22\"\n",
     'sensor 1 is a "biotac", which has E1..E19'),
])
def test_bad_unit_sensor_and_variant_keys_are_refused_naming_the_field(text, needle):
    with pytest.raises(SceneError) as e:
        parse_scene_text(BASE + text)
    assert needle in str(e.value), str(e.value)


def test_the_units_command_prints_a_unit_compares_it_and_refuses_bad_values():
    r = run_cli("units", "--seed", 17, "--compare")
    assert r.returncode == 0, r.stderr
    assert "serial BTU0000000000017" in r.stdout and "inflation_volume_mL" in r.stdout and "nominal" in r.stdout
    doc = json.loads(run_cli("units", "--serial", serial_for(17), "--json").stdout)
    assert doc["parameters"]["inflation_volume_mL"] == unit(17).params.inflation_volume_mL
    nominal = json.loads(run_cli("units", "--json").stdout)
    assert nominal["serial"] == NOMINAL_SERIAL and nominal["parameters"]["electrode_gap_spread_mm"] == 0.0
    for bad, needle in ((["--seed", "-2"], "--seed"), (["--serial", "XY"], "--serial"),
                        (["--seed", "1", "--serial", "BT1"], "not allowed with")):
        r = run_cli("units", *bad)
        assert r.returncode == 2 and needle in r.stderr and "Traceback" not in r.stderr, r.stderr


def test_a_unit_given_in_an_odd_form_is_refused_in_one_line_naming_the_command_and_the_flag():
    """A serial of the seed form naming a seed past 2³¹ − 1 passed the flag's check and failed in the command
    ("error: serial ..."); a non-ASCII digit passed str.isdigit ("²" then failed in int(): "invalid unit_choice
    value"; "١٧" became unit 17, which a scene's unit = "١٧" refuses)."""
    for argv, line in ((("units", "--serial", "BTU9999999999999"), "biotac-bench units: error: argument --serial: "
                        'serial "BTU9999999999999": unit seed 9999999999999 is above 2147483647'),
                       (("claims", "--unit", "²", "--only", "scales"), "biotac-bench claims: error: argument --unit: "
                        'unit "²": a unit seed 0 to 2147483647'),
                       (("claims", "--unit", "١٧", "--only", "scales"), "biotac-bench claims: error: argument --unit: "
                        'unit "١٧": a unit seed 0 to 2147483647')):
        r = run_cli(*argv)
        assert r.returncode == 2 and r.stderr.startswith(line) and r.stderr.count("\n") == 1, (argv, r.stderr)
    for odd in ("²", "١٧"):
        with pytest.raises(ValueError, match="a unit seed 0 to 2147483647"):
            unit(odd)
    assert unit("17").seed == 17


def test_claims_unit_runs_the_claims_on_that_unit():
    r = run_cli("claims", "--unit", 17, "--only", "scales", "--json")
    assert r.returncode == 0, r.stderr
    rows = {c["name"]: c for c in json.loads(r.stdout)}
    nominal = {c["name"]: c for c in json.loads(run_cli("claims", "--only", "scales", "--json").stdout)}
    assert rows["PDC scale"]["measured"] != nominal["PDC scale"]["measured"]  # the unit's own bridge span
    r = run_cli("claims", "--unit", "nope", "--only", "scales")
    assert r.returncode == 2 and "--unit" in r.stderr and "Traceback" not in r.stderr


@pytest.mark.firmware  # builds the Cheetah library
def test_the_pytest_fixtures_take_a_unit(biotac_sensor, biotac_cheetah):
    from emulator.spi.model import PROP_SERIAL

    port = biotac_sensor(unit=17)
    assert port.sensor.params == unit(17).params and port.properties[PROP_SERIAL][0] == serial_for(17).encode()
    assert biotac_sensor().sensor.params == SensorParams()
    cb = biotac_cheetah(2, units=[4, "nominal"])
    assert cb.bus.ports[1].sensor.params == unit(4).params and cb.bus.ports[2].sensor.params == SensorParams()
    assert [cb.bus.ports[k].sensor.serial for k in (1, 2)] == [serial_for(4), None]
