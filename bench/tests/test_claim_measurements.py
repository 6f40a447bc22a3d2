"""How the force, thermal, vibration and electrode claims measure: each row's number is the worst of the parts it
lists, taken over the range its name states, and the helpers behind the rows (the hysteresis loop's width, the
press's loading phase, the resonance peak's window) do what their docstrings say.  A mutation hunt found these
measurements unguarded: a wrong helper still let every row pass."""

import numpy as np
import pytest

from bench.tests.test_claims import _claims
from bench.verification.claims import Bench
from emulator import conversions as conv

pytestmark = pytest.mark.claims


def _row(group, name):
    (c,) = [c for c in _claims(group) if c.name == name]
    return c


# --- force ------------------------------------------------------------------------------------------------------
def test_loop_width_is_the_widest_unloading_gap_at_equal_force_over_the_mean_rise_at_2_N():
    """A made loop: loading rise 50 codes/N, unloading the same plus a bump of 3 codes peaking at 1.5 N, and a top
    at 2 N drifting from 100 to 104 codes (mean 102).  The width is the bump's 3 codes over 102: the largest gap
    (not the mean), anywhere over 0.3–1.7 N (not only at low force), unloading over loading, over the mean top."""
    from bench.verification.claims.force import loop_width

    up = np.linspace(0.0, 1.95, 40)  # N, steps of 0.05 N: the levels 0.3..1.7 fall on samples
    down = up[::-1]
    top_f = np.full(11, 2.0)
    force = np.concatenate([up, top_f, down])
    bump = 3.0 * np.exp(-(((down - 1.5) / 0.2) ** 2))  # codes
    rise = np.concatenate([50.0 * up, np.linspace(100.0, 104.0, 11), 50.0 * down + bump])
    loading = np.concatenate([np.ones(40 + 6, bool), np.zeros(5 + 40, bool)])
    assert loop_width(force, rise, loading) == pytest.approx(3.0 / 102.0, rel=1e-9)


def test_the_press_cycle_splits_loading_from_unloading_and_its_rise_starts_at_zero():
    """press_cycle's mask is True while the force rises or holds and False while it falls (the hysteresis loop
    compares the two at equal force), and the rise is measured from the rest before the press (≈ 0 codes there)."""
    from bench.verification.claims.force import CYCLE, press_cycle

    force, rise, loading = press_cycle(Bench())
    assert loading.any() and (~loading).any()
    assert np.all(np.diff(force[loading]) >= -1e-12), "the loading phase holds a falling force"
    assert np.all(np.diff(force[~loading]) <= 1e-12), "the unloading phase holds a rising force"
    assert force[loading].max() == pytest.approx(CYCLE["force_N"])
    at_rest = (force == 0.0) & loading
    assert np.count_nonzero(at_rest) >= 20 and abs(rise[at_rest].mean()) < 0.5  # codes


def test_the_creep_row_measures_the_skins_creep_law_as_a_share_of_the_settled_reading():
    """The held 1 N's PDC grows from the early to the late window as the skin-and-fluid standard linear solid grows
    the force it passes on (sls_creep_growth: 9.0 % of the late reading); the row's growth, a share of the late
    (settled) reading, is that within 0.6 point (the early window's 10 noisy PDC samples: 9.3 % measured), where a
    share of the early reading would be 10.3 %."""
    from bench.verification.claims.force import sls_creep_growth
    from emulator.params import SensorParams

    row = _row("force", "PDC creep under a held 1 N, 0.2 → 10 s")
    law = 100 * sls_creep_growth(SensorParams())
    assert 8.5 < law < 9.5 and row.details["creep_law_%"] == law
    assert abs(row.measured - law) <= 0.6, (row.measured, law)
    early, late = row.details["early_codes"], row.details["late_codes"]
    assert row.measured == pytest.approx(100 * (late - early) / late, rel=1e-12)


@pytest.mark.parametrize("relaxed_fraction", [0.4, 0.85])
def test_the_creep_law_follows_the_skin_s_relaxed_modulus(relaxed_fraction):
    """A skin that relaxes further (E∞/E0 = 0.4) creeps more, one nearly elastic (0.85) less: the PDC still grows as
    the closed-form standard linear solid says (within 0.6 point), so the creep row reads back the unit's own skin."""
    from bench.verification.claims.force import force_claims, sls_creep_growth
    from emulator.params import SensorParams

    p = SensorParams().replace(skin_relaxed_modulus_fraction=relaxed_fraction)
    (row,) = [c for c in force_claims(Bench(params=p)) if c.name.startswith("PDC creep")]
    law = 100 * sls_creep_growth(p)
    assert abs(law - 100 * sls_creep_growth(SensorParams())) > 2.0  # another skin, another creep
    assert abs(row.measured - law) <= 0.6, (row.measured, law)


@pytest.mark.parametrize("knee", [0.125, 0.4])
def test_the_knee_row_reads_back_the_unit_s_slope_above_the_knee(knee):
    """The force curve's slope above the knee is force_slope_above_knee times the slope below: the row measures it
    within 5 % for a unit whose fraction is half the nominal 0.25 (which the old accepted range, 0..0.5, let pass
    whatever the curve did) or 0.4, and accepts it."""
    from bench.verification.claims.force import force_claims
    from emulator.params import SensorParams

    rows = force_claims(Bench(params=SensorParams().replace(force_slope_above_knee=knee)))
    (row,) = [c for c in rows if c.name == "slope above the knee / slope below"]
    assert row.measured == pytest.approx(knee, rel=0.05) and row.passed


# --- thermal ----------------------------------------------------------------------------------------------------
def test_the_tdc_rows_span_0_to_70_C_and_report_their_worst_step():
    """The conversion row says "over 0–70 °C": its settled thermistor temperatures reach both ends, its number is the
    largest conversion error among them, and the resolution row is the coarsest code step per kelvin among the
    neighbouring temperatures inside 0–70 °C (the same sweep)."""
    conversion = _row("thermal", "TDC conversion error over 0–70 °C")
    sweep = conversion.details["bead_C_and_mean_code"]
    beads = np.array([b for b, _ in sweep])
    codes = np.array([c for _, c in sweep])
    assert beads.min() <= 0.5 and beads.max() >= 69.5, (beads.min(), beads.max())
    errors = np.abs(conv.tdc_to_celsius(codes) - beads)
    assert conversion.measured == pytest.approx(errors.max(), rel=1e-9)
    resolution = _row("thermal", "TDC resolution over 0–70 °C")
    inside = (np.maximum(beads[1:], beads[:-1]) >= 0.0) & (np.minimum(beads[1:], beads[:-1]) <= 70.0)
    per_K = np.abs(np.diff(codes) / np.diff(beads))[inside]
    assert inside.sum() >= 13 and resolution.measured == pytest.approx(1.0 / per_K.min(), rel=1e-9)


def test_the_range_top_is_where_the_line_through_the_last_two_unclipped_points_reaches_4094():
    """range_top_C: a line through the last two points below code 4093.5 (not earlier ones), extended to 4094; a
    sweep that never clips cannot place the top (inf: the row fails), and one with a single unclipped point is
    refused by name."""
    from bench.verification.claims.thermal import range_top_C

    sweep = [(66.0, 3900.0), (68.0, 3950.0), (70.0, 4010.0), (72.0, 4060.0), (74.0, 4094.6), (76.0, 4095.0)]
    assert range_top_C(sweep) == pytest.approx(72.0 + (4094.0 - 4060.0) * 2.0 / 50.0, rel=1e-12)  # 73.36 °C
    assert range_top_C(sweep[:4]) == np.inf
    with pytest.raises(ValueError, match="1 unclipped point"):
        range_top_C([(72.0, 4060.0), (74.0, 4094.6)])
    top = _row("thermal", "TDC range top (code 4094)")
    assert top.measured == range_top_C(top.details["bead_C_and_mean_code"])
    assert any(c >= 4093.5 for _, c in top.details["bead_C_and_mean_code"])  # the sweep reached the top


def test_the_tac_rate_integrates_to_the_tdc_temperature_change():
    """TAC is TDC through a first-order high-pass (τ = 1/(2π·0.45 Hz)): y + τ·y' = τ·x', so the rate r read from it
    obeys ∫r dt + τ·Δr = ΔT.  Over the aluminum touch (1 s to 11 s) the rate the thermal rows read — TAC's resting
    level taken before the touch, a running mean — integrates to the TDC's own cooling (−0.95 K) within 3 %; a
    resting level taken 2 s into the touch (12 % off) or a running sum in place of a mean (×20) would not."""
    from bench.verification.claims.thermal import material_touch, tac_rate_C_per_s

    t, tdc, tac = material_touch(Bench(), "aluminum", seed_offset=0)
    at, rate = tac_rate_C_per_s(t, tac, tdc)
    a, z = 0.7, 11.0  # s: before the touch, and at its end
    inside = (at >= a) & (at <= z)
    tau = 1.0 / (2 * np.pi * 0.45)
    integral = np.trapezoid(rate[inside], at[inside]) + tau * (np.interp(z, at, rate) - np.interp(a, at, rate))
    temp = conv.tdc_to_celsius(tdc)
    cooled = temp[np.abs(t - z) <= 0.1].mean() - temp[np.abs(t - a) <= 0.1].mean()
    assert cooled < -0.5
    assert integral == pytest.approx(cooled, rel=0.03)


def test_the_tac_rate_s_smoothing_keeps_the_resting_noise_under_the_weakest_transient():
    """The running mean exists for the noise: at rest (a touch that exchanges no heat) the largest cooling the rate
    reads is under a fifth of the transient the TAC row reports for polystyrene foam, its weakest material (2e-4 of
    1.5e-3 °C/s); read over 50 ms instead of 200 ms the noise alone would read a third of it."""
    from bench.verification.claims.thermal import material_touch, tac_rate_C_per_s

    row = _row("thermal", "TAC peak cooling rate over 10 s: Al > glass > wood > foam")
    foam = row.details["peak_cooling_C_per_s"]["polystyrene foam"]
    t, tdc, tac = material_touch(Bench(), None, seed_offset=4)
    _, rate = tac_rate_C_per_s(t, tac, tdc)
    assert 0.0 < -np.min(rate) < foam / 5, (-np.min(rate), foam)



def test_the_tac_row_orders_a_rate_tac_reads_as_one_within_its_range_and_resolution():
    """SENSOR.md §4 states that touching an object draws heat at a rate its thermal properties set, and gives TAC as
    the thermal flux: 0–1 °C/s, resolved to 0.001 °C/s, high-passed at 0.45 Hz.  The TAC row orders each
    material's fastest cooling during the 10 s hold.  That rate peaks seconds after contact (measured 2026-11-24:
    aluminum 7.5 s, glass 5.6 s, wood 5.1 s, foam 5.2 s), each more than 8 time constants of TAC's high-pass
    (τ = 0.35 s: 2.8 s) in, so TAC reads a rate there (below its corner the high-pass differentiates), and
    before the hold ends (10 s).  Every peak (0.124 °C/s on aluminum down to 0.0015 °C/s on foam) lies within the
    stated range and above the stated resolution, so the ordering is one the real TAC could read."""
    from bench.verification.claims.thermal import THERMAL_MATERIALS

    row = _row("thermal", "TAC peak cooling rate over 10 s: Al > glass > wood > foam")
    tau_s = 1.0 / (2 * np.pi * 0.45)
    after = row.details["peak_after_contact_s"]
    peaks = row.details["peak_cooling_C_per_s"]
    assert sorted(after) == sorted(peaks) == sorted(THERMAL_MATERIALS)
    assert all(8 * tau_s <= after[m] < 10.0 for m in THERMAL_MATERIALS), after
    assert all(0.001 < peaks[m] < 1.0 for m in THERMAL_MATERIALS), peaks

# --- vibration --------------------------------------------------------------------------------------------------
def test_the_vibration_rows_span_d_s_band_and_report_their_worst_frequency():
    """"PAC RMS proportional to drive amplitude" is judged on its worst drive frequency, and both it and the
    human-threshold row cover D's band up to its top, 900 Hz (the threshold row from 10 Hz, its lowest)."""
    row = _row("vibration", "PAC RMS proportional to drive amplitude")
    per = row.details["r_squared_by_frequency_Hz"]
    assert len(per) >= 5 and min(per) <= 20.0 and max(per) == 900.0
    assert row.measured == min(per.values()) and all(0.999 <= r <= 1.0 for r in per.values())
    human = _row("vibration", "sensor beats human threshold at every frequency").details["ratio_by_frequency"]
    assert min(human) == 10.0 and max(human) == 900.0


def test_d_min_s_background_is_d_s_resting_band_as_the_noise_row_measures_it():
    """D eq. 5.3's background: the typical (median) second's largest 2 Hz band at rest, D's 0.2 bits² (± 30 %, the
    noise row's tolerance); the noise row measures the same quantity on other seconds, so the two agree (± 25 %)
    where the loudest second's band (0.28 bits²) would not."""
    background = _row("vibration", "d_min near the 330 Hz resonance").details["background_bits2"]
    band = _row("noise", "largest 2 Hz band of a 1 s PAC spectrum at rest")
    assert 0.14 <= background <= 0.26
    assert background == pytest.approx(band.measured, rel=0.25)


def test_the_proportionality_row_fits_through_the_origin_and_no_drive_reads_nothing():
    """"Proportional" has two halves: the row's R² per frequency is that of a fit through the origin (a free line
    would forgive an offset) of the band RMS it lists per drive, and the measurement reads exactly nothing at no
    drive (noise off: an offset in the measurement, too small for R² to see, reads there)."""
    from bench.verification import analysis
    from bench.verification.claims.vibration import drive_rms_bits
    from emulator.sensor import NoiseSources

    row = _row("vibration", "PAC RMS proportional to drive amplitude")
    drives, rms = row.details["drive_m"], row.details["rms_bits_by_frequency_Hz"]
    assert len(drives) >= 4 and set(rms) == set(row.details["r_squared_by_frequency_Hz"])
    for f, r in rms.items():
        assert len(r) == len(drives) and all(np.diff(r) > 0), f
        assert row.details["r_squared_by_frequency_Hz"][f] == analysis.fit_proportional(drives, r).r_squared, f
        assert drive_rms_bits(Bench(), [0.0], f, NoiseSources.none()) == [0.0], f


def test_d_min_s_band_powers_are_the_drive_s_power_at_its_frequency():
    """D eq. 5.3's P_1µm, in the d_min row's details for the sweep and the peak search: the 2 Hz band at each drive
    frequency holds the drive's own power, A²/2 of the noise-free PAC (before the ADC) at that frequency over the same
    second, within the band's noise and hum (its RMS within 0.3 bits); a band beside the drive would hold ~nothing;
    and each d_min is eq. 5.3 of its band power and the background."""
    from bench.verification.analysis import minimum_detectable_amplitude
    from emulator.stimuli import Vibration

    row = _row("vibration", "d_min near the 330 Hz resonance")
    b, background = Bench(), row.details["background_bits2"]
    for powers, d_min in ((row.details["band_power_bits2"], row.details["d_min_m"]),
                          (row.details["peak_search_band_power_bits2"], row.details["peak_search_d_min_m"])):
        assert set(powers) == set(d_min) and len(powers) >= 20
        for f, p in powers.items():
            t, x = b.analog_pac_bits([Vibration(0.0, 2.0, 1e-6, f, fade_s=0.0)], 2.0)
            second = (t >= 1.0) & (t < 2.0)
            fit = np.column_stack([np.sin(2 * np.pi * f * t[second]), np.cos(2 * np.pi * f * t[second]),
                                   np.ones(np.count_nonzero(second))])
            (s, c, _), *_ = np.linalg.lstsq(fit, x[second], rcond=None)
            assert abs(np.sqrt(p) - np.sqrt((s**2 + c**2) / 2)) <= 0.3, (f, p, (s**2 + c**2) / 2)
            assert d_min[f] == minimum_detectable_amplitude(1e-6, p, noise_band_bits2=background), f


@pytest.mark.parametrize("mains_Hz", [50.0, 60.0, 51.0])
def test_the_peak_search_grid_is_5_Hz_over_250_to_400_Hz_clear_of_mains_harmonics(mains_Hz):
    """peak_search_frequencies_Hz: every 5 Hz from 250 to 400 Hz, both ends included, except those within 3 Hz of a
    harmonic of the unit's own mains frequency (a hum line in the drive's 2 Hz band would read as response); at 51 Hz
    the harmonics fall 1–2 Hz from grid points (255 Hz on 255, 306 beside 305, 357 between 355 and 360)."""
    from emulator.params import SensorParams
    from bench.verification.claims.vibration import peak_search_frequencies_Hz

    grid = peak_search_frequencies_Hz(Bench(params=SensorParams().replace(mains_frequency_Hz=mains_Hz)))
    harmonics = mains_Hz * np.arange(1, 10)
    expected = [f for f in np.arange(250.0, 400.1, 5.0) if np.min(np.abs(f - harmonics)) > 3.0]
    assert list(grid) == expected and len(grid) >= 25
    assert set(np.arange(250.0, 400.1, 5.0)) - set(grid) == {f for f in np.arange(250.0, 400.1, 5.0)
                                                             if np.min(np.abs(f - harmonics)) <= 3.0}
    assert len(set(np.arange(250.0, 400.1, 5.0)) - set(grid)) == {50.0: 4, 60.0: 2, 51.0: 4}[mains_Hz]


def test_a_sensitivity_peak_at_the_search_edge_fails_the_near_330_Hz_row():
    """A unit resonating at 200 Hz (the parameter's lowest) peaks at the search grid's 250 Hz edge, outside
    300–360 Hz: that is no peak "around 330 Hz", and the d_min row fails (NaN) rather than reporting the edge."""
    from emulator.params import SensorParams
    from bench.verification.claims.vibration import vibration_claims

    rows = vibration_claims(Bench(params=SensorParams().replace(resonance_Hz=200.0)))
    (near,) = [c for c in rows if c.name == "d_min near the 330 Hz resonance"]
    assert near.details["peak_Hz"] < 300.0, near.details["peak_Hz"]
    assert np.isnan(near.measured) and not near.passed


# --- electrodes -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("z, monotonic", [
    ([500.0, 800.0, 1000.0, 1000.0], True),  # rises, then holds at the bottomed impedance
    ([500.0, 800.0, 995.0, 990.0], True),  # both last readings within 2 % of bottomed: the gap is at its minimum
    ([500.0, 800.0, 800.0, 1000.0], False),  # a flat step away from the bottom (20 % under it)
    ([500.0, 1000.0, 900.0], False),  # falls from the bottom to 10 % under it: only one end is bottomed
    ([1000.0, 1000.0, 1000.0], False),  # bottomed at the lightest force
    ([500.0, 700.0, 650.0, 900.0], False),  # falls mid-way
])
def test_the_impedance_row_allows_flat_steps_only_once_the_skin_has_bottomed(z, monotonic):
    from bench.verification.claims.electrodes import monotonic_until_bottomed

    assert monotonic_until_bottomed(z, 1000.0) is monotonic


def test_a_resting_code_at_or_below_the_series_impedance_is_refused_as_a_pressed_one_is():
    """common_rest_codes needs fluid resistance left in the rest as in the pressed codes: a rest whose code implies
    Z ≤ Z_series (code 4000: 237 Ω) is refused by name, not turned into a negative conductance."""
    from bench.verification.claims.electrodes import common_rest_codes
    from emulator.params import SensorParams

    with pytest.raises(ValueError, match="series impedance"):
        common_rest_codes(np.array([2900.0]), np.array([4000.0]), SensorParams())


@pytest.mark.parametrize("group, name", [
    ("thermal", "TDC drop after 10 s: Al > glass > wood > foam"),
    ("thermal", "TAC peak cooling rate over 10 s: Al > glass > wood > foam"),
    ("electrodes", "pressed electrode's impedance rises with force"),
])
def test_a_yes_or_no_row_accepts_only_yes(group, name):
    """Rows whose number is a truth value (1 ordered or monotonic, 0 not) accept exactly 1: a range reaching 0 would
    pass the row whatever was measured, and its expected text ("strictly ordered", "monotonic ...") states no number
    for the range check to compare."""
    row = _row(group, name)
    assert (row.low, row.high) == (1.0, 1.0) and row.measured in (0.0, 1.0) and row.passed


def test_the_contact_estimate_is_the_change_weighted_centroid_of_the_four_electrodes_that_move_most():
    """contact_estimate_mm: of six made electrodes on a line (x = 0..5 mm), those whose changes are largest in size
    (−5, 3, 2, −1 codes at x = 1..4: a change's sign does not matter) weighted 5:3:2:1, the 0.1 and 0.5 code ones
    left out: x = (5·1 + 3·2 + 2·3 + 1·4) / 11 mm."""
    from bench.verification.claims.electrodes import contact_estimate_mm

    positions = np.column_stack([np.arange(6.0), np.zeros(6), np.full(6, 7.0)])  # mm
    estimate = contact_estimate_mm(np.array([0.1, -5.0, 3.0, 2.0, -1.0, 0.5]), positions)
    assert estimate == pytest.approx([21.0 / 11.0, 0.0, 7.0], rel=1e-12)


def test_the_held_codes_are_the_hold_s_own_not_the_ramp_s():
    """held_codes reads a touch in its hold: for the claims' 1 N touch over E17 (full force at 0.5 s, read at 0.6 s)
    every electrode's held code is within 1.5 codes of its own reading at 0.6 s (the skin creeps ~0.03 codes per
    ms); a window reaching 0.2 s back, into the ramp, would read the pressed electrode ~26 codes nearer its rest."""
    from bench.verification.claims.electrodes import ELECTRODES, held_codes
    from emulator.sensor import NoiseSources
    from emulator.stimuli import Touch

    b, touch, at_s = Bench(), Touch(0.2, 1.0, 0.3, 1.0, electrode="E17"), 0.6
    held = held_codes(b, touch, at_s)
    twice = [e for e in ELECTRODES for _ in range(2)]
    rec = b.acquire([touch], at_s + 0.05, sequence=twice, slot_rate_Hz=3800.0, noise=NoiseSources.none())
    at = []
    for e in ELECTRODES:
        t, code = rec[e][0][1::2], rec[e][1][1::2]
        at.append(code[np.argmin(np.abs(t - at_s))])
    assert held[16] < at[16] + 300 and np.max(np.abs(held - np.array(at))) <= 1.5, held - np.array(at)
    assert at[16] < held_codes(b, Touch(5.0, 1.0), 1.0)[16] - 300  # pressed: E17 read 350 codes below its rest


def test_a_contact_s_change_beyond_10_mm_is_the_faint_tail_of_its_dent_and_rim():
    """The locality row's detail: for each of the 19 contacts the largest |Δcode| beyond 10 mm (2.4 w) of the pressed
    electrode is the volume-balanced profile's faint tail, under 6 codes (emulator/electrodes.py: "under 6 codes beyond
    8 mm", next to −380 on the pressed electrode) but not nothing (−0.01…−0.02 of the central depth out to 3.5 w):
    a rim bulge that is missing (the dent's own tail then reads 6–12 codes) or twice as wide (56) would show here."""
    row = _row("electrodes", "a 1 N contact's change stays in the nearest 4 electrodes")
    far = row.details["largest_change_beyond_10_mm_codes"]
    assert len(far) == 19 and all(1.0 <= c < 6.0 for c in far), far


# --- sliding ----------------------------------------------------------------------------------------------------
def test_the_slip_onset_rise_is_the_band_power_ratio_in_decibels():
    """The slip-onset row is 10·log10 of the 30–200 Hz band's mean square (bits²) over the 100 ms after slip to that
    over the stick phase: a power ratio in dB (20·log10 would double it and pass a 5 dB rise)."""
    row = _row("sliding", "slip onset: 30–200 Hz PAC power, sliding over stick")
    stick, slip = row.details["stick_band_bits2"], row.details["slip_band_bits2"]
    assert 0.0 < stick < slip
    assert row.measured == pytest.approx(10.0 * np.log10(slip / stick), rel=1e-12)
