"""Thermal and electrode modalities: physics, exact integration, conversions, faults, demand-driven building."""

import numpy as np
import pytest

from emulator import conversions as conv
from emulator.channels import DEFAULT_FRAME_NAMES, channel_index
from emulator.electrodes import (Contact, electrode_gaps_mm, electrode_positions_mm, surface_point_mm,
                                 surface_point_over_mm)
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.stimuli import AmbientStep, PowerOn, Touch
from emulator.thermal import CORE, MATERIALS, ThermalNetwork, tdc_volts, thermistor_ohm

pytestmark = pytest.mark.unit
QUIET = NoiseSources.none()
E = [f"E{n}" for n in range(1, 20)]
E_IDX = np.array([channel_index(e) for e in E])


def tdc_celsius(sensor, times):
    return conv.tdc_to_celsius(sensor.analog(np.full(len(times), channel_index("TDC")), times) / conv.ADC_LSB_V)


def impedances(sensor, t):
    return conv.impedance_ohm(sensor.analog(E_IDX, t + np.arange(19) * 1e-5) / conv.ADC_LSB_V)


def test_thermistor_is_470k_at_25C_and_the_divider_matches_the_published_conversion():
    assert thermistor_ohm(25.0) == pytest.approx(470e3, rel=1e-6)
    for t in (5.0, 25.0, 35.0, 60.0):
        x = float(tdc_volts(thermistor_ohm(t))) / 3.3
        assert x == pytest.approx(100e3 / (float(thermistor_ohm(t)) + 30e3), rel=1e-9)
        assert float(conv.tdc_to_celsius(x * 4095)) == pytest.approx(t, abs=1e-3)  # the formula's constants are rounded



def test_celsius_to_tdc_inverts_the_published_conversion_exactly():
    """conversions.celsius_to_tdc is the inverse of D eq. 4.4 (x = TDC/4095, T = 4025/ln((155183 − 46555x)/x) −
    273.15), solved for the code: every code maps back to itself (the TAC conversion takes its slope from it)."""
    codes = np.array([200.0, 1000.0, 2047.5, 3000.0, 3900.0])
    assert np.allclose(conv.celsius_to_tdc(conv.tdc_to_celsius(codes)), codes, rtol=1e-12, atol=0)
    temps = np.array([5.0, 25.0, 35.0, 60.0])
    assert np.allclose(conv.tdc_to_celsius(conv.celsius_to_tdc(temps)), temps, rtol=0, atol=1e-9)

def test_heater_holds_the_core_10K_above_ambient_and_warms_up_over_minutes():
    s = Sensor(stimuli=[PowerOn(0.0)], channels_read=["TDC"], noise=QUIET)
    t = np.array([0.0, 60.0, 300.0, 1200.0, 3600.0])
    temps = tdc_celsius(s, t)
    assert np.all(np.diff(temps) > 0)
    assert temps[0] == pytest.approx(25.0, abs=0.2) and temps[1] < 30.0 and temps[3] > 33.5
    assert temps[-1] == pytest.approx(tdc_celsius(Sensor(channels_read=["TDC"], noise=QUIET), [0.0])[0], abs=0.05)
    net = ThermalNetwork(SensorParams())
    A, B = net.matrices(None)
    x = np.linalg.solve(A, -B @ np.array([net.heater_power_W(), 25.0, 25.0, 0.0]))
    assert x[CORE] == pytest.approx(35.0, abs=1e-9)


def test_exact_discretization_is_stable_at_any_step_and_chunks_equal_stepping():
    net = ThermalNetwork(SensorParams())
    contact = (MATERIALS["aluminum"], 1e-4)
    for dt in (1e-4, 0.01, 1.0, 100.0, 1e4):
        Phi, _ = net.discrete(contact, dt)
        assert np.max(np.abs(np.linalg.eigvals(Phi))) < 1.0
    powers, sums = net.chunk_response(contact, 0.01, 50)
    Phi, Gam = net.discrete(contact, 0.01)
    x = np.linspace(20, 40, net.n)
    u = np.array([0.3, 25.0, 20.0, 1e-4])
    y = x.copy()
    for j in range(50):
        y = Phi @ y + Gam @ u
        assert np.allclose(powers[j] @ x + sums[j] @ u, y, atol=1e-10)


def test_an_ambient_step_moves_the_settled_temperature_and_TAC_follows_dT_dt():
    s = Sensor(stimuli=[AmbientStep(5.0, 15.0)], channels_read=["TDC", "TAC"], noise=QUIET)
    t = np.arange(0.0, 400.0, 0.5)
    tdc = s.analog(np.full(t.size, channel_index("TDC")), t) / conv.ADC_LSB_V
    s2 = Sensor(stimuli=[AmbientStep(5.0, 15.0)], channels_read=["TDC", "TAC"], noise=QUIET)
    tac = s2.analog(np.full(t.size, channel_index("TAC")), t) / conv.ADC_LSB_V
    temp = conv.tdc_to_celsius(tdc)
    assert temp[-1] < temp[0] - 5.0  # heading for 15 + 10 °C
    slope = np.gradient(temp, t)
    rate = conv.tac_to_celsius_per_s(tac, tdc, tac_offset=2048.0)
    sel = (t > 60) & (np.abs(slope) > 0.01)
    assert sel.sum() > 100
    assert np.allclose(rate[sel], slope[sel], rtol=0.1)  # the documented TAC relation holds within 10 %


@pytest.mark.parametrize("fault,channel,check", [
    ({"thermistor": "open"}, "TDC", lambda c: c == 0),
    ({"thermistor": "short"}, "TDC", lambda c: c == 4095),
    # electrodes keep 0.67 % of the previous electrode's value in the multiplexer's hold node: near the rails
    ({"electrode_open": [7]}, "E7", lambda c: c < 40),
    ({"electrode_short": [7]}, "E7", lambda c: c > 4055),
])
def test_open_and_shorted_faults_read_at_the_rails(fault, channel, check):
    s = Sensor(channels_read=[channel], noise=QUIET, faults=fault)
    code = int(s.sample([channel_index(channel)], [0.01])[0])
    assert check(code), code


def test_a_broken_thermistor_with_the_adcs_noise_reads_as_docs_faults_md_says():
    """docs/faults.md: open reads 0 to 2, mostly 0 (the ADC's noise at the bottom rail); shorted, TDC's buffer stops
    at the supply rail, which reads 4095 with the ADC's noise, now and then 4094."""
    t = 0.1 + np.arange(2000) * 1e-3
    open_ = Sensor(channels_read=["TDC"], faults={"thermistor": "open"}, seed=3).sample([channel_index("TDC")] * 2000, t)
    short = Sensor(channels_read=["TDC"], faults={"thermistor": "short"}, seed=3).sample([channel_index("TDC")] * 2000, t)
    assert open_.max() <= 2 and np.mean(open_ == 0) > 0.8, np.unique(open_, return_counts=True)
    assert short.min() >= 4094 and np.mean(short == 4095) > 0.99, np.unique(short, return_counts=True)


@pytest.mark.parametrize("fault, after_itself, after_another", [
    ({"electrode_short": [7]}, (4095, 4095), (4080, 4094)), ({"electrode_open": [7]}, (0, 0), (5, 40))])
def test_a_faulted_electrode_sits_on_the_rail_only_when_read_after_itself(fault, after_itself, after_another):
    """docs/faults.md: the hold node keeps ~0.7 % of the previous channel, so after a resting electrode a faulted one
    reads just inside the rails (a firmware check for exactly 0 or 4095 would not fire), back to back on them."""
    t = 0.1 + np.arange(40) * 2.27e-4
    alone = Sensor(channels_read=["E7"], noise=QUIET, faults=fault).sample([channel_index("E7")] * 40, t)
    mixed = Sensor(channels_read=["E7", "E8"], noise=QUIET, faults=fault).sample(
        [channel_index("E8"), channel_index("E7")] * 20, t)[1::2]
    assert after_itself[0] <= alone[5:].min() and alone[5:].max() <= after_itself[1], np.unique(alone)
    assert after_another[0] <= mixed[5:].min() and mixed[5:].max() <= after_another[1], np.unique(mixed)


def test_a_stuck_multiplexer_returns_one_electrode_on_every_channel():
    touch = Touch(0.1, 1.5, 0.2, 1.0, electrode="E3")
    s = Sensor(stimuli=[touch], channels_read=E, noise=QUIET, faults={"mux_stuck": 3})
    z = impedances(s, 0.5)
    assert np.allclose(z[1:], z[2], rtol=1e-3)  # the first sample still remembers the node's previous value
    assert z[2] > 1.2 * impedances(Sensor(channels_read=E, noise=QUIET), 0.5)[2]


def test_a_dead_heater_leaves_the_finger_at_ambient_and_a_failing_one_cools_it():
    dead = Sensor(channels_read=["TDC"], noise=QUIET, faults={"heater_failed": True})
    assert tdc_celsius(dead, [0.0, 100.0]) == pytest.approx([25.0, 25.0], abs=0.2)
    from emulator.stimuli import HeaterFailure

    failing = Sensor(stimuli=[HeaterFailure(10.0)], channels_read=["TDC"], noise=QUIET)
    temps = tdc_celsius(failing, [0.0, 600.0, 7200.0])
    assert temps[0] > 34.0 and temps[1] < temps[0] - 2 and temps[2] == pytest.approx(25.0, abs=0.3)


def test_unknown_fault_is_refused_by_name():
    with pytest.raises(ValueError, match="unknown sensor fault"):
        Sensor(faults={"fan_failed": True})


def test_only_the_needed_modalities_are_built():
    plain = Sensor(channels_read=["PAC", "PDC"])
    assert plain.electrodes is None and plain.thermal is None
    names = [e["name"] for e in Sensor(channels_read=["TDC"]).effects_report()]
    assert "thermal_steady_state" in names and "thermal_network" not in names
    touched = Sensor(stimuli=[Touch(0.1, 1.0, material="glass")], channels_read=["TDC", "E1"])
    names = [e["name"] for e in touched.effects_report()]
    assert "thermal_network" in names and "electrodes" in names
    # a contact with no material changes no temperature: no thermal network
    assert Sensor(stimuli=[Touch(0.1, 1.0)], channels_read=["TDC"]).thermal is None


def test_shear_skews_the_pattern_toward_its_direction():
    base = impedances(Sensor(stimuli=[Touch(0.1, 1.5, 0.2, 1.0, electrode="E17")], channels_read=E, noise=QUIET),
                      0.5)
    sheared = impedances(Sensor(stimuli=[Touch(0.1, 1.5, 0.2, 1.0, electrode="E17", tangential_N=1.5)],
                                channels_read=E, noise=QUIET), 0.5)
    rest = impedances(Sensor(channels_read=E, noise=QUIET), 0.5)
    tipward = 9  # E10 (x = 1.3 mm) lies toward the tip of E17 (x = −2.8 mm)
    assert sheared[tipward] - base[tipward] > 0
    # the dimple (impedances above rest) moves toward the tip: its impedance-weighted centre along x moves +x
    # (electrodes on the rim bulge behind it move the other way: the bulge leaves them, so no rootward sign test)
    x = electrode_positions_mm()[:, 0]

    def centre_x(z):
        rise = np.maximum(z - rest, 0.0)
        return float((rise * x).sum() / rise.sum())

    assert centre_x(sheared) - centre_x(base) > 0.5


def test_a_touchs_contact_carries_its_tangential_force_along_the_core_surface():
    # tangential_N is the tangential force at full normal force: held at 2 N with 0.5 N of shear, the contact's forces
    # are (2, 0.5) N.  A shear at 90° points toward +angle around the finger: the unit tangent of the surface's circle
    # at the touch, ∂P/∂angle of surface_point_mm normalised (a central difference of a circle: 1e-9)
    for angle in (0.0, 30.0, -60.0):
        touch = Touch(0.1, 2.0, 0.2, 1.0, x_mm=-5.0, angle_deg=angle, tangential_N=0.5, shear_angle_deg=90.0)
        contact = Sensor(stimuli=[touch], channels_read=["E1"], noise=QUIET).electrodes.contacts[0]
        normal, tangential = contact.state(np.array([0.8]))
        assert (float(normal[0]), float(tangential[0])) == pytest.approx((2.0, 0.5), rel=1e-9)
        around = surface_point_mm(-5.0, angle + 1e-4) - surface_point_mm(-5.0, angle - 1e-4)
        assert np.array(contact.shear_direction) == pytest.approx(around / np.linalg.norm(around), abs=1e-9)


def test_ambient_steps_act_in_time_order_whatever_order_they_are_given_in():
    # a scene lists its stimuli in any order: the room is at 15 °C from 5 s and at 30 °C from 60 s either way
    t = np.arange(0.0, 200.0, 1.0)
    steps = [AmbientStep(5.0, 15.0), AmbientStep(60.0, 30.0)]
    given, reversed_ = (tdc_celsius(Sensor(stimuli=s, channels_read=["TDC"], noise=QUIET), t)
                        for s in (steps, steps[::-1]))
    assert np.array_equal(reversed_, given)
    assert given[59] < given[5] and given[-1] > given[60]  # the core cools toward 25 °C, then warms toward 40 °C


def test_forces_that_bottom_the_skin_stay_bounded():
    p = SensorParams()
    pos = electrode_positions_mm()
    c = Contact(surface_point_mm(-2.8, 0.0), 6.0, lambda t: np.full(np.shape(t), 50.0))
    gaps = electrode_gaps_mm(p, [c], np.array([0.0, 1.0]), pos)
    assert np.all(gaps >= p.minimum_gap_mm) and np.all(np.isfinite(gaps))
    s = Sensor(stimuli=[Touch(0.1, 50.0, 0.2, 1.0, electrode="E17")], channels_read=E + ["PDC"], noise=QUIET)
    codes = s.sample(E_IDX, 0.6 + np.arange(19) * 1e-4)
    # the pressed electrode reads the impedance of the fluid left over it (gap from the contact geometry), far
    # above rest, and no electrode reads a rail
    centre = surface_point_over_mm(pos[16])
    gap = electrode_gaps_mm(p, [Contact(centre, 3.0, lambda t: np.full(np.shape(t), 50.0))], np.array([0.6]), pos)[0]
    z = conv.impedance_ohm(codes.astype(float))
    # read E17 again right after itself: no memory of E16 in the multiplexer's hold node (0.67 % of a 2 V swing)
    again = s.sample(np.full(2, channel_index("E17")), 0.61 + np.arange(2) * 1e-4)
    assert float(conv.impedance_ohm(float(again[-1]))) == pytest.approx(
        p.electrode_series_ohm + p.fluid_sheet_ohm_mm / gap[16], rel=0.02)
    assert z[16] > 3 * (p.electrode_series_ohm + p.fluid_sheet_ohm_mm / p.resting_gap_mm)
    assert codes.min() > 100 and codes.max() < 4000


def test_the_full_frame_with_both_modalities_is_deterministic():
    stim = [Touch(0.2, 1.0, 0.1, 0.3, electrode="E5", material="aluminum")]
    chans = np.array([channel_index(n) for n in DEFAULT_FRAME_NAMES] * 20)
    t = np.arange(chans.size) / 4400.0
    a = Sensor(stimuli=stim, channels_read=DEFAULT_FRAME_NAMES, seed=3).sample(chans, t)
    b = Sensor(stimuli=stim, channels_read=DEFAULT_FRAME_NAMES, seed=3).sample(chans, t)
    assert np.array_equal(a, b)


def test_the_core_temperature_drives_the_bridge_drift_into_PDC():
    p = SensorParams(bridge_offset_drift_V_per_V_K=-2e-5)
    steady = Sensor(p, channels_read=["PDC"], noise=QUIET)
    cooled = Sensor(p, stimuli=[AmbientStep(1.0, 15.0)], channels_read=["PDC"], noise=QUIET)
    t = np.array([0.5, 900.0])
    a, b = steady.analog([1, 1], t), cooled.analog([1, 1], t)
    assert a[0] == pytest.approx(b[0], abs=1e-9)  # same before the step
    drift_bits = (b[1] - b[0]) / conv.ADC_LSB_V
    assert drift_bits > 20  # 10 K cooler core, negative offset drift -> PDC rises
    assert a[1] == pytest.approx(a[0], abs=1e-9)


@pytest.mark.parametrize("gap_mm", [0.12, 0.3, 0.8, 1.5, 2.5])
def test_impedance_round_trips_through_eq_4_1(gap_mm):
    from emulator.electrodes import electrode_volts

    p = SensorParams()
    z_true = p.electrode_series_ohm + p.fluid_sheet_ohm_mm / gap_mm
    code = np.floor(electrode_volts(p, np.full((1, 19), gap_mm))[0, 0] / conv.ADC_LSB_V + 0.5)
    assert float(conv.impedance_ohm(code)) == pytest.approx(z_true, rel=0.01)


def test_an_electrode_at_rest_carries_about_half_an_lsb_of_noise():
    """Issue 10: quiet channels sit near half an LSB RMS at rest (the ADC's own noise; PAC's extra noise belongs to
    PAC's path). Table 4-1's 3.2 mV electrode resolution equals 3.3 V / 1024, not a noise figure."""
    s = Sensor(channels_read=["E5"], seed=4)
    codes = s.sample(np.full(20000, channel_index("E5")), np.arange(20000) / 1000.0).astype(float)
    assert 0.3 <= codes.std() <= 0.7


# --- the touched object's layers against heat conduction's closed forms (from a mutation hunt) --------------------
def _object_flux_W(mat, t_s, area=1e-4, rise_K=10.0, contact_W_per_m2K=1e6):
    """Heat flow (W) from a skin held ``rise_K`` above an object initially at the far field's temperature into the
    object's layers, ``t_s`` after the touch (np.inf: the steady state), from the network's own matrices."""
    from scipy.linalg import expm

    from emulator.thermal import SKIN

    net = ThermalNetwork(SensorParams().replace(contact_conductance_W_per_m2K=contact_W_per_m2K))
    A, _ = net.matrices((mat, area))
    obj = np.arange(4, A.shape[0])
    a_oo, b = A[np.ix_(obj, obj)], A[obj, SKIN] * rise_K
    x = (np.linalg.solve(a_oo, -b) if np.isinf(t_s)
         else np.linalg.solve(a_oo, (expm(a_oo * t_s) - np.eye(obj.size)) @ b))
    g_skin_to_first = A[obj[0], SKIN] * mat.rho * mat.c * area * net.layers[0]
    return g_skin_to_first * (rise_K - x[0])


@pytest.mark.parametrize("name", ["glass", "wood", "polystyrene foam", "granite", "aluminum", "steel"])
def test_a_touched_object_draws_heat_as_a_semi_infinite_body(name):
    """Prediction (Carslaw & Jaeger): a surface held ΔT above a semi-infinite body draws e·ΔT/√(πt) per m² (e the
    effusivity √(kρc)).  The object's 10 geometric layers (50 µm growing ×1.8, 22 mm deep) give it within 5 % from
    30 ms until the heat nears their far end: to 10 s for poor conductors, to 0.3 s for metals (α ≈ 1e-5–1e-4
    m²/s reach 22 mm within seconds; beyond, the far field at ambient takes heat as a finite slab does)."""
    mat = MATERIALS[name]
    until = 0.3 if mat.k > 10 else 10.0
    for t in (0.03, 0.1, 0.3, 1.0, 3.0, 10.0):
        if t <= until:
            exact = mat.effusivity * 10.0 / np.sqrt(np.pi * t) * 1e-4
            assert _object_flux_W(mat, t) == pytest.approx(exact, rel=0.05), (name, t)


@pytest.mark.parametrize("name", ["aluminum", "glass", "polystyrene foam"])
def test_a_touched_objects_steady_heat_flow_is_the_contact_and_slab_in_series(name):
    """Derived: in the steady state the heat crosses the contact conductance and the whole layered slab (thickness
    L, the layers' sum, to the far field at ambient) in series: ΔT / (1/(h·A) + L/(k·A)), exactly — every link of
    the chain (the contact, the first half-layer, the layers, the last half-layer to the far field) counts."""
    mat, area = MATERIALS[name], 1e-4
    slab_m = float(np.sum(ThermalNetwork(SensorParams()).layers))
    for h in (3000.0, 1e6):
        expected = 10.0 / (1 / (h * area) + slab_m / (mat.k * area))
        assert _object_flux_W(mat, np.inf, area, contact_W_per_m2K=h) == pytest.approx(expected, rel=1e-9)


def test_a_touch_on_a_whole_second_meets_its_object_at_once():
    """The thermal model advances in 1 s chunks; a cold object (aluminum at 15 °C) touched exactly at a chunk's start
    (2.0 s) must arrive as one touched 1 µs later does: TDC and TAC over the next 2 s agree within 3 % of the touch's
    own swing (measured 0.8 % for TAC, from the 1 µs; a mutation hunt found the arrival could wait a whole second,
    89 %)."""
    t = np.arange(1.5, 4.0, 0.01)

    def trace(start, channel):
        touch = Touch(start, 1.0, 0.2, 5.0, electrode="E7", material="aluminum", object_temperature_C=15.0)
        return Sensor(stimuli=[touch], channels_read=["TDC", "TAC"], seed=1).analog_trace(channel, t)

    for channel in ("TDC", "TAC"):
        on_the_second, just_after = trace(2.0, channel), trace(2.0 + 1e-6, channel)
        assert np.max(np.abs(on_the_second - just_after)) < 0.03 * np.ptp(just_after), channel


def test_the_first_response_to_a_touch_scales_with_the_objects_own_temperature():
    """Prediction (a linear network): the heat a touched object draws in its first half second — TAC's swing — is
    proportional to its temperature less the skin's.  Aluminum at 15, 25 and 35 °C: equal 10 K steps give equal
    steps of the swing (within 5 %), and the sign turns between 25 °C and 35 °C, across the skin's ~33 °C (a
    mutation hunt: the object's layers starting at the previous temperature gave one swing for all three)."""
    quiet = NoiseSources(**{k: False for k in NoiseSources.__dataclass_fields__})
    t = np.arange(1.5, 2.6, 0.01)
    swings = []
    for celsius in (15.0, 25.0, 35.0):
        touch = Touch(2.0, 1.0, 0.2, 5.0, electrode="E7", material="aluminum", object_temperature_C=celsius)
        tac = Sensor(stimuli=[touch], channels_read=["TDC", "TAC"], seed=1, noise=quiet).analog_trace("TAC", t)
        after = tac[(t > 2.0) & (t < 2.5)] - tac[t < 1.99].mean()
        swings.append(after[np.argmax(np.abs(after))])
    assert swings[0] < swings[1] < 0 < swings[2]
    assert swings[1] - swings[0] == pytest.approx(swings[2] - swings[1], rel=0.05)


#: effusivity √(kρc) bands (W·s^½/(m²·K)) of the classes of surfaces a fingertip tells apart by touch, from the
#: textbook tables the materials come from (Incropera & DeWitt App. A; Callister): conductors (metals, graphite)
#: above 5000, stone, glass and ceramics 1000–3000, solid polymers, rubbers, leather, paper and wood 200–1000,
#: foams, felts, fabrics and fur below 200
EFFUSIVITY_CLASSES = {
    (5000.0, 1e5): ("aluminum", "steel", "stainless steel", "graphite"),
    (1000.0, 3000.0): ("granite", "glass", "ceramic tile"),
    (200.0, 1000.0): ("acrylic", "PTFE", "nylon", "polyethylene", "polypropylene", "phenolic laminate", "vinyl (PVC)",
                      "silicone rubber", "rubber (soft)", "leather", "paper", "hardwood", "wood"),
    (10.0, 200.0): ("balsa", "cork", "cotton fabric", "polystyrene foam", "polyurethane foam", "EVA foam",
                    "wool felt", "fur"),
}


def test_every_material_draws_heat_as_its_class_does():
    """What a touch feels is the surface's effusivity √(kρc): a metal colder than stone or glass, those colder than
    plastics and wood, those colder than foams and fabrics.  Every material of the table sits in its class's band,
    and the bands cover the whole table.  (A mutation hunt: acrylic's conductivity ten times too high passed.)"""
    listed = [name for names in EFFUSIVITY_CLASSES.values() for name in names]
    assert sorted(listed) == sorted(MATERIALS)
    for (lo, hi), names in EFFUSIVITY_CLASSES.items():
        for name in names:
            m = MATERIALS[name]
            assert m.effusivity == pytest.approx(np.sqrt(m.k * m.rho * m.c), rel=1e-12)
            assert lo <= m.effusivity <= hi, (name, m.effusivity)
