"""Scene files: a touch's shear within static friction; the place of a press or a tap; a drop has none."""

import pytest

from bench.errors import SceneError
from bench.scenes.scene import parse_scene
from emulator.stimuli import Press, Tap, Touch

pytestmark = pytest.mark.unit

MINIMAL = {"scene": {"name": "t", "duration_s": 2.0}}
TOUCH = {"kind": "touch", "start_s": 0.1, "force_N": 0.5, "ramp_s": 0.2, "hold_s": 0.3}


def problems(data):
    with pytest.raises(SceneError) as e:
        parse_scene(data, source="s.toml")
    return e.value.problems


def test_a_touch_sheared_beyond_static_friction_is_refused_naming_stimulus_field_value_and_limit():
    (msg,) = problems({**MINIMAL, "stimulus": [{**TOUCH, "tangential_N": 20.0}]})
    assert msg.startswith("stimulus[0].tangential_N = 20.0: exceeds the static friction µs·force_N = 1.3 × 0.5 N = "
                          "0.65 N"), msg
    assert 'kind = "slide"' in msg
    (msg,) = problems({**MINIMAL, "stimulus": [{**TOUCH, "force_N": 0.0, "tangential_N": -0.1}]})
    assert msg.startswith("stimulus[0].tangential_N = -0.1: exceeds the static friction"), msg
    ok = parse_scene({**MINIMAL, "stimulus": [{**TOUCH, "tangential_N": -0.65}]})
    assert ok.stimuli[0].tangential_N == -0.65


def test_a_press_and_a_tap_take_a_place_and_keep_none_by_default():
    scene = parse_scene({**MINIMAL, "stimulus": [
        {"kind": "press", "start_s": 0.1, "force_N": 1.0, "ramp_s": 0.2, "hold_s": 0.3},
        {"kind": "press", "start_s": 0.1, "force_N": 1.0, "ramp_s": 0.2, "hold_s": 0.3, "electrode": "E7"},
        {"kind": "tap", "at_s": 1.5, "peak_N": 2.0, "x_mm": 3.0, "angle_deg": -20.0, "indenter_radius_mm": 2.0},
        {"kind": "tap", "at_s": 1.6, "peak_N": 2.0}]})
    bare, placed, tap, bare_tap = scene.stimuli
    assert type(bare) is Press and (bare.x_mm, bare.angle_deg, bare.electrode) == (None, None, None)
    assert type(placed) is Press and placed.electrode == "E7" and not isinstance(placed, Touch)
    assert type(tap) is Tap and (tap.x_mm, tap.angle_deg, tap.indenter_radius_mm) == (3.0, -20.0, 2.0)
    assert (bare_tap.x_mm, bare_tap.angle_deg, bare_tap.electrode) == (None, None, None)


@pytest.mark.parametrize("extra, needle", [
    ({"electrode": "E7", "x_mm": -3.0}, "stimulus[0]: give the place either as electrode"),
    ({"angle_deg": 170.0}, "stimulus[0].angle_deg = 170.0: beyond 120°"),
    ({"x_mm": 5.5}, "stimulus[0].x_mm = 5.5: allowed range is"),
    ({"electrode": "E21"}, "stimulus[0].electrode = \"E21\": sensor 1 is a \"biotac\""),
    ({"indenter_radius_mm": 3.0}, "stimulus[0].indenter_radius_mm: the indenter of a place"),
])
@pytest.mark.parametrize("kind", ["press", "tap"])
def test_a_press_or_taps_place_is_checked_as_a_touchs(kind, extra, needle):
    st = ({"kind": "press", "start_s": 0.1, "force_N": 1.0, "ramp_s": 0.2, "hold_s": 0.3} if kind == "press"
          else {"kind": "tap", "at_s": 0.5, "peak_N": 1.0})
    msgs = problems({**MINIMAL, "stimulus": [{**st, **extra}]})
    assert any(m.startswith(needle) for m in msgs), msgs


def test_a_sphere_drop_given_a_place_is_refused_saying_why():
    msgs = problems({**MINIMAL, "stimulus": [{"kind": "sphere_drop", "sphere": "1 mm steel bearing", "at_s": 0.5,
                                              "electrode": "E7"}]})
    assert any(m.startswith("stimulus[0].electrode: a sphere_drop has no place on the finger") for m in msgs), msgs


def test_a_placed_tap_shorter_than_two_electrode_steps_is_refused_naming_the_profiles_that_fit():
    """The electrodes' model samples a placed tap's force at its own rate (fast 250 Hz, default 500 Hz, reference
    2 kHz): a 5 ms tap at a place needs 8 ms on fast; default and reference take it, and a 5 ms tap with no place
    (only the fluid feels it, on the grid) is taken on fast."""
    tap = {"kind": "tap", "at_s": 0.5, "peak_N": 1.0, "duration_s": 0.005, "electrode": "E7"}
    fast = {"scene": {"name": "t", "duration_s": 2.0, "fidelity": "fast"}}
    (msg,) = problems({**fast, "stimulus": [tap]})
    assert msg == ("the stimulus starting at 0.5 s: a tap of 5 ms (duration_s) at a place is shorter than two steps "
                   "of the electrodes' model at fidelity 'fast' (250 Hz: at least 8 ms); lengthen duration_s or use "
                   "\"default\" or \"reference\""), msg
    assert parse_scene({**MINIMAL, "stimulus": [tap]}).stimuli[0].electrode == "E7"
    bare = {k: v for k, v in tap.items() if k != "electrode"}
    assert parse_scene({**fast, "stimulus": [bare]}).stimuli[0].electrode is None


def test_a_placed_press_or_touch_shorter_than_two_electrode_steps_is_refused_as_a_placed_tap_is():
    """The tap's rule on a press's whole span, 2·ramp_s + hold_s (a touch is a placed press): 1 ms ramps held 1 ms
    (3 ms) over E7 need 8 ms on fast and 4 ms on default, so only "reference" takes them; short ramps held long
    are taken (the dent is then held over many steps), and so is the short press with no place."""
    press = {"kind": "press", "start_s": 0.5, "force_N": 1.0, "ramp_s": 0.001, "hold_s": 0.001, "electrode": "E7"}
    fast = {"scene": {"name": "t", "duration_s": 2.0, "fidelity": "fast"}}
    (msg,) = problems({**fast, "stimulus": [press]})
    assert msg == ("the stimulus starting at 0.5 s: a press of 3 ms (2·ramp_s + hold_s) at a place is shorter than "
                   "two steps of the electrodes' model at fidelity 'fast' (250 Hz: at least 8 ms); lengthen "
                   "2·ramp_s + hold_s or use \"reference\""), msg
    (msg,) = problems({**fast, "stimulus": [{**TOUCH, "ramp_s": 0.001, "hold_s": 0.0}]})
    assert msg.startswith("the stimulus starting at 0.1 s: a touch of 2 ms (2·ramp_s + hold_s) at a place"), msg
    held = parse_scene({**fast, "stimulus": [{**press, "hold_s": 0.5}]}).stimuli[0]
    assert (held.ramp_s, held.electrode) == (0.001, "E7")
    bare = {k: v for k, v in press.items() if k != "electrode"}
    assert parse_scene({**fast, "stimulus": [bare]}).stimuli[0].electrode is None
