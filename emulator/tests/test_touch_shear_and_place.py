"""A touch's shear (tangent to the skin, within static friction) and the place of a press or a tap."""

import warnings

import numpy as np
import pytest

from emulator.channels import channel_index
from emulator.electrodes import CORE_RADIUS_MM, surface_point_mm
from emulator.sensor import NoiseSources, Sensor
from emulator.stimuli import TOUCH_STATIC_FRICTION, OutsideModelWarning, Press, Tap, Touch

pytestmark = pytest.mark.unit

QUIET = NoiseSources.none()
E = [f"E{n}" for n in range(1, 20)]
E_IDX = np.array([channel_index(e) for e in E])


def _contact(touch):
    return Sensor(stimuli=[touch], channels_read=["E1"], noise=QUIET).electrodes.contacts[0]


def _outward_normal(point_mm):
    """The core surface's outward unit normal at ``point_mm``: radial from the axis on the cylinder (x ≤ 0), from
    the tip's centre on the hemispherical tip (x > 0)."""
    p = np.asarray(point_mm, float)
    n = p.copy() if p[0] > 0 else np.array([0.0, p[1], p[2]])
    return n / np.linalg.norm(n)


PLACES = [dict(x_mm=-5.0, angle_deg=0.0), dict(x_mm=-12.0, angle_deg=-60.0), dict(x_mm=0.0, angle_deg=30.0),
          dict(x_mm=2.5, angle_deg=0.0), dict(x_mm=4.0, angle_deg=45.0), dict(x_mm=4.9, angle_deg=-100.0),
          dict(x_mm=5.0, angle_deg=0.0)] + [dict(electrode=e) for e in E]


@pytest.mark.parametrize("shear_angle_deg", [0.0, 45.0, 90.0, -135.0])
def test_a_touchs_shear_is_tangent_to_the_skin_at_its_place_on_the_pad_and_on_the_tip(shear_angle_deg):
    """On the hemispherical tip the pad's frame (+x, the circle's tangent) points off the surface; the shear is built
    in the skin's tangent plane wherever the touch is: unit length, dot product with the outward normal ~0."""
    for place in PLACES:
        c = _contact(Touch(0.1, 1.0, tangential_N=0.5, shear_angle_deg=shear_angle_deg, **place))
        u = np.asarray(c.shear_direction, float)
        assert np.linalg.norm(u) == pytest.approx(1.0, abs=1e-12), place
        assert abs(float(u @ _outward_normal(c.center_mm))) < 1e-12, (place, u)


def test_a_shear_at_0_deg_on_the_tip_points_along_the_meridian_toward_the_apex():
    """At 0° the shear runs toward the tip: on the tip, along the meridian through the touch, toward the apex (the
    direction in which x_mm grows along the skin); at 90° around the finger, as on the pad."""
    for x, angle in ((1.0, 0.0), (3.0, 20.0), (4.5, -40.0)):
        c = _contact(Touch(0.1, 1.0, tangential_N=0.5, x_mm=x, angle_deg=angle))
        ahead = surface_point_mm(x + 1e-4, angle) - surface_point_mm(x - 1e-4, angle)
        assert np.array(c.shear_direction) == pytest.approx(ahead / np.linalg.norm(ahead), abs=1e-6)
        side = _contact(Touch(0.1, 1.0, tangential_N=0.5, x_mm=x, angle_deg=angle, shear_angle_deg=90.0))
        around = surface_point_mm(x, angle + 1e-4) - surface_point_mm(x, angle - 1e-4)
        assert np.array(side.shear_direction) == pytest.approx(around / np.linalg.norm(around), abs=1e-9)


def test_a_shear_on_the_pad_is_the_former_direction_bit_for_bit():
    """Pad contacts (x ≤ 0) keep the direction they always had: cos φ·x̂ + sin φ·(0, cos a, sin a), exactly."""
    for place in [p for p in PLACES if p.get("x_mm", -1.0) <= 0.0]:
        for phi_deg in (0.0, 30.0, 90.0, -135.0, 180.0):
            c = _contact(Touch(0.1, 1.0, tangential_N=0.5, shear_angle_deg=phi_deg, **place))
            if c.center_mm[0] > 0.0:
                continue
            a, phi = np.arctan2(c.center_mm[1], -c.center_mm[2]), np.radians(phi_deg)
            former = np.cos(phi) * np.array([1.0, 0, 0]) + np.sin(phi) * np.array([0, np.cos(a), np.sin(a)])
            assert tuple(c.shear_direction) == tuple(former), place


def test_a_shear_beyond_static_friction_is_warned_of_naming_the_touch_field_value_and_limit():
    """No fingertip holds 20 N of shear under 0.5 N without slipping: a Sensor built in Python warns (a scene
    refuses it); at the limit µs·force_N (and below) it is taken silently."""
    with pytest.warns(OutsideModelWarning, match=r"Touch at 0\.1 s: tangential_N = 20\.0 N exceeds the static "
                                                 r"friction µs·force_N = 1\.3 × 0\.5 N = 0\.65 N.*slide"):
        Sensor(stimuli=[Touch(0.1, 0.5, tangential_N=20.0)], channels_read=["E1"])
    with pytest.warns(OutsideModelWarning, match=r"tangential_N = -1\.0 N exceeds .* = 0 N"):
        Sensor(stimuli=[Touch(0.1, 0.0, tangential_N=-1.0)], channels_read=["E1"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        limit = TOUCH_STATIC_FRICTION * 0.5
        Sensor(stimuli=[Touch(0.1, 0.5, tangential_N=limit), Touch(3.0, 0.5, tangential_N=-limit)],
               channels_read=["E1"])


def _codes(stimuli, t, channels=E_IDX):
    s = Sensor(stimuli=stimuli, channels_read=E + ["PDC"], noise=QUIET)
    return np.stack([s.sample(channels, np.full(channels.size, ti) + np.arange(channels.size) * 1e-5)
                     for ti in t]).astype(int)


T = np.array([0.05, 0.2, 0.45, 0.7, 1.0, 1.4])
ALL = np.append(E_IDX, channel_index("PDC"))


@pytest.mark.parametrize("place", [dict(electrode="E17"), dict(x_mm=2.0, angle_deg=20.0)])
def test_a_press_given_a_place_moves_the_electrodes_as_a_touch_of_that_force_there(place):
    """A press with a place is a touch without shear or object: every electrode and PDC read the same codes."""
    press = _codes([Press(0.1, 1.0, 0.2, 0.5, **place)], T, ALL)
    touch = _codes([Touch(0.1, 1.0, 0.2, 0.5, **place)], T, ALL)
    assert np.array_equal(press, touch)
    rest = _codes([], T, ALL)
    assert np.abs(press[2, :19] - rest[2, :19]).max() > 100  # held at 1 N: the place's electrodes move


def test_a_press_or_tap_without_a_place_leaves_the_electrodes_at_rest_as_before():
    """The default (no place) is unchanged: only PDC/PAC move; the electrodes read their resting codes."""
    rest = _codes([], T)
    assert np.array_equal(_codes([Press(0.1, 1.0, 0.2, 0.5)], T), rest)
    assert np.array_equal(_codes([Tap(0.4, 2.0, 0.1)], T), rest)


def test_a_tap_given_a_place_dents_its_electrode_during_the_tap_only():
    """A 2 N, 100 ms tap over E17 moves E17 at its peak (0.45 s) like a held touch would, and E17 is back near rest
    well after it (the skin's creep recovers over ~1 s: within a few codes at 1.4 s)."""
    e17 = np.array([channel_index("E17")])
    rest = _codes([], T, e17)[:, 0]
    tap = _codes([Tap(0.4, 2.0, 0.1, electrode="E17")], T, e17)[:, 0]
    assert np.array_equal(tap[:2], rest[:2])  # before the tap
    assert abs(tap[2] - rest[2]) > 100
    assert abs(tap[-1] - rest[-1]) < 0.1 * abs(tap[2] - rest[2])


@pytest.mark.parametrize("make, needle", [
    (lambda: Press(0.1, 1.0, x_mm=8.0), r"Press\.x_mm = 8\.0: must be a finite number from -20 to 5 or None"),
    (lambda: Tap(0.1, 1.0, electrode="E42"), r"Tap\.electrode = 'E42': an electrode's name"),
    (lambda: Press(0.1, 1.0, electrode="E7", x_mm=-3.0), r"Press: give the place either as electrode"),
    (lambda: Tap(0.1, 1.0, indenter_radius_mm=0.0), r"Tap\.indenter_radius_mm = 0\.0: must be a finite number > 0"),
])
def test_a_press_or_taps_place_is_checked_when_made(make, needle):
    with pytest.raises(ValueError, match=needle):
        make()


def test_a_placed_press_on_the_nail_or_on_an_electrode_the_sensor_lacks_is_refused_as_a_touch_is():
    with pytest.raises(ValueError, match=r"Press\.angle_deg = 180\.0: beyond 120°"):
        Sensor(stimuli=[Press(0.1, 1.0, angle_deg=180.0)], channels_read=["E1"])
    with pytest.raises(ValueError, match=r"tap over electrode 'E22': a 'biotac' sensor has E1\.\.E19"):
        Sensor(stimuli=[Tap(0.1, 1.0, electrode="E22")], channels_read=["PDC"])


def test_the_apex_is_on_the_finger_and_its_normal_is_plus_x():
    assert _outward_normal(surface_point_mm(CORE_RADIUS_MM, 0.0)) == pytest.approx([1.0, 0.0, 0.0])


@pytest.mark.parametrize("angle_deg", [0.0, 30.0, 80.0, 100.0, -100.0])
@pytest.mark.parametrize("shear_angle_deg", [0.0, 90.0])
def test_a_shear_at_the_apex_follows_the_touchs_own_meridian_as_just_below_it(angle_deg, shear_angle_deg):
    """At the apex (x_mm = 5) the place's point no longer tells its angle around the finger (y = z = 0, their signs
    those of zeros): the shear follows the touch's angle_deg as it does a micrometre below the apex — not the same
    direction for every angle, nor one flipped dorsal/ventral between 80° and 100°."""
    apex = _contact(Touch(0.1, 1.0, tangential_N=0.5, x_mm=CORE_RADIUS_MM, angle_deg=angle_deg,
                          shear_angle_deg=shear_angle_deg))
    below = _contact(Touch(0.1, 1.0, tangential_N=0.5, x_mm=CORE_RADIUS_MM - 1e-6, angle_deg=angle_deg,
                           shear_angle_deg=shear_angle_deg))
    assert np.array(apex.shear_direction) == pytest.approx(np.array(below.shear_direction), abs=1e-3)


def test_a_placed_tap_too_short_for_the_electrodes_model_is_warned_of_in_python_as_a_scene_refuses_it():
    """A 3 ms tap over E17 on "fast" (electrodes stepped every 4 ms) moves E17 by ~300 codes or not at all depending
    on where the steps fall (0.100 s: nothing; 0.102 s: a dent): a scene refuses it, a Python Sensor that reads an
    electrode warns (OutsideModelWarning naming the tap, its length and the least length); 8 ms is taken silently,
    and so is the short tap when no electrode is read (only the fluid's channels feel it)."""
    with pytest.warns(OutsideModelWarning, match=r"Tap at 0\.1 s: 3 ms \(duration_s\) at a place is shorter than two steps of the "
                                                 r"electrodes' model at fidelity 'fast' \(250 Hz: at least 8 ms\)"):
        Sensor(stimuli=[Tap(0.1, 2.0, 0.003, electrode="E17")], channels_read=["E17"], fidelity="fast")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Sensor(stimuli=[Tap(0.1, 2.0, 0.008, electrode="E17")], channels_read=["E17"], fidelity="fast")
        Sensor(stimuli=[Tap(0.1, 2.0, 0.003, electrode="E17")], channels_read=["PDC"], fidelity="fast")
        Sensor(stimuli=[Tap(0.1, 2.0, 0.003)], channels_read=["E17"], fidelity="fast")


def test_a_placed_press_too_short_for_the_electrodes_model_is_warned_of_as_a_placed_tap_is():
    """The same rule as a tap's, on the whole press (2·ramp_s + hold_s): on "fast" (4 ms steps) a press over E17 of
    1 ms ramps and no hold dents E17 by 410 codes or not at all as its start moves by 1 ms; a Python Sensor reading
    an electrode warns naming the press, its span's fields and the least span (8 ms), as does a touch's; 8 ms (3 ms
    ramps held 2 ms) and 1 ms ramps held 0.1 s (short ramps: only the onset's instant is quantised) are taken, and
    so is the short press with no place or no electrode read."""
    with pytest.warns(OutsideModelWarning, match=r"Press at 0\.1 s: 2 ms \(2·ramp_s \+ hold_s\) at a place is shorter "
                                                 r"than two steps of the electrodes' model at fidelity 'fast' \(250 Hz: "
                                                 r"at least 8 ms\)"):
        Sensor(stimuli=[Press(0.1, 2.0, 0.001, 0.0, electrode="E17")], channels_read=["E17"], fidelity="fast")
    with pytest.warns(OutsideModelWarning, match=r"Touch at 0\.1 s: 7 ms \(2·ramp_s \+ hold_s\) at a place"):
        Sensor(stimuli=[Touch(0.1, 2.0, 0.003, 0.001)], channels_read=["E17"], fidelity="fast")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for press in (Press(0.1, 2.0, 0.003, 0.002, electrode="E17"), Press(0.1, 2.0, 0.001, 0.1, electrode="E17")):
            Sensor(stimuli=[press], channels_read=["E17"], fidelity="fast")
        Sensor(stimuli=[Press(0.1, 2.0, 0.001, 0.0, electrode="E17")], channels_read=["PDC"], fidelity="fast")
        Sensor(stimuli=[Press(0.1, 2.0, 0.001, 0.0)], channels_read=["E17"], fidelity="fast")


def test_a_sensor_driven_outside_the_model_fails_a_test_that_does_not_ask_for_the_warning():
    """The suite's own setting (pyproject: ``filterwarnings``): an OutsideModelWarning a test does not ask for with
    ``pytest.warns`` is an error, so a test whose input left the model's range by mistake fails instead of passing
    on the model's extrapolation (four had, in test_electrode_shear)."""
    with pytest.raises(OutsideModelWarning, match="tangential_N = 20.0 N exceeds"):
        Sensor(stimuli=[Touch(0.1, 0.5, tangential_N=20.0)], channels_read=["E1"])
