"""Scene files: validation messages name the field, the value and what is allowed."""

import pytest

from bench.errors import SceneError
from bench.scenes.scene import load_scene, parse_scene
from emulator.stimuli import Press, SphereDrop, Vibration

pytestmark = pytest.mark.unit

MINIMAL = {"scene": {"name": "t", "duration_s": 1.0}}


def problems(data):
    with pytest.raises(SceneError) as e:
        parse_scene(data, source="s.toml")
    return e.value.problems


def test_a_minimal_scene_is_valid_with_documented_defaults():
    sc = parse_scene(MINIMAL)
    assert sc.fidelity == "default" and sc.seed == 0 and sc.sequence == "default" and sc.slot_rate_Hz == 4400.0


def test_out_of_range_value_names_field_value_and_range():
    (msg,) = problems({"scene": {"name": "t", "duration_s": -2}})
    assert "scene.duration_s = -2" in msg and "allowed range" in msg


def test_missing_required_fields_are_named():
    msgs = problems({"scene": {"name": "t"}, "stimulus": [{"kind": "tap", "at_s": 0.1}]})
    assert any("scene.duration_s is missing" in m for m in msgs)
    assert any("stimulus[0].peak_N is missing" in m for m in msgs)


def test_every_problem_is_reported_at_once():
    msgs = problems({"scene": {"name": "", "duration_s": 1.0, "fidelity": "ultra"},
                     "host": {"sequence": ["PAC", "QQQ"], "spi_clock_Hz": 20e6},
                     "sensor": {"stage1_gain": 0.0, "no_such": 1}})
    text = "\n".join(msgs)
    for needle in ("scene.name", 'scene.fidelity = "ultra"', 'host.sequence[1] = "QQQ"', "host.spi_clock_Hz",
                   "sensor.stage1_gain = 0.0", 'unknown field "no_such"'):
        assert needle in text


def test_stimulus_after_the_end_and_unknown_sphere_are_refused():
    msgs = problems({**MINIMAL, "stimulus": [{"kind": "sphere_drop", "sphere": "marble", "at_s": [0.5, 3.0]}]})
    text = "\n".join(msgs)
    assert 'stimulus[0].sphere = "marble"' in text and "0.45 mm solder ball" in text
    assert "stimulus[0].at_s[1] = 3.0 s: after the end of the scene" in text


@pytest.mark.parametrize("stimulus, duration_s, needle", [
    ({"kind": "press", "start_s": 1.5, "force_N": 1.0, "ramp_s": 0.5, "hold_s": 5.0}, 2.0,
     "stimulus[0]: the press starting at 1.5 s ends at 7.500 s, after the end of the scene (duration_s = 2.0)"),
    ({"kind": "vibration", "start_s": 0.5, "duration_s": 5.0, "amplitude_um": 1, "frequency_Hz": 100.0}, 2.0,
     "stimulus[0]: the vibration starting at 0.5 s ends at 5.500 s, after the end of the scene (duration_s = 2.0)"),
    ({"kind": "vibration", "start_s": 0.5, "duration_s": 10.0, "amplitude_um": 1, "f_start_Hz": 10.0,
      "f_stop_Hz": 900.0}, 3.0, "stimulus[0]: the vibration (a 10 → 900 Hz sweep) starting at 0.5 s ends at 10.500 s"),
    ({"kind": "pressure", "start_s": 0.5, "duration_s": 2.0, "offset_kPa": 5.0}, 1.0,
     "stimulus[0]: the pressure starting at 0.5 s ends at 2.500 s"),
    ({"kind": "touch", "start_s": 0.2, "force_N": 1.0, "electrode": "E7"}, 1.0,  # default ramps 0.5 s, hold 1 s
     "stimulus[0]: the touch starting at 0.2 s ends at 2.200 s"),
    ({"kind": "tap", "at_s": [0.3, 0.9], "peak_N": 1.0, "duration_s": 0.2}, 1.0,
     "stimulus[0]: the tap starting at 0.9 s ends at 1.100 s"),
], ids=["press", "vibration", "sweep", "pressure", "touch", "tap"])
def test_a_stimulus_ending_after_the_scene_is_refused_as_a_slide_is(stimulus, duration_s, needle):
    """Finding 7 of the user review: these were accepted and silently cut off at the scene's end."""
    (msg,) = problems({"scene": {"name": "t", "duration_s": duration_s}, "stimulus": [stimulus]})
    assert needle in msg and "after the end of the scene" in msg


def test_stimuli_ending_exactly_at_the_end_of_the_scene_are_accepted():
    sc = parse_scene({**MINIMAL, "stimulus": [
        {"kind": "press", "start_s": 0.2, "force_N": 1.0, "ramp_s": 0.2, "hold_s": 0.4},  # 0.2 + 0.4 + 0.4 s
        {"kind": "vibration", "start_s": 0.3, "duration_s": 0.7, "amplitude_um": 1, "frequency_Hz": 50.0},
        {"kind": "tap", "at_s": 0.97, "peak_N": 0.5, "duration_s": 0.03}]})
    assert [round(s.end_s, 12) for s in sc.stimuli] == [1.0, 1.0, 1.0]


def test_vibration_too_fast_for_the_fidelity_grid_is_refused_with_advice():
    msgs = problems({"scene": {"name": "t", "duration_s": 1.0, "fidelity": "fast"},
                     "stimulus": [{"kind": "vibration", "start_s": 0.0, "duration_s": 0.5, "amplitude_um": 1,
                                   "frequency_Hz": 2500.0}]})
    assert any("finer grid" in m and "reference" in m for m in msgs)


def test_each_stimulus_too_fast_for_the_grid_is_named_by_its_start_and_finger():
    """Two vibrations and a pressure too fast for 'fast' (on two fingers): each problem says which one (they had
    been identical lines, naming no stimulus)."""
    msgs = problems({"scene": {"name": "t", "duration_s": 1.0, "fidelity": "fast"},
                     "stimulus": [{"kind": "vibration", "start_s": [0.1, 0.6], "duration_s": 0.2, "amplitude_um": 1,
                                   "frequency_Hz": 2500.0},
                                  {"kind": "pressure", "start_s": 0.25, "duration_s": 0.5, "amplitude_Pa": 10.0,
                                   "frequency_Hz": 3000.0, "sensor": 2}]})
    assert len(msgs) == len(set(msgs)) == 3
    assert any("vibration at 2500 Hz" in m and m.startswith("the stimulus starting at 0.1 s: ") for m in msgs)
    assert any("vibration at 2500 Hz" in m and m.startswith("the stimulus starting at 0.6 s: ") for m in msgs)
    assert any("pressure at 3000 Hz" in m and m.startswith("the stimulus starting at 0.25 s on sensor 2: ") for m in msgs)


def _grid_problems(fidelity, stimulus):
    """The problems of a one-stimulus scene at ``fidelity`` ([] if the scene is accepted)."""
    try:
        parse_scene({"scene": {"name": "t", "duration_s": 1.0, "fidelity": fidelity}, "stimulus": [stimulus]},
                    source="s.toml")
    except SceneError as e:
        return list(e.problems)
    return []


def _vibration(f_Hz, other_end_Hz=None):
    v = {"kind": "vibration", "start_s": 0.0, "duration_s": 0.5, "amplitude_um": 1}
    return {**v, "frequency_Hz": f_Hz} if other_end_Hz is None else {**v, "f_start_Hz": other_end_Hz, "f_stop_Hz": f_Hz}


def _calibrator(f_Hz):
    return {"kind": "pressure", "start_s": 0.0, "duration_s": 0.5, "offset_kPa": 0.0, "amplitude_Pa": 10.0,
            "frequency_Hz": f_Hz}


@pytest.mark.parametrize("make", [_vibration, lambda f: _vibration(f, other_end_Hz=10.0),
                                  lambda f: {**_vibration(10.0, f), "f_start_Hz": f, "f_stop_Hz": 10.0}, _calibrator],
                         ids=["vibration", "sweep up", "sweep down", "calibrator"])
def test_the_fast_grid_refuses_a_frequency_from_0_45_of_its_rate_and_names_the_profiles_that_fit(make):
    """The fast profile's 4400 Hz grid computes up to 0.45 of its rate, 1980 Hz (scenes allow up to 3000 Hz, which
    the default 8800 Hz grid computes): just below is accepted, at and above refused, naming the profiles to use."""
    from emulator.fidelity import profile

    assert profile("fast").grid_Hz == 4400.0
    assert _grid_problems("fast", make(1979.99)) == []
    assert _grid_problems("default", make(3000.0)) == []  # the highest a scene allows, on the default grid
    for f in (1980.0, 2000.0, 3000.0):
        (msg,) = _grid_problems("fast", make(f))
        assert "needs a finer grid than fidelity 'fast' (4400 Hz)" in msg, msg
        assert msg.endswith('use "default" or "reference"'), msg  # the profiles that compute it, not the one refused


def test_a_calibrator_that_holds_a_steady_pressure_needs_no_grid():
    steady = {"kind": "pressure", "start_s": 0.0, "duration_s": 0.5, "offset_kPa": 2.0, "frequency_Hz": 2500.0}
    assert _grid_problems("fast", steady) == []


def test_bad_types_are_reported_not_crashed_on():
    msgs = problems({"scene": {"name": "t", "duration_s": "long", "seed": 1.5},
                     "stimulus": {"kind": "tap"}})
    text = "\n".join(msgs)
    assert 'scene.duration_s = "long"' in text and "scene.seed = 1.5" in text and "array of tables" in text


def test_toml_syntax_errors_and_missing_files_name_the_file(tmp_path):
    f = tmp_path / "broken.toml"
    f.write_text("[scene\nname = 1")
    with pytest.raises(SceneError, match="(?s)broken.toml.*TOML syntax error"):
        load_scene(f)
    with pytest.raises(SceneError, match="cannot read the file"):
        load_scene(tmp_path / "absent.toml")


def test_each_stimulus_kind_builds_its_object():
    sc = parse_scene({**MINIMAL, "stimulus": [
        {"kind": "sphere_drop", "sphere": "1 mm steel bearing", "at_s": [0.1, 0.2]},
        {"kind": "sphere_drop", "mass_mg": 2.0, "height_m": 0.2, "at_s": 0.3},
        {"kind": "press", "start_s": 0.1, "force_N": 1.0, "ramp_s": 0.2, "hold_s": 0.3},
        {"kind": "vibration", "start_s": 0.0, "duration_s": 0.5, "amplitude_um": 1, "f_start_Hz": 10,
         "f_stop_Hz": 900},
        {"kind": "pressure", "start_s": 0.0, "duration_s": 0.5, "offset_kPa": 5.0},
    ]})
    kinds = [type(s) for s in sc.stimuli]
    assert kinds.count(SphereDrop) == 3 and Press in kinds and Vibration in kinds
    assert sc.stimuli[2].mass_kg == pytest.approx(2e-6)


def test_shipped_scenes_are_all_valid():
    from pathlib import Path
    scenes = sorted((Path(__file__).resolve().parents[2] / "fixtures" / "scenes").glob("*.toml"))
    assert len(scenes) >= 4
    for f in scenes:
        load_scene(f)


def test_touch_thermal_kinds_and_faults_are_validated():
    sc = parse_scene({**MINIMAL, "stimulus": [
        {"kind": "touch", "start_s": 0.1, "force_N": 1.0, "ramp_s": 0.2, "hold_s": 0.3, "electrode": "E7",
         "material": "glass"},
        {"kind": "power_on", "at_s": 0.0}, {"kind": "ambient_step", "at_s": 0.5, "temperature_C": 18.0}],
        "faults": {"electrode_open": [3], "mux_stuck": 4, "thermistor": "open", "heater_failed": True}})
    assert len(sc.stimuli) == 3 and sc.faults["mux_stuck"] == 4
    msgs = problems({**MINIMAL, "stimulus": [{"kind": "touch", "start_s": 0.1, "force_N": 1.0, "electrode": "E42",
                                              "material": "cheese"}],
                     "faults": {"electrode_open": [0, 20], "thermistor": "melted", "fan": True}})
    text = "\n".join(msgs)
    for needle in ('stimulus[0].electrode = "E42"', 'stimulus[0].material = "cheese"', "faults.electrode_open",
                   'faults.thermistor = "melted"', 'unknown field "fan"'):
        assert needle in text


def test_a_touch_on_the_skin_tethered_at_the_nail_is_refused_by_that_fingers_own_limit():
    """A 1 N touch at 180° (on the nail) raised PDC 84 codes, exactly as on the pad: the model's contact loads the
    fluid wherever it is.  Beyond free_skin_half_angle_deg (120°) it is refused; a finger given 180° takes it."""
    touch = {"kind": "touch", "start_s": 0.1, "force_N": 1.0, "ramp_s": 0.2, "hold_s": 0.3}
    (msg,) = problems({**MINIMAL, "stimulus": [{**touch, "angle_deg": -150.0}]})
    assert msg.startswith("stimulus[0].angle_deg = -150.0: beyond 120° from the ventral midline the skin is "
                          "tethered at the nail") and msg.endswith("allowed -120 to 120°")
    assert parse_scene({**MINIMAL, "stimulus": [{**touch, "angle_deg": 120.0}]}).stimuli[0].angle_deg == 120.0
    hand = {**MINIMAL, "sensors": [{"index": 2, "free_skin_half_angle_deg": 180.0}]}
    assert parse_scene({**hand, "stimulus": [{**touch, "angle_deg": 180.0, "sensor": 2}]}).n_sensors == 2
    (msg,) = problems({**hand, "stimulus": [{**touch, "angle_deg": 180.0}]})  # sensor 1 keeps 120°
    assert msg.startswith("stimulus[0].angle_deg = 180.0: beyond 120°")


def test_a_sensor_number_of_the_wrong_type_or_missing_is_named_in_plain_words():
    """The sensor numbers' description was spelled as a unit: "must be a whole number in (a sensor number) (2 to
    5)", "is missing ((a sensor number), 2 to 5)"."""
    assert problems({**MINIMAL, "sensors": [{"index": 2.0}]}) == [
        "sensors[0].index = 2.0: must be a whole number (a sensor number, 2 to 5)"]
    assert problems({**MINIMAL, "sensors": [{"unit": 3}]}) == ["sensors[0].index is missing (a sensor number, 2 to 5)"]
    tap = {"kind": "tap", "at_s": 0.2, "peak_N": 1.0}
    assert problems({**MINIMAL, "stimulus": [{**tap, "sensor": "2"}]}) == [
        'stimulus[0].sensor = "2": must be a whole number (a sensor number, 1 to 5)']
    assert problems({**MINIMAL, "stimulus": [{**tap, "sensor": 6}]}) == [
        "stimulus[0].sensor = 6: allowed range is 1 to 5 (a sensor number)"]
    assert problems({**MINIMAL, "stimulus": [{**tap, "peak_N": "1"}]}) == [  # a unit is still said as one
        'stimulus[0].peak_N = "1": must be a number in N (0.0 to 50.0)']


def test_a_touch_beyond_the_fingertips_apex_is_refused():
    """The finger ends at its tip's apex, x = 5 mm: a touch at x_mm = 8 had been taken and dented the electrodes from
    3 mm beyond the tip.  The apex itself is a place."""
    touch = {"kind": "touch", "start_s": 0.1, "force_N": 1.0, "ramp_s": 0.2, "hold_s": 0.3}
    (msg,) = problems({**MINIMAL, "stimulus": [{**touch, "x_mm": 5.5}]})
    assert msg == "stimulus[0].x_mm = 5.5: allowed range is -20.0 to 5.0 mm"
    assert parse_scene({**MINIMAL, "stimulus": [{**touch, "x_mm": 5.0}]}).stimuli[0].x_mm == 5.0


@pytest.mark.parametrize("stimulus", [
    {"kind": "vibration", "start_s": 0.1, "duration_s": 0.5, "amplitude_um": 1.0, "frequency_Hz": 100.0},
    {"kind": "pressure", "start_s": 0.1, "duration_s": 0.5, "offset_kPa": 1.0},
])
def test_a_fade_longer_than_half_the_stimulus_is_refused_not_a_silently_smaller_stimulus(stimulus):
    # a 5 s fade on a 0.5 s vibration had been accepted: the stimulus reached 0.6 % of its amplitude
    (msg,) = problems({**MINIMAL, "stimulus": [{**stimulus, "fade_s": 5.0}]})
    assert "stimulus[0].fade_s = 5" in msg and "at most 0.25 s" in msg
    parse_scene({**MINIMAL, "stimulus": [{**stimulus, "fade_s": 0.25}]})  # exactly half: the peak is reached


def test_the_default_fade_of_a_short_stimulus_fits_it_so_the_stimulus_reaches_its_amplitude():
    import numpy as np

    from emulator.stimuli import fade_window

    sc = parse_scene({**MINIMAL, "stimulus": [{"kind": "vibration", "start_s": 0.1, "duration_s": 0.004,
                                               "amplitude_um": 1.0, "frequency_Hz": 100.0}]})
    (v,) = sc.stimuli
    assert v.fade_s == 0.002  # the default 0.01 s, shortened to half the stimulus
    assert fade_window(np.array([0.002]), v.duration_s, v.fade_s)[0] == pytest.approx(1.0)


def test_a_vibration_too_fast_for_fast_is_advised_the_default_profile_too():
    # 2500 Hz fits the default profile's 8.8 kHz grid: the advice had named only "reference" (8x slower)
    (msg,) = problems({"scene": {"name": "t", "duration_s": 1.0, "fidelity": "fast"},
                       "stimulus": [{"kind": "vibration", "start_s": 0.0, "duration_s": 0.5, "amplitude_um": 1,
                                     "frequency_Hz": 2500.0}]})
    assert msg.endswith('use "default" or "reference"')


def test_a_mixed_bus_reading_e20_to_e24_runs_sensor_1_answering_error_words(tmp_path):
    # sensor 1 a BioTac, sensor 2 a BioTac SP, the host reading E24: validate and run had ended in a KeyError
    # traceback (Scene.channels looked E24 up in sensor 1's channel map); the README has the 19-electrode sensor
    # answer E20..E24 with error words, and the bridge's refusal sends such scenes to `run`
    from bench.running.runner import check_buildable, run_scene

    sc = parse_scene({"scene": {"name": "t", "duration_s": 0.05}, "sensors": [{"index": 2, "variant": "biotac-sp"}],
                      "host": {"sequence": ["E24", "PDC"]}})
    assert sc.channels == ["PDC"]
    check_buildable(sc)
    rec = run_scene(sc, progress=False)
    assert rec.status == "ok", rec.error
    assert (rec.channels["E24"].status != 0).all() and (rec.channels["PDC"].status == 0).all()
    assert (rec.sensors[2].channels["E24"].status == 0).all()


def test_a_toml_date_or_a_missing_name_is_named_as_the_file_spells_it():
    """A TOML date-time where a number belongs is quoted as the file writes it, not as Python's
    ``datetime.datetime(1979, 5, 27, ...)``; a scene without a name says the name is missing (not ``= None``)."""
    import datetime

    msgs = problems({"scene": {"duration_s": datetime.datetime(1979, 5, 27, 7, 32, tzinfo=datetime.timezone.utc)}})
    text = "\n".join(msgs)
    assert "scene.duration_s = 1979-05-27T07:32:00+00:00: must be a number" in text and "datetime." not in text
    assert "scene.name is missing: a name of 1 to 100 ASCII letters" in text


def test_a_drop_that_would_push_the_skin_onto_the_core_is_refused_naming_the_stimulus_and_that_fingers_gap():
    """A scene's sphere_drop deeper than the fluid over the core is refused naming the stimulus and how deep it
    would go; D's heaviest sphere from the highest height allowed (10 m: 0.9 mm) is taken; a finger with a thicker
    fluid layer takes the heavy drop."""
    heavy = {"kind": "sphere_drop", "mass_mg": 10000, "height_m": 0.07, "at_s": 0.3}
    (msg,) = problems({**MINIMAL, "stimulus": [heavy]})
    assert msg.startswith("stimulus[0]: a 10000 mg sphere from 0.07 m") and "past the 1.5 mm of fluid" in msg
    ok = parse_scene({**MINIMAL, "stimulus": [{"kind": "sphere_drop", "sphere": "5/64 in aluminum bearing",
                                               "height_m": 10.0, "at_s": 0.3}]})
    assert isinstance(ok.stimuli[0], SphereDrop)
    thick = parse_scene({**MINIMAL, "sensor": {"resting_gap_mm": 2.0}, "stimulus": [heavy]})
    assert isinstance(thick.stimuli[0], SphereDrop)


def test_two_fingers_given_one_unit_are_refused_naming_both_and_nominal_twins_are_taken():
    """A unit is one real device with one serial: sensor 2 given sensor 1's unit (as a seed or as its serial), or
    sensors 2 and 3 sharing one, is refused naming both; fingers of the nominal unit (each keeps its port's default
    serial) and fingers of different units are taken."""
    base = {**MINIMAL, "sensor": {"unit": 17}}
    (msg,) = problems({**base, "sensors": [{"index": 2, "unit": "BTU0000000000017"}]})
    assert msg == ("sensors[0].unit: sensor 2 is given unit 17 (serial BTU0000000000017), already sensor 1's "
                   "([sensor]): a unit is one real device, so each finger needs its own (another seed or serial)")
    (msg,) = problems({**base, "sensors": [{"index": 3, "unit": 5}, {"index": 2, "unit": 5}]})
    assert msg.startswith("sensors[0].unit: sensor 3 is given unit 5") and "already sensor 2's (sensors[1])" in msg
    parse_scene({**MINIMAL, "sensors": [{"index": 2}, {"index": 3}]})
    parse_scene({**base, "sensors": [{"index": 2, "unit": 18}, {"index": 3, "unit": "BTU0000000000019"}]})
