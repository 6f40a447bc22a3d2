"""Thermal contact of a commanded finger (a rig's CommandedMotion): touching while its commanded depth is > 0,
read only as far as the sensor has been asked for, independent of block size, and right in a copy of the sensor."""

import copy

import numpy as np
import pytest

from emulator import channels as ch
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.sliding import CommandedMotion
from emulator.stimuli import AmbientStep
from emulator.texture import Texture
from emulator.skin import contact_patch_area_m2
from emulator.thermal import ThermalNetwork, live_patch_area_m2, shared_network
from emulator.thermal import material as thermal_material

pytestmark = pytest.mark.unit

TDC, TAC, PDC = ch.TDC, ch.TAC, ch.PDC


def flat(material: str) -> Texture:
    """A flat, hard surface of thermal ``material`` (only the material differs between calls)."""
    return Texture(1101, "flat", "test", rms_height_m=0.01e-6, correlation_length_m=50e-6, hurst=0.8, mu_static=1.0,
                   mu_kinetic=0.8, modulus_Pa=70e9, material=material, seed=3)


def lowered(material: str = "glass") -> CommandedMotion:
    """A finger 0.2 mm above the surface lowered at 1 mm/s from 0.1 s, stopped at 1.5 s (1.2 mm deep, about
    0.6 N on a hard flat), slid 3 cm at 5 cm/s, lifted at 5 mm/s from 3.5 s: every command given in advance."""
    m = CommandedMotion(flat(material), max_travel_m=0.05, depth_m=-0.2e-3)
    m.move_finger(0.1 - m.latency_s, 1e-3)
    m.move_finger(1.5 - m.latency_s, 0.0)
    m.move_stage(1.8 - m.latency_s, 0.05)
    m.move_stage(2.4 - m.latency_s, 0.0)
    m.move_finger(3.5 - m.latency_s, -5e-3)
    return m


def frame_codes(sensor: Sensor, t_end: float, read_s: float, channels=(TDC, TAC, PDC)) -> np.ndarray:
    """Codes of ``channels`` every 10 ms up to ``t_end`` (s), asked for ``read_s`` of frames at a time."""
    times = np.arange(0.0, t_end, 0.01)
    chans = np.tile(channels, times.size)
    tt = np.repeat(times, len(channels)) + np.tile(np.arange(len(channels)) * 1e-4, times.size)
    parts = np.array_split(np.arange(tt.size), max(1, int(round(t_end / read_s))))
    return np.concatenate([sensor.sample(chans[i], tt[i]) for i in parts]).reshape(times.size, len(channels))


def test_the_commanded_finger_cools_the_fingertip_in_the_order_of_the_surfaces_effusivity():
    """Aluminum draws heat faster than glass, glass than polystyrene foam: TDC falls and TAC goes below its bias
    in that order (noise off: the analog values)."""
    t = np.array([0.25, 3.5, 4.5])
    drop = {}
    for material in ("aluminum", "glass", "polystyrene foam"):
        sensor = Sensor(stimuli=[lowered(material)], channels_read=("TDC", "TAC"), noise=NoiseSources.none())
        v = sensor.analog(np.tile([TDC, TAC], t.size), np.repeat(t, 2)).reshape(t.size, 2)
        assert v[0, 1] == pytest.approx(1.65, abs=1e-6)  # above the surface: TAC at its bias
        drop[material] = (v[0, 0] - v[2, 0], 1.65 - v[1, 1])  # TDC fall by 4.5 s, TAC below bias at 3.5 s (V)
    assert drop["aluminum"][0] > drop["glass"][0] > 10 * drop["polystyrene foam"][0] > 0
    assert drop["aluminum"][1] > drop["glass"][1] > 10 * drop["polystyrene foam"][1] > 0
    assert drop["glass"][1] > 3e-3  # about 4 TAC counts


def test_a_finger_above_the_surface_changes_nothing_thermal():
    """Never reaching the surface, the commanded finger leaves TDC and TAC bit for bit as a sensor whose network
    runs with no contact at all (a far ambient step builds it), on glass as on aluminum."""
    reference = frame_codes(Sensor(stimuli=[AmbientStep(1e6, 25.0)], channels_read=("TDC", "TAC"), seed=5), 3.0,
                            0.5, (TDC, TAC))
    for material in ("glass", "aluminum"):
        hover = CommandedMotion(flat(material), depth_m=-1e-3)
        hover.move_finger(0.2, 0.5e-3)  # lowered 0.5 mm, still 0.5 mm above the surface
        hover.move_finger(1.2, 0.0)
        sensor = Sensor(stimuli=[hover], channels_read=("TDC", "TAC"), seed=5)
        assert sensor.thermal is not None  # the live contact builds the network
        np.testing.assert_array_equal(frame_codes(sensor, 3.0, 0.5, (TDC, TAC)), reference)


def test_codes_do_not_depend_on_block_size_or_on_how_reads_are_cut():
    a = frame_codes(Sensor(stimuli=[lowered()], channels_read=("TDC", "TAC", "PDC"), seed=7, block_s=0.05), 5.0,
                    0.13)
    b = frame_codes(Sensor(stimuli=[lowered()], channels_read=("TDC", "TAC", "PDC"), seed=7, block_s=2.0), 5.0, 1.0)
    c = frame_codes(Sensor(stimuli=[lowered()], channels_read=("TDC", "TAC", "PDC"), seed=7, block_s=0.37), 5.0,
                    5.0)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, c)
    t = np.arange(0.0, 5.0, 0.01)
    assert a[t < 0.3, 1].mean() - a[(t > 3.0) & (t < 3.5), 1].mean() > 2.0  # TAC counts: the contact mattered


def test_reading_TDC_fixes_the_motion_only_through_the_instants_read():
    """The thermal network reads the finger's depth only at instants already asked for: a command taking effect
    after them is accepted, one reaching back into them is refused, as without the thermal model."""
    motion = CommandedMotion(flat("glass"), depth_m=-0.2e-3)
    motion.move_finger(0.0, 1e-3)  # touches at 0.22 s
    sensor = Sensor(stimuli=[motion], channels_read=("TDC",), seed=1)
    assert sensor.thermal is not None and not sensor.nodes  # only the thermal network reads the motion
    sensor.sample(np.full(3, TDC), np.array([0.5, 1.0, 2.005]))
    with pytest.raises(ValueError, match="already computed"):
        motion.move_finger(1.99 - motion.latency_s, 0.0)
    motion.move_finger(2.01 - motion.latency_s, 0.0)  # after everything read: accepted
    assert sensor.sample(np.array([TDC]), np.array([2.5])).shape == (1,)


def test_a_copy_of_the_sensor_reads_its_own_copy_of_the_motion():
    """The rig snapshots its run (deepcopy) and goes back: the copy's thermal contact must follow the copy's
    commands.  The copy stops the finger at 1 s, the original keeps lowering; the copy then reads as a fresh
    sensor given the copy's commands."""

    def run(stop: bool, copy_at_s: float | None):
        m = CommandedMotion(flat("glass"), depth_m=-0.2e-3)
        m.move_finger(0.0, 1e-3)
        s = Sensor(stimuli=[m], channels_read=("TDC", "TAC"), seed=3)
        first = frame_codes(s, 0.9, 0.9, (TDC, TAC))
        if copy_at_s is not None:
            s, m = copy.deepcopy((s, m))
        if stop:
            m.move_finger(1.0 - m.latency_s, 0.0)
        times = np.arange(0.9, 3.0, 0.01)
        rest = s.sample(np.tile([TDC, TAC], times.size), np.repeat(times, 2) + np.tile([0, 1e-4], times.size))
        return np.concatenate([first.ravel(), rest])

    fresh_stopped, copy_stopped, original_lowering = run(True, None), run(True, 0.9), run(False, None)
    np.testing.assert_array_equal(copy_stopped, fresh_stopped)
    assert not np.array_equal(copy_stopped, original_lowering)


def test_a_planned_contact_never_takes_a_live_patchs_discretization():
    """Models of the same parameters share one network; a live patch (its own expm) of the same material and area
    as a planned contact (a 1 N slide: radius 2.5 mm, exactly 50 rounding steps) must not stand in for it, so a
    scripted scene's codes do not depend on a rig trial run before it in the process."""
    p = SensorParams()
    glass, area = thermal_material("glass"), float(contact_patch_area_m2(1.0, p.contact_radius_at_1N_m))
    assert float(live_patch_area_m2(np.array([1.0]), p)[0]) == pytest.approx(area, rel=1e-12)
    net = shared_network(p)
    net.discrete((glass, area), 0.01, live=True)
    for planned, fresh in zip(net.discrete((glass, area), 0.01), ThermalNetwork(p).discrete((glass, area), 0.01)):
        np.testing.assert_array_equal(planned, fresh)


def test_the_live_contact_builds_the_network_only_for_thermal_or_pressure_reads():
    def built(channels):
        return Sensor(stimuli=[lowered()], channels_read=channels).thermal is not None

    assert not built(("E1", "E7"))  # electrodes only: no thermal network, the motion is not read for it
    assert built(("TAC",)) and built(("PDC",))  # PDC: the core temperature drives the bridge's drift


def test_the_inputs_of_many_steps_at_once_are_each_steps_own():
    """(derived) :meth:`ThermalModel.inputs_at` (the one rule for the heater and the ambient, every path's) equals the
    written-out rule instant by instant, at, just before and around a power-on, ambient steps and a heater failure:
    no heater before power-on or from the failure on, each ambient step from its instant on."""
    from emulator.thermal import ThermalEvents, ThermalModel

    events = ThermalEvents([], power_on_s=0.5, ambient_steps=((0.3, 30.0), (0.7, 18)), heater_failed_s=0.9)
    model = ThermalModel(SensorParams(), events, seed=1)
    events_s = [0.3, 0.5, 0.7, 0.9]
    t = np.sort(np.concatenate([np.arange(0.0, 1.2, 0.01), events_s, np.nextafter(events_s, 0)]))
    heater, ambient = (a.tolist() for a in model.inputs_at(t))
    room = SensorParams().ambient_temperature_C
    assert heater == [model.heater_W if 0.5 <= x < 0.9 else 0.0 for x in t.tolist()]
    assert ambient == [18 if x >= 0.7 else 30.0 if x >= 0.3 else room for x in t.tolist()]
    assert model.heater_W > 0
    failed = ThermalModel(SensorParams(), ThermalEvents([]), seed=1, faults={"heater_failed": True})
    assert failed.inputs_at(t)[0].tolist() == [0.0] * t.size


def test_one_column_of_the_thermal_outputs_is_that_column_of_all_three():
    """:meth:`ThermalModel.value_at` gives :meth:`values_at`'s column, bit for bit, for a live contact."""
    a = Sensor(stimuli=[lowered()], channels_read=("TDC", "TAC", "PDC"), seed=7).thermal
    b = Sensor(stimuli=[lowered()], channels_read=("TDC", "TAC", "PDC"), seed=7).thermal
    for t0 in (0.0, 1.3, 2.0, 4.1):
        t = t0 + np.arange(0.0, 0.5, 1e-3)
        every = a.values_at(t)
        for column in range(3):
            np.testing.assert_array_equal(b.value_at(t, column), every[:, column])


@pytest.mark.parametrize("name", ["aluminum", "glass", "polyurethane foam"])
def test_compiled_steps_are_numpys_steps_bit_for_bit(name):
    """The live network's stepwise runs (compiled) give numpy's Φ @ x + Γu step by step, to the bit, on the network's
    own discretizations (the same BLAS product is called; a machine where it is not would fail here)."""
    from emulator.thermal import _steps

    net = shared_network(SensorParams())
    rng = np.random.default_rng(4)
    for area in np.geomspace(1e-7, 5e-5, 12):
        Phi, Gam = net.discrete((thermal_material(name), float(area)), 0.01, True)
        gu = Gam @ np.array([0.3, 22.0, 25.0, 1e-5])
        x = 20.0 + 15.0 * rng.random(net.n)
        expected = np.empty((40, net.n))
        y = x
        for i in range(40):
            y = Phi @ y + gu
            expected[i] = y
        got = np.empty((40, net.n))
        last = _steps(np.ascontiguousarray(Phi), x, gu, got)
        np.testing.assert_array_equal(got, expected)
        np.testing.assert_array_equal(last, expected[-1])


def test_the_touches_of_many_steps_at_once_are_the_first_touching_contact_instant_by_instant():
    """:meth:`ThermalModel.touches` (the live network's steps, all at once): per instant the first contact touching
    then (overlapping planned contacts, a live one whose load is zero part of the time), its area (m²), or None."""
    from emulator.thermal import ThermalContact, ThermalEvents, ThermalModel

    glass, foam = thermal_material("glass"), thermal_material("polyurethane foam")
    live = ThermalContact(0.2, 1.0, glass, 25.0, load_N=lambda t: np.where(t < 0.6, 0.0, 0.5 + t))
    contacts = [ThermalContact(0.1, 0.4, foam, 30.0, area_m2=2e-5), live, ThermalContact(0.3, 0.8, glass, 20.0, 1e-5)]
    model = ThermalModel(SensorParams(), ThermalEvents(contacts), seed=1)
    t = np.arange(0.0, 1.2, 0.01)
    got = model.touches(t)
    for when, touch in zip(t.tolist(), got):
        first = next((i for i, c in enumerate(contacts) if c.start_s <= when < c.end_s and
                      (c.planned or live.load_N(np.array([when]))[0] > 0)), None)
        if first is None:
            assert touch is None
            continue
        c = contacts[first]
        area = c.area_m2 if c.planned else float(live_patch_area_m2(c.load_N(np.array([when])), model.p)[0])
        assert touch == (first, area)
    assert {None if g is None else g[0] for g in got} == {None, 0, 1, 2}


def test_a_steps_contiguous_response_is_the_discretization_remembered():
    """:meth:`ThermalNetwork.step_response` is :meth:`ThermalNetwork.discrete` to the bit, Φ C-contiguous, and the
    same arrays when asked again (no contact, a planned and a live patch; one patch both planned and live: its two
    discretizations differ in the last bits, and each is its own)."""
    net = shared_network(SensorParams())
    aluminum = (thermal_material("aluminum"), 7.1e-6)
    glass = (thermal_material("glass"), 3e-6)
    for contact, live in ((None, False), (glass, False), (aluminum, True), (aluminum, False)):
        Phi, Gam = net.step_response(contact, 0.01, live)
        Phi_d, Gam_d = net.discrete(contact, 0.01, live)
        assert Phi.flags.c_contiguous
        np.testing.assert_array_equal(Phi, Phi_d)
        np.testing.assert_array_equal(Gam, Gam_d)
        again = net.step_response(contact, 0.01, live)
        assert again[0] is Phi and again[1] is Gam


def test_the_step_table_holds_each_contacts_step_response_to_the_bit():
    """(consistency) :meth:`ThermalNetwork.step_table`'s rows are :meth:`ThermalNetwork.step_response`'s Φ and Γ to
    the bit (nothing touching, live and planned patches; a patch both live and planned gets two rows), one row per
    distinct contact, and rows added later replace the stacks without editing the ones handed out."""
    net = shared_network(SensorParams())
    glass, aluminum = thermal_material("glass"), thermal_material("aluminum")
    contacts = [None, (glass, 3e-6, True), (aluminum, 7.1e-6, True), (glass, 3e-6, False), (glass, 3e-6, True)]
    phis, gams, rows = net.step_table(contacts, 0.01)
    for c, r in zip(contacts, rows.tolist()):
        Phi, Gam = net.step_response(None if c is None else c[:2], 0.01, c is not None and c[2])
        np.testing.assert_array_equal(phis[r], Phi)
        np.testing.assert_array_equal(gams[r], Gam)
    assert rows[1] == rows[4] and len(set(rows.tolist())) == 4
    before = phis.copy()
    more, _, rows_more = net.step_table([(glass, 3e-6, True), (aluminum, 1.3e-5, True)], 0.01)
    np.testing.assert_array_equal(phis, before)
    assert rows_more[0] == rows[1]
    np.testing.assert_array_equal(more[rows_more[1]], net.step_response((aluminum, 1.3e-5), 0.01, True)[0])


def test_the_compiled_runs_are_numpys_steps_run_by_run():
    """(consistency) :func:`emulator.thermal._step_runs` — the live network's stepwise runs in one compiled pass —
    gives numpy's x ← Φ x + Γu step by step with each run's own Φ and u (heater, ambient, the touched object's
    temperature or the ambient, self-heating), to the bit, a newly touched object's layers set to its temperature
    before its run's first step (and not again while it stays touched)."""
    from emulator.thermal import _step_runs

    net = shared_network(SensorParams())
    glass = thermal_material("glass")
    contacts = [None, (glass, 3e-6, True), (glass, 5e-6, True), None, (glass, 5e-6, True)]
    phis, gams, rows = net.step_table(contacts, 0.01)
    bounds = np.array([0, 3, 4, 9, 11, 16])
    heater = np.full(16, 0.3)
    ambient = np.r_[np.full(9, 22.0), np.full(7, 21.0)]
    index = np.repeat([-1, 0, 0, -1, 0], np.diff(bounds))
    temperature, p_self = np.array([25.0]), 1e-5
    x = 20.0 + 15.0 * np.random.default_rng(2).random(net.n)
    expected, y = np.empty((16, net.n)), x
    for r, arrive in enumerate([False, True, False, False, True]):
        j = bounds[r]
        if arrive:
            y = y.copy()
            y[4:] = 25.0
        u = np.array([heater[j], ambient[j], 25.0 if index[j] >= 0 else ambient[j], p_self])
        for i in range(j, bounds[r + 1]):
            y = phis[rows[r]] @ y + gams[rows[r]] @ u
            expected[i] = y
    got = np.empty((16, net.n))
    last = _step_runs(phis, gams, rows, bounds, heater, ambient, index, temperature, p_self, -1, x, got)
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal(last, expected[-1])


def test_expm_by_products_equals_scipys_on_the_networks_own_matrices():
    """The live contact's exp(A·dt) by scaling, squaring and a degree-12 Taylor series equals scipy's Padé expm on
    the network's matrices for every material, dt 1 ms to 10 s and a random stiff matrix, to rounding: 1e-13 ×
    ‖A·dt‖₁ of the largest entry (the squarings multiply both methods' rounding; measured ≤ 2e-15 × ‖A·dt‖₁) — a
    Taylor series cut short (a mutation hunt: 4 terms) is off by ~1e-5."""
    from scipy.linalg import expm

    from emulator.params import SensorParams
    from emulator.thermal import MATERIALS, ThermalNetwork, expm_products

    net = ThermalNetwork(SensorParams())
    mats = [net.matrices(None)[0]] + [net.matrices((m, 1e-4))[0] for m in MATERIALS.values()]
    rng = np.random.default_rng(2)
    mats.append(rng.normal(size=(8, 8)) * np.logspace(-3, 3, 8))
    for A in mats:
        for dt in (1e-3, 0.01, 0.1, 1.0, 10.0):
            ref = expm(A * dt)
            tol = 1e-13 * max(1.0, np.abs(A * dt).sum(axis=0).max()) * max(1.0, np.max(np.abs(ref)))
            assert np.max(np.abs(expm_products(A * dt) - ref)) <= tol


def test_the_live_patch_radius_is_rounded_to_the_nearest_step():
    """live_patch_area_m2 rounds the Hertz radius a₁·N^(1/3) to the nearest 50 µm (not down): loads whose radius lies
    0.3 and 0.7 of a step above a whole number of steps give that number and the next (a floor biased every patch
    small by up to a step)."""
    from emulator.params import SensorParams
    from emulator.thermal import PATCH_RADIUS_STEP_M, live_patch_area_m2

    p = SensorParams()
    for steps, frac, expected in ((40, 0.3, 40), (40, 0.7, 41), (80, 0.7, 81)):
        load = ((steps + frac) * PATCH_RADIUS_STEP_M / p.contact_radius_at_1N_m) ** 3
        area = float(live_patch_area_m2(np.array([load]), p)[0])
        assert area == pytest.approx(np.pi * (expected * PATCH_RADIUS_STEP_M) ** 2, rel=1e-12), (steps, frac)


def test_a_touch_and_a_slide_warm_the_object_over_their_contact_areas():
    """The thermal contact of a touch is its indenter's disc, π r² (a 3 mm indenter: 28.3 mm²), and a slide's the
    skin's patch under its force, π (a_1N·F^(1/3))² (skin.contact_patch_area_m2) — not the slide's at 1 N, nor a
    radius left unsquared; the thermal model sees exactly these (derived, D's thermal contact over the area touched)."""
    from emulator.sliding import Slide
    from emulator.stimuli import Touch

    p = SensorParams()
    smooth = Texture(903, "smooth", "test", rms_height_m=0.0, correlation_length_m=100e-6, hurst=0.8, mu_static=1.0,
                     mu_kinetic=0.9, material="aluminum")
    s = Sensor(p, [Touch(0.1, 1.0, material="glass", indenter_radius_mm=3.0), Slide(4.0, smooth, 2.0, 0.01, 0.01)],
               channels_read=["TDC"])
    touch, slide = s.thermal.events.contacts
    assert touch.area_m2 == pytest.approx(np.pi * 3e-3 ** 2, rel=1e-12)
    assert slide.area_m2 == pytest.approx(np.pi * (p.contact_radius_at_1N_m * 2.0 ** (1 / 3)) ** 2, rel=1e-12)
