"""Inputs are checked where they are made: a stimulus with a NaN, infinite or negative value where that is not
physical, an SPI fault outside its range, or a bench with a sensor count the bridge firmware and the Cheetah
adapter cannot address, is a ValueError naming the field, the value and what is allowed — never a stimulus that
silently produces nothing or a numpy overflow later."""

import dataclasses

import pytest

from emulator.spi.model import Faults
from emulator.stimuli import (AmbientStep, HeaterFailure, PowerOn, Press, PressureCalibrator, SphereDrop, Tap, Touch,
                              Vibration)

NAN, INF = float("nan"), float("inf")

#: (what is made, the field named in the error, a word of the allowed range)
BAD_STIMULI = [
    (lambda: Tap(0.1, NAN), "Tap.peak_N", "≥ 0"),
    (lambda: Tap(0.1, -3.0), "Tap.peak_N", "≥ 0"),
    (lambda: Tap(NAN, 1.0), "Tap.time_s", "≥ 0"),
    (lambda: Tap(-0.1, 1.0), "Tap.time_s", "≥ 0"),
    (lambda: Tap(0.1, 1.0, 0.0), "Tap.duration_s", "> 0"),
    (lambda: Tap(0.1, "1"), "Tap.peak_N", "finite number"),
    (lambda: Tap(0.1, True), "Tap.peak_N", "finite number"),
    (lambda: Press(0.1, INF), "Press.force_N", "≥ 0"),
    (lambda: Press(0.1, 1.0, ramp_s=0.0), "Press.ramp_s", "> 0"),
    (lambda: Press(0.1, 1.0, hold_s=-1.0), "Press.hold_s", "≥ 0"),
    (lambda: Touch(0.1, -1.0), "Touch.force_N", "≥ 0"),
    (lambda: Touch(0.1, 1.0, x_mm=NAN), "Touch.x_mm", "finite number"),
    (lambda: Touch(0.1, 1.0, x_mm=8.0), "Touch.x_mm", "from -20 to 5"),  # beyond the tip's apex: no skin there
    (lambda: Touch(0.1, 1.0, electrode="E42"), "Touch.electrode", "E1..E24"),  # had been taken when no E was read
    (lambda: Touch(0.1, 1.0, electrode="PDC"), "Touch.electrode", "E1..E24"),
    (lambda: Touch(0.1, 1.0, electrode=["E1"]), "Touch.electrode", "E1..E24"),  # (had been a TypeError: unhashable)
    (lambda: Touch(0.1, 1.0, indenter_radius_mm=0.0), "Touch.indenter_radius_mm", "> 0"),
    (lambda: Touch(0.1, 1.0, tangential_N=INF), "Touch.tangential_N", "finite number"),
    (lambda: Touch(0.1, 1.0, material="aluminum", object_temperature_C=-300.0), "Touch.object_temperature_C",
     "> -273.15"),
    (lambda: SphereDrop(0.1, -1e-6), "SphereDrop.mass_kg", "> 0"),
    (lambda: SphereDrop(0.1, 1e-6, restitution=1.5), "SphereDrop.restitution", "from 0 to 1"),
    (lambda: SphereDrop(NAN, 1e-6), "SphereDrop.time_s", "≥ 0"),
    (lambda: Vibration(0.0, 1.0, -1e-6, 100.0), "Vibration.amplitude_m", "≥ 0"),
    (lambda: Vibration(0.0, 1.0, 1e-6, 0.0), "Vibration.f_start_Hz", "> 0"),
    (lambda: Vibration(0.0, 1.0, 1e-6, 100.0, f_stop_Hz=-5.0), "Vibration.f_stop_Hz", "> 0"),
    (lambda: Vibration(0.0, 0.0, 1e-6, 100.0), "Vibration.duration_s", "> 0"),
    (lambda: PressureCalibrator(0.0, 1.0, offset_Pa=NAN), "PressureCalibrator.offset_Pa", "finite number"),
    (lambda: PressureCalibrator(0.0, 1.0, amplitude_Pa=-1.0), "PressureCalibrator.amplitude_Pa", "≥ 0"),
    (lambda: PressureCalibrator(0.0, 1.0, fade_s=-0.1), "PressureCalibrator.fade_s", "≥ 0"),
    (lambda: AmbientStep(1.0, NAN), "AmbientStep.temperature_C", "> -273.15"),
    (lambda: AmbientStep(-1.0, 20.0), "AmbientStep.at_s", "≥ 0"),
    (lambda: PowerOn(INF), "PowerOn.at_s", "≥ 0"),
    (lambda: HeaterFailure(NAN), "HeaterFailure.at_s", "≥ 0"),
]


@pytest.mark.parametrize("make,field,allowed", BAD_STIMULI, ids=[f"{f}-{i}" for i, (_, f, _a) in
                                                                  enumerate(BAD_STIMULI)])
def test_a_stimulus_with_an_impossible_value_is_refused_naming_field_value_and_range(make, field, allowed):
    with pytest.raises(ValueError) as e:
        make()
    message = str(e.value)
    assert message.startswith(f"{field} = "), message
    assert allowed in message, message


def test_the_message_shows_the_value():
    with pytest.raises(ValueError, match=r"Tap\.peak_N = -3\.0: must be a finite number ≥ 0"):
        Tap(0.1, -3.0)


def test_a_touch_with_an_object_temperature_but_no_material_is_refused():
    """A scene refuses it; in Python (the plugin's ``stimuli=``) the touch was made and exchanged no heat: a cold
    contact that never cooled the finger."""
    with pytest.raises(ValueError, match=r"Touch\.object_temperature_C = 5\.0 needs a material"):
        Touch(0.1, 1.0, object_temperature_C=5.0)
    assert Touch(0.1, 1.0, material="glass", object_temperature_C=5.0).material == "glass"


def test_good_stimuli_are_still_made():
    """Boundary values that are physical (zero force, zero hold, no fade, restitution 1, an optional left out)."""
    made = [Tap(0.0, 0.0), Press(0.0, 0.0, 1e-3, 0.0), Touch(0.3, 1.0, 0.2, 0.6, electrode="E17"),
            Touch(0.0, 1.0, x_mm=-20.0, angle_deg=-180.0, tangential_N=-2.0, material="aluminum",
                  object_temperature_C=-40.0),
            SphereDrop(0.4, 4e-6, restitution=1.0), Vibration(0.0, 1.0, 0.0, 1.0, None, fade_s=0.0),
            PressureCalibrator(0.0, 1.0, offset_Pa=-5e4), AmbientStep(1.0, -10.0), PowerOn(), HeaterFailure(2.0)]
    assert len(made) == 10
    assert Tap(0.1, 1.0).cumulative(1.0) == pytest.approx(0.015)


def test_the_place_is_declared_once_and_given_by_keyword_only():
    """Tap and Press take their place (x_mm, angle_deg, electrode, indenter_radius_mm) from one declaration,
    PlacedForce's, by keyword only; their own fields stay positional as before (a place given positionally is a
    TypeError, not a value landing in the wrong field — a Touch's fifth positional had been x_mm)."""
    from emulator.stimuli import PlacedForce

    place = ("x_mm", "angle_deg", "electrode", "indenter_radius_mm")
    for cls in (Tap, Press):
        assert not set(place) & set(vars(cls).get("__annotations__", {})), cls.__name__
        fields = {f.name: f for f in dataclasses.fields(cls)}
        assert all(fields[k].kw_only for k in place)
    assert set(place) <= set(vars(PlacedForce)["__annotations__"])
    assert all(f.kw_only for f in dataclasses.fields(Touch) if f.name not in ("start", "force_N", "ramp_s", "hold_s"))
    tap, press = Tap(0.1, 2.0, 0.05, electrode="E3"), Press(0.2, 1.5, 0.1, 0.4, x_mm=-3.0, angle_deg=10.0)
    assert (tap.time_s, tap.peak_N, tap.duration_s, tap.electrode) == (0.1, 2.0, 0.05, "E3")
    assert (press.start, press.force_N, press.ramp_s, press.hold_s, press.x_mm, press.angle_deg) == \
        (0.2, 1.5, 0.1, 0.4, -3.0, 10.0)
    for make in (lambda: Tap(0.1, 2.0, 0.05, -3.0), lambda: Press(0.2, 1.5, 0.1, 0.4, -3.0),
                 lambda: Touch(0.2, 1.5, 0.1, 0.4, -3.0)):
        with pytest.raises(TypeError, match="positional argument"):
            make()


def test_scenes_and_the_fault_campaign_still_build_their_stimuli():
    from bench.campaigns.faults import SCENES
    from bench.scenes.scene import load_scene
    from bench.paths import REPO

    assert all(isinstance(s, list) for s in SCENES.values())
    for path in sorted((REPO / "fixtures" / "scenes").glob("*.toml")):
        load_scene(path)


# --- SPI faults -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kw,field,allowed", [
    (dict(miso_flip_bit=99), "miso_flip_bit", "0 to 15"),
    (dict(miso_flip_bit=-1), "miso_flip_bit", "0 to 15"),
    (dict(mosi_flip_bit=16), "mosi_flip_bit", "0 to 15"),
    (dict(mosi_flip_bit=2.0), "mosi_flip_bit", "0 to 15"),
    (dict(miso_flip_bit=True), "miso_flip_bit", "0 to 15"),
    (dict(miso_stuck=2), "miso_stuck", "0 or 1"),
    (dict(miso_stuck=-1), "miso_stuck", "0 or 1"),
    (dict(slow_response="yes"), "slow_response", "True or False"),
    (dict(bad_parity=1), "bad_parity", "True or False"),
])
def test_an_spi_fault_out_of_range_is_refused(kw, field, allowed):
    with pytest.raises(ValueError) as e:
        Faults(**kw)
    assert str(e.value).startswith(f"Faults.{field} = {kw[field]!r}: ") and allowed in str(e.value), str(e.value)


def test_spi_faults_in_range_are_made():
    for k in (0, 15):
        assert Faults(miso_flip_bit=k).miso_flip_bit == k and Faults(mosi_flip_bit=k).mosi_flip_bit == k
    assert Faults(miso_stuck=0).miso_stuck == 0 and Faults(miso_stuck=1).miso_stuck == 1
    assert Faults(bad_parity=True, slow_response=True).any and not Faults().any


# --- sensor counts of the host benches ------------------------------------------------------------------------
@pytest.mark.parametrize("n", [0, 6, 7, -1, 2.5, True, "3"])
def test_a_bench_with_an_impossible_sensor_count_is_refused(n):
    """FirmwareBench and CheetahBench take 1..MAX_SENSORS sensors, as the CLI does (--sensors 1 to 5); the check
    comes before anything is built or opened."""
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.cheetah_server import CheetahBench
    from bench.scenes.limits import MAX_SENSORS

    for bench in (FirmwareBench, CheetahBench):
        with pytest.raises(ValueError, match=rf"n_sensors = {n!r}: must be a whole number from 1 to {MAX_SENSORS}"):
            bench(n)


def test_a_bench_with_sensors_numbered_outside_1_to_5_is_refused():
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.cosim import default_sensors

    sensors = default_sensors(1)
    with pytest.raises(ValueError, match=r"sensors numbered \[9\]: sensor numbers are 1 to 5"):
        FirmwareBench(sensors={9: sensors[1]})


def test_nan_checks_cover_every_numeric_field():
    """Every float field of the checked stimuli has a limit (a new field without one would go unchecked)."""
    import dataclasses
    import typing

    for cls in (Tap, Press, Touch, SphereDrop, Vibration, PressureCalibrator, AmbientStep, PowerOn, HeaterFailure):
        hints = typing.get_type_hints(cls)
        numeric = {f.name for f in dataclasses.fields(cls) if hints[f.name] in (float, float | None)}
        assert numeric <= set(cls.LIMITS), f"{cls.__name__}: unchecked {sorted(numeric - set(cls.LIMITS))}"


@pytest.mark.parametrize("kw, needle", [
    (dict(block_s=float("nan")), "block_s = nan: must be a finite number > 0"),  # had been "cannot convert float NaN"
    (dict(block_s=0), "block_s = 0"),
    (dict(seed=-5), "seed = -5: must be a whole number ≥ 0"),  # had been numpy's "expected non-negative integer"
    (dict(seed=2.5), "seed = 2.5: must be a whole number ≥ 0"),  # (3262.0 is one: the claims pass such seeds)
    (dict(params={"inflation_volume_mL": 0.6}), "give a SensorParams"),  # had been "unhashable type: 'dict'"
])
def test_sensor_arguments_are_refused_naming_the_argument(kw, needle):
    from emulator.sensor import Sensor

    with pytest.raises((ValueError, TypeError), match=needle):
        Sensor(**kw)


def test_a_touch_over_an_electrode_the_sensor_lacks_is_refused_also_when_no_electrode_is_read():
    """A touch over E22 on a 19-electrode sensor reading only PDC pressed somewhere unnamed: the place was checked
    only when the electrode model was built."""
    from emulator.sensor import Sensor

    for read in (["PDC"], ["E1"]):
        with pytest.raises(ValueError, match="touch over electrode 'E22': a 'biotac' sensor has E1..E19"):
            Sensor(stimuli=[Touch(0.1, 1.0, electrode="E22")], channels_read=read)
    Sensor(stimuli=[Touch(0.1, 1.0, electrode="E22")], channels_read=["PDC"], variant="biotac-sp")


def test_a_sensor_refuses_a_touch_on_the_skin_tethered_at_the_nail():
    from emulator.params import SensorParams
    from emulator.sensor import Sensor

    for angle in (121.0, -180.0, 200.0):  # 200° is -160°
        with pytest.raises(ValueError, match=f"Touch.angle_deg = {angle!r}: beyond 120° .* tethered at the nail"):
            Sensor(stimuli=[Touch(0.1, 1.0, angle_deg=angle)], channels_read=["PDC"])
    Sensor(stimuli=[Touch(0.1, 1.0, angle_deg=-120.0), Touch(0.1, 1.0, angle_deg=350.0)], channels_read=["PDC"])
    Sensor(stimuli=[Touch(0.1, 1.0, angle_deg=180.0)], params=SensorParams(free_skin_half_angle_deg=180.0))


def test_a_whole_seed_written_as_a_float_is_the_same_seed():
    """``Sensor(seed=3262.0)`` is seed 3262 (the claims' vibration sweep passes 1000 + a frequency in Hz): the
    argument check refused it for a while, stopping `claims --only vibration`."""
    import numpy as np

    from emulator.sensor import Sensor
    from emulator.stimuli import Tap

    a, b = (Sensor(stimuli=[Tap(0.01, 1.0)], seed=s) for s in (3262, 3262.0))
    t = np.arange(200) / 4400.0
    assert b.seed == 3262 and np.array_equal(a.sample(np.zeros(200, int), t), b.sample(np.zeros(200, int), t))


def _hertz_depth_m(drop) -> float:
    """Hertz's peak indentation of a rigid sphere on a soft half-space, written out here (m):
    δ = (15·m·v² / (16·E*·√R))^(2/5)."""
    m, v, R, E = drop.mass_kg, drop.impact_speed_m_per_s, drop.sphere_radius_m, drop.contact_modulus_Pa
    return (15.0 * m * v**2 / (16.0 * E * R**0.5)) ** 0.4


def test_a_drop_that_would_push_the_skin_onto_the_core_is_warned_of_by_the_sensor_with_its_own_gap():
    """A Hertz drop deeper than the fluid over the core (``resting_gap_mm``) is outside the model (the sphere would
    meet the core): a scene refuses it (bench/tests/test_scene.py); a Sensor built in Python warns, saying how deep
    (analyses probe the chain there on purpose); shallower, on a thicker fluid layer or as the legacy half-sine
    (``contact_s``: no depth), nothing is said."""
    import warnings

    from emulator.params import SensorParams
    from emulator.sensor import Sensor
    from emulator.stimuli import OutsideModelWarning, sphere_drop_on

    p = SensorParams()
    heavy = sphere_drop_on(p, 0.1, 0.01, 0.07)  # a steel sphere
    depth = _hertz_depth_m(heavy)
    assert depth > p.resting_gap_mm * 1e-3  # 10 g from 7 cm: ~1.7 mm into 1.5 mm of fluid
    with pytest.warns(OutsideModelWarning, match=rf"SphereDrop at 0\.1 s: .* indent the skin {depth * 1e3:.2f} mm, "
                                                   r"past the 1\.5 mm of fluid over the core \(resting_gap_mm\)"):
        Sensor(stimuli=[heavy], channels_read=["PDC"], params=p)
    shallower = dataclasses.replace(heavy, mass_kg=heavy.mass_kg * 0.6)  # δ ∝ m^(2/5)·R^(-1/5) ∝ m^(1/3): ×0.84
    assert _hertz_depth_m(shallower) < p.resting_gap_mm * 1e-3
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Sensor(stimuli=[heavy], channels_read=["PDC"], params=SensorParams(resting_gap_mm=depth * 1e3 * 1.01))
        Sensor(stimuli=[shallower], channels_read=["PDC"], params=p)
        Sensor(stimuli=[dataclasses.replace(heavy, contact_s=1e-3)], channels_read=["PDC"], params=p)
