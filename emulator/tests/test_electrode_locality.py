"""Electrode model: any number of electrodes, per-electrode resting gaps, locality of a contact's pattern."""

import numpy as np
import pytest

from emulator.electrodes import Contact, ElectrodeModel, electrode_positions_mm, surface_point_over_mm
from emulator.params import SensorParams

pytestmark = pytest.mark.unit


def _sp_like_positions(n=24):
    """A made-up (n, 3) table: electrodes spread over the ventral half of the core, mm."""
    x = np.linspace(-14.0, 4.0, n)
    a = np.radians(np.linspace(-80.0, 80.0, n)[np.random.default_rng(0).permutation(n)])
    return np.column_stack([x, 5.0 * np.sin(a), -5.0 * np.cos(a)])


def test_the_model_serves_as_many_electrodes_as_its_positions_table_has():
    p = SensorParams()
    pos = _sp_like_positions(24)
    press = Contact(surface_point_over_mm(pos[20]), 2.0, lambda t: np.full(np.shape(t), 1.0), start_s=0.1)
    m = ElectrodeModel(p, [press], positions=pos)
    v = m.targets(np.arange(1, 25), np.full(24, 0.8))
    assert v.shape == (24,) and np.all(np.isfinite(v))
    assert int(np.argmin(v)) == 20  # the pressed electrode's fluid thins most: lowest voltage
    assert ElectrodeModel(p, [], positions=pos).targets(np.array([24]), np.array([0.5])).shape == (1,)
    # default: the 19 of fixtures/electrodes.csv
    assert ElectrodeModel(p, []).positions.shape == (19, 3)
    assert np.array_equal(ElectrodeModel(p, []).positions, electrode_positions_mm())


def test_faults_index_electrodes_1_to_N_and_bad_numbers_are_refused_by_name():
    p = SensorParams()
    pos = _sp_like_positions(24)
    m = ElectrodeModel(p, [], faults={"electrode_open": [24], "mux_stuck": 22}, positions=pos)
    assert m.rest[23] == 0.0
    with pytest.raises(ValueError, match=r"faults.electrode_short: electrode 20 .* 1..19"):
        ElectrodeModel(p, [], faults={"electrode_short": [20]})
    with pytest.raises(ValueError, match=r"faults.mux_stuck: electrode 25 .* 1..24"):
        ElectrodeModel(p, [], faults={"mux_stuck": 25}, positions=pos)
    with pytest.raises(ValueError, match=r"shape \(19, 2\)"):
        ElectrodeModel(p, [], positions=np.zeros((19, 2)))
    with pytest.raises(ValueError, match="E1..E19"):
        ElectrodeModel(p, []).sample(np.array([20]), np.array([0.1]))


# --- per-electrode resting gaps (issue 10.1/10.3) ---------------------------------------------------------------
def test_resting_gaps_are_nominal_without_spread_and_drawn_per_electrode_with_it():
    from emulator.electrodes import resting_gaps_mm

    p = SensorParams()
    assert np.array_equal(resting_gaps_mm(p, 19), np.full(19, p.resting_gap_mm))
    q = p.replace(electrode_gap_spread_mm=0.6, electrode_gap_seed=12345)
    g = resting_gaps_mm(q, 19)
    assert np.array_equal(g, resting_gaps_mm(q, 19))  # deterministic from the seed
    assert np.array_equal(g, resting_gaps_mm(q, 24)[:19])  # electrode order: a 24-electrode draw extends it
    assert not np.allclose(g, resting_gaps_mm(q.replace(electrode_gap_seed=12346), 19))
    assert np.all(np.abs(g - p.resting_gap_mm) <= 2 * 0.6 + 1e-12) and g.min() >= 2 * p.minimum_gap_mm
    assert 0.3 < g.std() < 0.9
    with pytest.raises(ValueError, match=r"electrode_gap_seed = 1.5: must be a whole number"):
        resting_gaps_mm(q.replace(electrode_gap_seed=1.5), 19)


def test_a_units_resting_codes_differ_by_electrode_and_every_rest_uses_them():
    from emulator import conversions as conv
    from emulator.channels import channel_index
    from emulator.electrodes import electrode_volts, resting_gaps_mm
    from emulator.sensor import NoiseSources, Sensor
    from emulator.stimuli import Touch

    names = [f"E{n}" for n in range(1, 20)]
    idx = np.array([channel_index(e) for e in names])
    q = SensorParams().replace(electrode_gap_spread_mm=0.6, electrode_gap_seed=7)
    expected = electrode_volts(q, resting_gaps_mm(q, 19)[None, :])[0] / conv.ADC_LSB_V
    assert expected.max() - expected.min() > 300  # a unit's electrodes rest hundreds of codes apart
    untouched = Sensor(q, channels_read=names, noise=NoiseSources.none())
    # a touch that has ended long ago (the skin's ~1.1 s creep recovered too): each electrode's own rest again
    touched = Sensor(q, stimuli=[Touch(0.1, 1.0, 0.1, 0.3, electrode="E5")], channels_read=names,
                     noise=NoiseSources.none())
    for s, t0 in ((untouched, 0.2), (touched, 6.0)):
        codes = np.array([s.sample(np.array([i, i]), t0 + np.array([0.0, 1e-4]))[-1] for i in idx], float)
        assert np.allclose(codes, expected, atol=2.0)


# --- viscoelastic creep of the indentation (emulator/viscoelastic.py) -------------------------------------------
def test_a_held_force_makes_the_electrode_code_creep_and_a_release_recovers():
    from emulator import conversions as conv
    from emulator.channels import channel_index
    from emulator.electrodes import indentation_fraction, resting_gaps_mm
    from emulator.mechanics import skin_fluid
    from emulator.sensor import NoiseSources, Sensor
    from emulator.stimuli import Touch

    p = SensorParams()
    sf = skin_fluid(p)
    assert 0.5 < sf.creep_ratio < 1.0 and sf.creep_time_s > 0.1
    touch = Touch(0.5, 1.0, 0.01, 6.0, electrode="E17")  # 1 N on within 10 ms, held 6 s, off within 10 ms
    s = Sensor(stimuli=[touch], channels_read=["E17"], noise=NoiseSources.none())
    t = np.array([0.4, 0.7, 1.5, 3.0, 6.4, 6.8, 8.0, 12.0])
    codes = s.sample(np.full(t.size, channel_index("E17")), t).astype(float)
    z = conv.impedance_ohm(codes)
    assert z[1] < z[2] < z[3] < z[4]  # held: the skin creeps toward the core, the impedance keeps rising
    # the pressed electrode's gap follows a(F·c(t)), c = r + (1 − r)(1 − e^(−t/τ)) (standard linear solid)
    gmin, g0 = p.minimum_gap_mm, resting_gaps_mm(p, 19)[16]

    def z_at(held_s):
        c = sf.creep_ratio + (1 - sf.creep_ratio) * (1 - np.exp(-held_s / sf.creep_time_s))
        gap = g0 - (g0 - gmin) * indentation_fraction(p, 1.0 * c)
        return p.electrode_series_ohm + p.fluid_sheet_ohm_mm / gap

    assert z[4] / z[1] == pytest.approx(z_at(5.9) / z_at(0.2), rel=0.01)
    assert z[4] / z[1] > 1.03  # a visible creep: several % in impedance, tens of codes
    assert codes[1] - codes[4] > 10
    # released: the skin recovers over the same time, back to rest
    assert z[5] > z[6] > z[7] and z[7] == pytest.approx(z[0], rel=2e-3)


def test_the_crept_pattern_does_not_depend_on_how_the_host_reads_it():
    from emulator.channels import channel_index
    from emulator.sensor import NoiseSources, Sensor
    from emulator.stimuli import Touch

    stim = [Touch(0.3, 1.2, 0.2, 2.5, electrode="E10")]
    t = np.sort(np.random.default_rng(3).uniform(0.0, 5.0, 400))
    idx = np.full(t.size, channel_index("E10"))
    whole = Sensor(stimuli=stim, channels_read=["E10"], noise=NoiseSources.none()).sample(idx, t)
    s = Sensor(stimuli=stim, channels_read=["E10"], noise=NoiseSources.none())
    parts = np.concatenate([s.sample(idx[i:i + 37], t[i:i + 37]) for i in range(0, t.size, 37)])
    np.testing.assert_array_equal(whole, parts)


# --- locality: where a contact's change goes ---------------------------------------------------------------------
def _press_changes(p, radius_mm=3.0, force_N=1.0):
    """|Δcode| of every electrode (rows: a press over E1..E19 in turn) and the electrode distances, mm."""
    from emulator.conversions import ADC_LSB_V
    from emulator.electrodes import electrode_gaps_mm, electrode_volts, resting_gaps_mm

    pos = electrode_positions_mm()
    rest = electrode_volts(p, resting_gaps_mm(p, 19)[None, :])[0] / ADC_LSB_V
    rows = []
    for i in range(19):
        c = Contact(surface_point_over_mm(pos[i]), radius_mm, lambda t: np.full(np.shape(t), force_N))
        rows.append(np.abs(electrode_volts(p, electrode_gaps_mm(p, [c], np.array([0.5]), pos))[0] / ADC_LSB_V - rest))
    return np.array(rows), np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=2)


def test_a_1N_press_changes_mostly_the_nearest_electrodes_and_little_beyond_10_mm():
    d, dist = _press_changes(SensorParams())
    order = np.argsort(dist, axis=1)
    share4 = np.array([d[i, order[i, :4]].sum() / d[i].sum() for i in range(19)])
    assert np.median(share4) > 0.7 and share4.min() > 0.6
    assert np.all(np.argmax(d, axis=1) == np.arange(19))  # the pressed electrode moves most
    assert d[16, 16] > 300  # ~380 codes under a 1 N, 3 mm contact (E17 pressed)
    assert d[dist > 10.0].max() < 10.0  # a uniform bulge would move every far electrode by ~20-30 codes
    # a spread pattern (wider indenter) reaches further but still stays local
    wide, _ = _press_changes(SensorParams(), radius_mm=5.0)
    assert wide[dist > 10.0].max() > d[dist > 10.0].max() and wide[dist > 14.0].max() < 10.0


def test_a_press_over_a_tip_electrode_moves_it_as_much_as_one_over_the_pad():
    """E7..E10 sit on the hemispherical tip, nearer the axis than the pad's 5 mm: a contact "over" them had been put
    on the pad's cylinder continued beyond the tip, 2.7 mm from E7 (E7 moved 93 codes, the pad's electrodes 381)."""
    d, _ = _press_changes(SensorParams())
    pressed = np.diag(d)
    assert pressed.min() > 0.9 * np.median(pressed), np.round(pressed)


@pytest.mark.parametrize("variant", ["biotac", "biotac-sp"])
def test_a_contact_over_an_electrode_is_centred_on_the_skin_over_it(variant):
    from emulator.electrodes import CORE_RADIUS_MM, free_skin_grid, surface_point_mm

    pos = electrode_positions_mm(variant)
    centres = np.array([surface_point_over_mm(q) for q in pos])
    assert np.linalg.norm(centres - pos, axis=1).max() < 0.5  # mm (E7's 5.30 mm from the tip's centre: 0.30)
    skin, _ = free_skin_grid(180.0, 0.25)
    for x, a in ((4.9, 0.0), (3.0, 40.0), (0.5, -90.0), (-5.0, 10.0)):  # each on the modelled skin's surface
        assert np.linalg.norm(skin - surface_point_mm(x, a), axis=1).min() < 0.25, (x, a)
    assert np.allclose(surface_point_mm(CORE_RADIUS_MM, 30.0), [CORE_RADIUS_MM, 0.0, 0.0])  # the apex
    with pytest.raises(ValueError, match="x_mm = 5.5: the finger ends at its tip's apex, x = 5 mm"):
        surface_point_mm(5.5, 0.0)


def test_the_profile_falls_off_as_documented():
    from emulator.electrodes import indentation_profile

    w = np.hypot(3.0, 3.0)
    prof = lambda d: float(indentation_profile(d * d, w, 1 / np.sqrt(2), 2.0))  # noqa: E731 (plane: κ = 2)
    assert prof(0.0) == -1.0
    assert abs(prof(0.845 * w)) < 0.01  # the dimple ends at 0.85 w
    assert 0.18 < max(prof(x * w) for x in np.linspace(1.0, 1.5, 11)) < 0.21  # the rim bulge: +0.2 at 1.24 w
    assert abs(prof(2.07 * w)) < 0.01 and all(abs(prof(x * w)) < 0.03 for x in (2.5, 3.0, 4.0))


@pytest.mark.parametrize("x_mm,angle_deg", [(-5.0, 0.0), (-5.0, 100.0), (4.0, 0.0), (-17.0, 40.0)])
def test_the_displaced_liquid_is_put_back_on_the_free_skin(x_mm, angle_deg):
    from emulator.electrodes import bulge_balance, free_skin_grid, indentation_profile, surface_point_mm

    p = SensorParams()
    w = np.hypot(3.0, p.skin_spread_mm)
    c = surface_point_mm(x_mm, angle_deg)
    kappa = bulge_balance(p, c, w)
    pts, area = free_skin_grid(p.free_skin_half_angle_deg)
    d2 = ((pts - c) ** 2).sum(axis=1)
    net = (area * indentation_profile(d2, w, p.bulge_width_ratio, kappa)).sum()
    assert abs(net) < 1e-9 * (area * np.exp(-d2 / (2 * w * w))).sum()  # volume conserved on the free skin
    assert 1.5 < kappa < 3.0  # 2 on a plane; more where the nail or the base takes part of the ring away
    # the skin under the nail cannot take the liquid: the free rim takes more of it near the tether
    if angle_deg == 100.0:
        assert kappa > bulge_balance(p, surface_point_mm(x_mm, 0.0), w)


def test_a_held_shear_computes_one_row_per_run_with_the_same_bits():
    """Consistency: the dent and ring under a tangential load held in runs (a finger still, the stage cruising) or
    held throughout are computed once per run and repeated; they equal the row-by-row computation bit for bit."""
    from emulator.electrodes import Footprint

    p = SensorParams()
    press = Contact(surface_point_over_mm(electrode_positions_mm()[8]), 2.0, lambda t: np.ones(np.shape(t)),
                    0.6, (1.0, 0.0, 0.0))
    fp = Footprint(p, press, electrode_positions_mm())
    runs = np.repeat([0.3, 0.45, 0.45001, 0.2], [40, 300, 7, 120])
    for ft in (runs, np.full(500, 0.37), np.linspace(0.1, 0.5, 50)):
        dent, ring = fp.shapes(ft)
        ref_dent, ref_ring = fp._shifted_shapes(fp.shift_mm_per_N * ft)
        assert np.array_equal(np.broadcast_to(dent, ref_dent.shape), ref_dent)
        assert np.array_equal(np.broadcast_to(ring, ref_ring.shape), ref_ring)


@pytest.mark.parametrize("rows", [1, 300])
@pytest.mark.parametrize("faults", [([], []), ([3], [7]), ([2, 5], [])])
def test_compiled_gaps_and_volts_are_the_numpy_laws_to_the_bit(rows, faults):
    """Consistency: the electrodes' compiled gap and voltage passes equal :func:`_contact_gaps_mm` then
    :func:`_volts_in_place` bit for bit, for none, one or two pressing contacts, one-row or per-sample dents, with open
    and shorted electrodes, and contacts pressed to the core (the g_min floor)."""
    from emulator.electrodes import _contact_gaps_mm, _contact_volts, _volts_in_place, resting_gaps_mm

    p, n = SensorParams(), 300
    rng = np.random.default_rng(rows + len(faults[0]))
    rest = resting_gaps_mm(p, 19)
    for k in (0, 1, 2):  # no contact pressing (a released finger while the filter settles), one, two
        terms = [(rng.uniform(0.0, 1.5, n), 0.05, rng.random((rows, 19)), rng.random((rows, 19))) for _ in range(k)]
        ref = _volts_in_place(p, _contact_gaps_mm(p, rest, terms, n), *faults)
        assert np.array_equal(_contact_volts(p, rest, terms, n, *faults), ref)


def test_a_contact_held_since_before_the_start_does_not_creep_after_it():
    """A contact loaded before t = 0 (a rig that starts pressed) has crept already: its electrodes read the same at
    0.05 s and at 3 s (within 1e-6 of a volt), where an unsettled creep filter drifts them for about a second."""
    from emulator.electrodes import electrode_positions_mm, surface_point_over_mm

    p = SensorParams()
    pos = electrode_positions_mm()
    held = Contact(surface_point_over_mm(pos[6]), 2.0, lambda t: np.full(np.shape(t), 1.0))  # start_s = -inf
    m = ElectrodeModel(p, [held])
    early, late = (m.targets(np.arange(1, 20), np.full(19, t)) for t in (0.05, 3.0))
    assert np.max(np.abs(early - late)) < 1e-6
    assert np.ptp(early) > 1e-3  # the contact does move the pressed electrodes


# --- from a mutation hunt on emulator/electrodes.py --------------------------------------------------------------
def test_resting_gaps_drawn_below_the_clearance_stop_at_twice_the_bottoming_gap():
    """Documented (resting_gaps_mm): a drawn gap is clipped to at least 2·g_min, a resting skin staying clear of where
    it bottoms.  At the largest spread allowed (1 mm, ±2 mm truncation around 1.5 mm) some of 400 draws fall below
    2·g_min = 0.2 mm: they read exactly 0.2 mm, and every gap above it is the unclipped draw within ±2 spreads."""
    from emulator.electrodes import resting_gaps_mm

    p = SensorParams().replace(electrode_gap_spread_mm=1.0, electrode_gap_seed=7)
    g = resting_gaps_mm(p, 400)
    clear = 2 * p.minimum_gap_mm
    assert g.min() == pytest.approx(clear, rel=1e-12)
    assert 5 <= int((g == g.min()).sum()) < 100  # several clipped, most not
    assert np.all(np.abs(g[g > clear] - p.resting_gap_mm) <= 2.0 + 1e-12)


def test_the_free_skin_grid_tiles_the_untethered_cylinder_and_tip():
    """The free skin (free_skin_grid) is the cylinder x ∈ [−20, 0] mm and the hemispherical tip (r = 5 mm) within
    ±θ of the ventral midline: its areas sum to 20·r·2θ + r²·2θ (the tip's ∫ sin φ dφ over [0, π/2] is 1), every
    point lies on the core, and the cylinder's area is spread evenly along it (its centroid at x = −10 mm, its points
    from the base clamp to the tip).  (A mutation hunt: the cylinder's points squeezed into its front half, with
    their areas kept, passed.)"""
    from emulator.electrodes import CORE_RADIUS_MM, SKIN_BASE_X_MM, free_skin_grid

    r = CORE_RADIUS_MM
    for half_deg in (60.0, 120.0):
        pts, area = free_skin_grid(half_deg)
        two_theta = 2 * np.radians(half_deg)
        cyl = pts[:, 0] <= 0.0
        assert area[cyl].sum() == pytest.approx(-SKIN_BASE_X_MM * r * two_theta, rel=1e-9)
        assert np.average(pts[cyl, 0], weights=area[cyl]) == pytest.approx(SKIN_BASE_X_MM / 2, rel=1e-9)
        assert pts[cyl, 0].min() < SKIN_BASE_X_MM + 0.5 and pts[cyl, 0].max() > -0.5
        assert area[~cyl].sum() == pytest.approx(r * r * two_theta, rel=2e-3)  # midpoint rule over φ
        assert np.allclose(np.hypot(pts[cyl, 1], pts[cyl, 2]), r)
        assert np.allclose(np.linalg.norm(pts[~cyl], axis=1), r)
        assert np.all(np.abs(np.arctan2(pts[:, 1], -pts[:, 2])) <= np.radians(half_deg) + 1e-9)


def test_a_held_press_settles_on_the_static_gap_law_rim_bulge_included():
    """Consistency of two paths: once its creep and the 100 Hz filter have settled, the model's pattern under a held
    force is :func:`electrode_volts` of :func:`electrode_gaps_mm` for that force (each working out its own rim bulge
    κ at the footprint width w = √(r_indenter² + spread²)), on the dimple and on the ring alike."""
    from emulator.electrodes import electrode_gaps_mm, electrode_volts

    p = SensorParams()
    pos = electrode_positions_mm()
    for k, radius in ((6, 2.0), (12, 4.0)):
        press = Contact(surface_point_over_mm(pos[k]), radius, lambda t: np.full(np.shape(t), 1.5))  # held forever
        model = ElectrodeModel(p, [press]).targets(np.arange(1, 20), np.full(19, 6.0))
        static = electrode_volts(p, electrode_gaps_mm(p, [press], np.array([6.0]), pos))[0]
        rest = electrode_volts(p, np.full((1, 19), p.resting_gap_mm))[0]
        assert np.any(static > rest + 1e-3)  # the ring does raise some electrodes
        assert np.max(np.abs(model - static)) < 1e-9


def test_a_contact_held_since_before_the_start_reads_its_pattern_from_the_first_instant():
    """A contact loaded before t = 0 has been forever (Contact.resting_load_N): the 100 Hz electrode filter has
    settled on its pattern too, so the first conversions (E1..E19 within the first 9 ms of a frame) read the static
    pattern of :func:`electrode_gaps_mm`, not the unpressed rest easing toward it over ~5 ms (tens of codes).
    Sheared too: the held shear moves the pattern before t = 0 as after."""
    from emulator.electrodes import electrode_gaps_mm, electrode_volts

    p = SensorParams()
    pos = electrode_positions_mm()
    for ratio in (0.0, 0.5):
        held = Contact(surface_point_over_mm(pos[6]), 2.0, lambda t: np.full(np.shape(t), 1.0), ratio)
        static = electrode_volts(p, electrode_gaps_mm(p, [held], np.array([0.0]), pos))[0]
        m = ElectrodeModel(p, [held])
        for t in (0.0, 0.001, 0.002, 0.005, 0.05):
            assert np.max(np.abs(m.targets(np.arange(1, 20), np.full(19, t)) - static)) < 1e-9
        first = ElectrodeModel(p, [held]).sample(np.array([7]), np.array([0.0]))[0]  # the hold node held E1
        assert first == pytest.approx(
            (1 - m.mux_keep) * static[6] + m.mux_keep * (static[0] + p.mux_injection_V), rel=1e-12)


def test_a_contact_presses_only_within_its_window_whatever_its_profile_gives_outside():
    """``Contact(start_s, end_s)``: no force outside the window (the class says so), also when the force profile is
    not zero there — a user's constant press from 0.5 s to 1 s.  It used to press for the whole 1 s chunk the model
    computes at once (already at 0.01 s), and from before t = 0 (its resting load), so where the chunks fell
    decided the output."""
    from emulator.electrodes import electrode_volts

    p = SensorParams()
    pos = electrode_positions_mm()
    press = Contact(surface_point_over_mm(pos[6]), 2.0, lambda t: np.full(np.shape(t), 1.0), start_s=0.5, end_s=1.0)
    t = np.array([-1.0, 0.0, 0.49, 0.5, 1.0, 1.01])
    assert press.state(t)[0].tolist() == [0.0, 0.0, 0.0, 1.0, 1.0, 0.0] and press.resting_load_N() == 0.0
    rest = electrode_volts(p, np.full((1, 19), p.resting_gap_mm))[0]
    m = ElectrodeModel(p, [press])
    for when in (0.01, 0.3, 0.49):
        assert np.max(np.abs(m.targets(np.arange(1, 20), np.full(19, when)) - rest)) < 1e-12, when
    assert np.max(np.abs(m.targets(np.arange(1, 20), np.full(19, 0.9)) - rest)) > 1e-3  # pressed within it
