"""Sliding claims (D ch. 3, 4, 6): slip onset, a 3 mm grating's rhythm, fingerprints, foam, force control
through PDC, and skin wear — measured through the SPI path a host uses (PAC and PDC codes), with the test
surfaces of the texture library (60-grit sandpaper, the 3 mm grating) and its foam."""

from __future__ import annotations

import numpy as np

from bench.rigs.texture_rig import Movement, TextureRig
from bench.textures.library import texture
from bench.textures.properties import roughness
from bench.verification.analysis import causal_band_pass, harmonic_levels_db, ramp_ratio, stick_phase
from bench.verification.claims.core import Bench, Claim, claim_group
from emulator.effects import Block
from emulator.fidelity import profile
from emulator.sensor import NoiseSources, Sensor
from emulator.skin import Skin, contact_patch_area_m2
from emulator.sliding import Slide, SlidingContact

PAC_RATE_HZ = 2200.0


def _band_power(x: np.ndarray, fs: float, lo: float, hi: float) -> float:
    """Mean power (bits²) of ``x`` in [lo, hi] Hz (periodogram with a Hann window)."""
    x = np.asarray(x, float) - np.mean(x)
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size))) ** 2
    f = np.fft.rfftfreq(x.size, 1 / fs)
    sel = (f >= lo) & (f <= hi)
    return float(spec[sel].sum() / max(x.size, 1))


def _pac(b: Bench, slide: Slide, t_end: float):
    rec = b.acquire([slide], t_end, sequence=("PAC", "PDC"))
    return rec["PAC"]


def _slide_forces(b: Bench, slide: Slide, times: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The slide's force log (:meth:`emulator.sliding.SlidingContact.force_log`: 100 Hz instants, forces in N,
    slip velocity in m/s) and its tangential force (N) at ``times`` (s, in order), from a noise-free run of the same
    slide and seed: friction does not depend on the sensor's noise, so these are the forces of :func:`_pac`'s run."""
    sensor = Sensor(b.params, [slide], ("PAC",), b.fidelity, b.seed, NoiseSources.none(),
                    record_signals=("tangential_force_N",))
    tangential = sensor.signal("tangential_force_N", times)
    contact = next(e for e in sensor.graph.effects if e.name == "sliding_contact")
    return contact.force_log(0), tangential


#: slip onset: the skin slips once its slip velocity reaches this fraction of the stage's (before: it sticks)
SLIPPING_FRACTION = 0.5
#: slip onset: the window after the onset whose 30–200 Hz power is compared with the stick phase's (s)
SLIP_WINDOW_S = 0.1
#: slip onset: the tangential force at the last instant of stick over the force at its first, at least
STICK_RAMP_MIN = 3.0


def _slip_onset_claims(b: Bench, slide: Slide, t: np.ndarray, pac: np.ndarray) -> list[Claim]:
    """D ch. 3 Fig. 3-5 on one slide's PAC codes (instants ``t``): the tangential force ramps while the skin sticks
    (the stage moving, the skin not slipping), and at slip 30–200 Hz power rises ≥ 10 dB over that stick phase."""
    log, tangential = _slide_forces(b, slide, t)
    try:
        phase = stick_phase(log["t"], slide.stage_velocity_m_per_s(log["t"]), log["slip_m_per_s"],
                            SLIPPING_FRACTION)
        stuck = (t >= phase.stage_start_s) & (t <= phase.last_stuck_s)
        if np.count_nonzero(stuck) < 3:
            raise ValueError(f"the stick phase ({phase.stage_start_s:.4g}–{phase.last_stuck_s:.4g} s) holds "
                             f"{np.count_nonzero(stuck)} PAC samples: too short to measure")
    except ValueError as e:  # no stick, no slip or a stick too short: both rows fail, saying why
        detail = {"no_stick_phase": str(e)}
        rise_db = ramp = float("nan")
    else:
        band = causal_band_pass(pac, PAC_RATE_HZ, 30, 200)

        def power(start, stop):  # mean square (bits²) of the band-passed PAC over [start, stop] s
            return float(np.mean(band[(t >= start) & (t <= stop)] ** 2))

        stick = float(np.mean(band[stuck] ** 2))
        slip = power(phase.slip_onset_s, phase.slip_onset_s + SLIP_WINDOW_S)
        rise_db = 10 * np.log10(slip / stick)
        stuck_force = tangential[stuck]
        ramp = ramp_ratio(stuck_force)
        detail = {"stage_moves_s": phase.stage_start_s, "last_stuck_s": phase.last_stuck_s,
                  "slip_onset_s": phase.slip_onset_s, "stick_band_bits2": stick, "slip_band_bits2": slip,
                  "stick_over_hold_dB": 10 * np.log10(stick / power(slide.slide_start_s - 0.2, slide.slide_start_s)),
                  "steady_sliding_over_stick_dB": 10 * np.log10(
                      power(slide.slide_start_s + 0.3, slide.slide_end_s - 0.05) / stick),
                  "tangential_N_stick_start_end": [float(stuck_force[0]), float(stuck_force[-1])],
                  "rising_steps_share": float(np.mean(np.diff(stuck_force) > 0))}
    window = (f"stick = the stage moving while the skin's slip stays below {SLIPPING_FRACTION:.0%} of the stage's "
              "speed, on the 100 Hz force log")
    return [
        Claim("slip onset: 30–200 Hz PAC power, sliding over stick", "≥ 10 dB rise", rise_db, 10.0, np.inf, "dB",
              "D ch. 3 Fig. 3-5", detail, kind="prediction",
              note=f"{window}; slip = the {SLIP_WINDOW_S * 1e3:.0f} ms after the onset; PAC through a causal 4th-order "
                   "Butterworth 30–200 Hz band-pass, so the short stick window takes nothing from the slip after it "
                   "(D used a 5 Hz high-pass and a trailing 80 ms STFT against leakage); the texture passes under "
                   "the skin only once it slips. The stick is not silent as D saw it: the stage's start kicks the "
                   "skin's resonance (stick over hold in the detail)"),
        Claim("slip onset: tangential force ramps while the skin sticks", f"rises ≥ {STICK_RAMP_MIN:g}× to slip",
              ramp, STICK_RAMP_MIN, np.inf, "ratio", "D ch. 3 Fig. 3-5", detail, kind="prediction",
              note=f"{window}; the tangential force at the grid rate at the stick's last instant over its first, 0 "
                   "unless a least-squares line through it rises; the ramp is the skin's tangential spring "
                   f"({b.params.skin_tangential_stiffness_N_per_m:g} N/m, a model choice) loaded at the stage's "
                   "speed until static friction (LuGre) gives way"),
    ]


#: the 3 mm grating's period (m: texture 902 in fixtures/textures/library.toml)
GRATING_PERIOD_M = 3e-3
#: a harmonic n·v/λ is looked for within ± this fraction of its frequency (the fundamental's tolerance)
HARMONIC_TOLERANCE = 0.05
#: a harmonic is present if its level over the local spectral floor reaches this (dB)
HARMONIC_MIN_DB = 6.0


def _grating_harmonics_claim(levels: dict[str, dict[int, float]], movement: str) -> Claim:
    """D ch. 3: the grating's spectrum has harmonics — at least two of the 2nd–4th harmonics of v/λ stand
    :data:`HARMONIC_MIN_DB` over the local floor (:func:`bench.verification.analysis.harmonic_levels_db`) for
    ``movement`` (a key of ``levels``: every movement's levels per order go to the detail)."""
    present = sum(levels[movement][n] >= HARMONIC_MIN_DB for n in (2, 3, 4))
    return Claim(f"3 mm grating at {movement}: harmonics 2–4 of v/λ over the local floor",
                 f"≥ 2 of 3 at ≥ {HARMONIC_MIN_DB:g} dB", present, 2, 3, "harmonics", "D ch. 3",
                 {"level_over_floor_dB_by_order": levels}, kind="prediction",
                 note=f"{movement}; a harmonic's level: the Welch spectrum's largest bin within ± "
                      f"{HARMONIC_TOLERANCE:.0%} of n·v/3 mm over the median of the bins between it and its "
                      "neighbours (± v/λ/2); the harmonics present come from the grating's profile as the library "
                      "defines it (T902: a square wave, lands = grooves, so 0, −1/3, 0, 1/5, 0, −1/7 of the "
                      "fundamental for the 2nd–7th: odd only; D gives no profile)",
                 deviation="at 0.5 N @ 10 cm/s the 2nd and 4th harmonics stand ~2 dB over the floor: the library's "
                           "grating is a square wave, which has no even harmonics (an assumption: lands = grooves), "
                           "and the contact makes little of them at this movement; only the profile's 3rd stands out "
                           "(~7 dB). The "
                           "count depends on the movement: at 0.5 N @ 15 cm/s the 3rd and 4th reach ~14 and ~7 dB "
                           "(2 of 3), at 1.5 N @ 10 cm/s none (the patch averages more); the 5th and 6th stand 8–18 "
                           "dB over the floor at 0.5 N (see the detail)")


def _ridge_release_claim(b: Bench, sand) -> Claim:
    """Ridge-resolved fingerprints (the reference profile's sliding contact alone, no sensor needed): release events
    per second while the skin slips over 60-grit at 0.5 N, 1 cm/s, and none on a smooth skin."""
    grid = profile("reference")
    rates = {}
    for label, skin in (("ridged", Skin()), ("smooth", Skin(fingerprints=False))):
        slide = Slide(0.0, sand, 0.5, 0.01, 0.01, approach_s=0.1, hold_s=0.1, skin=skin)
        contact = SlidingContact([slide], b.params, grid.grid_Hz, grid.sliding_dx_m, grid.friction_substeps,
                                 grid.patch_radii, b.seed, ridges=grid.ridges)
        n = int(round(slide.end_s * grid.grid_Hz))
        contact.process(Block(0, n, grid.grid_Hz), {})
        log, releases = contact.force_log(0), contact.ridge_releases(0)
        slipping = log["t"][log["slip_m_per_s"] > 0.5 * slide.velocity_m_per_s]
        t0, t1 = slipping.min(), slipping.max()
        rates[label] = float(releases["count"][(releases["t"] >= t0) & (releases["t"] < t1)].sum() / (t1 - t0))
    return Claim("ridge-resolved (reference): release events while slipping over 60-grit at 0.5 N, 1 cm/s",
                 "> 0 per s; a smooth skin: none", rates["ridged"] if rates["smooth"] == 0 else 0.0, 1.0, np.inf,
                 "1/s", "D ch. 4", {"events_per_s": rates}, kind="consistency",
                 note="no published figure: D gives the ridges' geometry, not their release events; a smooth skin "
                      "releases nothing by construction (no ridge, no limit), and an event is a model choice (a "
                      "drop of a ridge's force by its stiffness × 20 µm), so the row is a regression check of the "
                      "mechanism (its tests: emulator/tests/test_ridge_release.py), not evidence")


@claim_group("sliding")
def sliding_claims(b: Bench) -> list[Claim]:
    """Slip onset, the grating's rhythm, fingerprints vs smooth skin, and foam."""
    grating, sand, foam = texture(902), texture(901), texture(30)
    out = []
    # slip onset: contact, stick, slip, steady sliding on the grating at 1 N, 2 cm/s (the slip_onset scene)
    slide = Slide(0.5, grating, 1.0, 0.02, 0.06, approach_s=0.03, hold_s=0.5, accel_s=0.02)
    t, pac = _pac(b, slide, slide.end_s + 0.3)
    out += _slip_onset_claims(b, slide, t, pac)
    rest = pac[t < 0.45]
    contact = pac[(t >= slide.start_s) & (t < slide.start_s + 0.08)]
    p_rest_hi = _band_power(rest[-contact.size:], PAC_RATE_HZ, 200, 1000)
    p_contact_hi = _band_power(contact, PAC_RATE_HZ, 200, 1000)
    out += [
        Claim("contact transient: 200–1000 Hz PAC power over rest", "broadband spike: ≥ 10 dB",
              10 * np.log10(p_contact_hi / p_rest_hi), 10.0, np.inf, "dB", "D ch. 3", kind="prediction",
              note="a 30 ms force ramp through the skin resonance"),
    ]
    # 3 mm grating: the spectrum peaks at v / 3 mm; more force or speed raises the intensity, not the peak
    peaks, powers, harmonics = {}, {}, {}
    for force, v in ((0.5, 0.1), (1.5, 0.1), (0.5, 0.15)):
        s = Slide(0.3, grating, force, v, 0.2, approach_s=0.1, hold_s=0.3)
        t, pac = _pac(b, s, s.slide_end_s)
        x = pac[(t >= s.slide_start_s + 0.1) & (t < s.slide_end_s - 0.05)].astype(float)
        spec = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(x.size))) ** 2
        f = np.fft.rfftfreq(x.size, 1 / PAC_RATE_HZ)
        band = (f > 15) & (f < 200)
        peaks[(force, v)] = float(f[band][np.argmax(spec[band])])
        powers[(force, v)] = float(np.var(x))
        harmonics[f"{force} N @ {v * 100:g} cm/s"] = harmonic_levels_db(x, PAC_RATE_HZ, v / GRATING_PERIOD_M,
                                                                        range(1, 7), HARMONIC_TOLERANCE)
    expected = 0.1 / 3e-3
    out += [
        Claim("3 mm grating at 10 cm/s: PAC spectral peak", f"v/3 mm = {expected:.1f} Hz ± 5 %", peaks[(0.5, 0.1)],
              0.95 * expected, 1.05 * expected, "Hz", "D ch. 3", {"peaks_Hz": {str(k): v for k, v in peaks.items()}},
              kind="derived", note="kinematics: the grating's period passes at v; a check of the texture track"),
        Claim("grating: 3× force raises PAC power", "> 1", powers[(1.5, 0.1)] / powers[(0.5, 0.1)], 1.0, np.inf,
              "ratio", "D ch. 3 Fig. 3-6", kind="prediction"),
        Claim("grating: 1.5× speed raises PAC power", "> 1", powers[(0.5, 0.15)] / powers[(0.5, 0.1)], 1.0, np.inf,
              "ratio", "D ch. 3 Fig. 3-7", kind="prediction"),
        Claim("grating: the peak stays at v/λ with more force", "within 5 %",
              abs(peaks[(1.5, 0.1)] / peaks[(0.5, 0.1)] - 1) * 100, 0.0, 5.0, "%", "D ch. 3", kind="derived"),
        _grating_harmonics_claim(harmonics, "0.5 N @ 10 cm/s"),
    ]
    # fingerprints vs smooth skin over 60-grit sandpaper at 0.5 N, 1 cm/s: 20–700 Hz PAC power
    band_power = {}
    for label, skin in (("ridged", Skin()), ("smooth", Skin(fingerprints=False))):
        s = Slide(0.3, sand, 0.5, 0.01, 0.02, approach_s=0.2, hold_s=0.3, skin=skin)
        t, pac = _pac(b, s, s.slide_end_s)
        x = pac[(t >= s.slide_start_s + 0.2) & (t < s.slide_end_s - 0.05)]
        band_power[label] = _band_power(x, PAC_RATE_HZ, 20, 700)
    out.append(Claim("fingerprints over 60-grit at 0.5 N, 1 cm/s: 20–700 Hz PAC power", "≥ 10 dB over smooth skin",
                     10 * np.log10(band_power["ridged"] / band_power["smooth"]), 10.0, np.inf, "dB", "D ch. 4",
                     kind="prediction",
                     note="ridge pitch and height from D; the crest contact width (0.1 mm) is a model choice; the "
                          "smooth skin's signal is mostly the friction fluctuation's (3 % RMS of µ), which brought "
                          "the margin from ~48 to ~18 dB"))
    out.append(_ridge_release_claim(b, sand))
    # sliding on foam: signal-to-noise above 1000
    s = Slide(0.5, foam, 1.0, 0.03, 0.05, approach_s=0.2, hold_s=0.3)
    t, pac = _pac(b, s, s.slide_end_s)
    snr = np.var(pac[(t >= s.slide_start_s + 0.2) & (t < s.slide_end_s - 0.05)]) / np.var(pac[t < 0.45])
    out.append(Claim("sliding on foam: PAC power / rest power", "> 1000", snr, 1000.0, np.inf, "ratio",
                     "D ch. 5 Fig. 5-3", kind="prediction"))
    return out


@claim_group("rig")
def rig_claims(b: Bench) -> list[Claim]:
    """Force control through PDC, and skin wear."""
    rig = TextureRig(fidelity=b.fidelity, params=b.params, wear=False)
    errors = {}
    for number in (901, 24):  # the abrasive and a glass
        for force in (0.2, 0.5, 1.26, 2.0):
            for k in range(6):
                trial = rig.run_trial(texture(number), Movement(force, 0.02), seed=b.seed + 10 * k)
                errors[(number, force, k)] = (trial.true_normal_N / force - 1) * 100
    mean_err = {f: float(np.mean([e for (n, ff, k), e in errors.items() if ff == f])) for f in (0.2, 0.5, 1.26, 2.0)}
    worst_trial = max(abs(e) for e in errors.values())
    detail = {"mean_error_%_per_target": mean_err,
              "per_trial_%": {f"T{n} {f} N seed+{10 * k}": round(e, 2) for (n, f, k), e in errors.items()}}
    out = [Claim("force control through PDC: each target's mean true force vs target", "within ± 10 %",
                 max(abs(e) for e in mean_err.values()), 0.0, 10.0, "% (worst target)", "D ch. 6", detail,
                 kind="prediction",
                 note=f"true force = the emulator's normal load while sliding, never read from codes; 4 targets "
                      f"(0.2–2 N) × 2 textures × 6 seeds; single trials reach {worst_trial:.1f} %; the stop frame is "
                      f"the first whose PDC change reaches the target (D ch. 6; at 0.2 N the target is 17 PDC counts "
                      f"against ~0.5 LSB of PDC noise), and the stop acts 20 ms after that frame's 100 ms batch "
                      f"arrives (D ch. 6: data in 100 ms batches, the stepper updated every 100 ms)",
                 deviation=f"the controller acts on D's 100 ms batches, so the finger lowers on at 0.5 mm/s for up "
                           f"to 120 ms (60 µm) past the frame that met the target; the skin's contact stiffness turns "
                           f"that into a mean overshoot of {mean_err[0.2]:+.1f} % at 0.2 N ({mean_err[0.5]:+.1f} % at "
                           f"0.5 N, {mean_err[1.26]:+.1f} % at 1.26 N, {mean_err[2.0]:+.1f} % at 2 N). With the rule "
                           f"acted on at every 10 ms frame the 0.2 N mean was about +6 %; the ± 10 % is the project's "
                           f"requirement, not D's figure, whose rig had the same 100 ms period (bench/tests/test_texture_rig.py "
                           f"pins each trial's force to the stop frame's load plus stiffness × 0.5 mm/s × the delay)")]
    # wear: ridge height falls faster for high force × high speed than for low (one trial each on a fresh skin)
    lost = {}
    for label, mv in (("low", Movement(0.2, 0.01)), ("high", Movement(2.0, 0.1))):
        skin = Skin()
        area = contact_patch_area_m2(mv.force_N, b.params.contact_radius_at_1N_m)
        lost[label] = skin.wear(mv.force_N, 0.05, area, 0.6, mv.velocity_m_per_s)
    out.append(Claim("ridge wear per trial, high vs low power movement (2 N @ 10 cm/s vs 0.2 N @ 1 cm/s)",
                     "high wears > 1000× faster", lost["high"] / max(lost["low"], 1e-30), 1000.0, np.inf, "ratio",
                     "D ch. 6", {"lost_m": lost}, kind="consistency",
                     note="the wear law: worn volume ∝ N·d·(N·v)^β, crest area ∝ N^(2/3); 100 times the sliding "
                          "power wears ~10^7 times faster at β = 3.4, and 2.2× without the power factor"))
    out += _wear_calibration_claims(b)
    # after wear, roughness for a fixed texture and movement drops; a fresh skin restores it
    mv, sand, excluded = Movement(0.5, 0.025), texture(901), Movement(1.26, 0.0631)
    worn_skin = Skin()
    area = contact_patch_area_m2(excluded.force_N, b.params.contact_radius_at_1N_m)
    for _ in range(20):  # the skin_wear scene: D's named high-wear movement, 20 slides
        worn_skin.wear(excluded.force_N, 0.05, area, float(sand.mu_kinetic), excluded.velocity_m_per_s)
    worn = [roughness(TextureRig(skin=worn_skin, wear=False, fidelity=b.fidelity, params=b.params)
                      .run_trial(sand, mv, seed=100 + k).recording)
            for k in range(3)]
    fresh = [roughness(TextureRig(skin=worn_skin.replace(), wear=False, fidelity=b.fidelity, params=b.params)
                       .run_trial(sand, mv, seed=100 + k).recording)
             for k in range(3)]
    out.append(Claim("roughness after 20 slides of 1.26 N @ 6.31 cm/s (wear law) vs a fresh skin", "drops",
                     float(np.mean(fresh) - np.mean(worn)), ANY_DROP_LN, np.inf, "log units", "D ch. 6",
                     {"fresh": fresh, "worn": worn, "ridge_left": worn_skin.ridge_factor}, kind="prediction",
                     note="D names 1.26 N @ 6.31 cm/s among the movements excluded for wear; the fresh skin is the "
                          "worn one replaced"))
    return out


#: the least roughness difference (ln bits²) that counts as a drop: above 0, so that the same skin measured twice (a
#: difference of exactly 0, e.g. a replacement that kept the worn ridges) fails the row; far below any real drop
ANY_DROP_LN = 1e-6


def _wear_calibration_claims(b: Bench) -> list[Claim]:
    """D's two wear observations, which calibrate the wear law's k and β (bench.experiments.trials)."""
    from bench.experiments.trials import PILOT_WORTH_TRIALS, wear_calibration

    cal = wear_calibration(b.params)
    knobs = {"first_visible_wear_fraction": cal["first_visible_wear_fraction"], "solved": cal["solved"],
             "beta_range": cal["beta_range"]}
    return [
        Claim("skins used over D's training session (117 textures × 3 movements × 5 trials), replaced at the first "
              "visible wear", "3 (replaced two times)", cal["training_skins"], 3, 3, "skins", "D ch. 6", knobs,
              kind="calibrated",
              calibration="wear_coefficient k: the session wears 2.5 skins' worth of visible wear (the middle of "
                          "two replacements)",
              note="D's three movements (all power level 6); visible wear = a 0.1 mm flat on the rounded 0.4 mm "
                   "crest, 3.2 % of the ridge height (a model choice for what the eye sees)"),
        Claim(f"a pilot's worth ({PILOT_WORTH_TRIALS} trials of one movement): worn fraction / visible wear, worst "
              f"kept movement (power level ≤ 7)", "< 1 (no visible wear)", cal["pilot_kept_worst"], 0.0, 1.0,
              "ratio", "D ch. 6 (Fig. 6-7)", cal["pilot_mildest_by_level"], kind="calibrated",
              calibration="wear_power_exponent β: visible wear at the geometric middle of the worst level-7 and the "
                          "mildest level-8 movement after a pilot's worth",
              note="a pilot's worth: D's 10 pilot textures × 6 repetitions of each movement; the worst kept one is "
                   "2 N @ 1 cm/s"),
        Claim(f"a pilot's worth ({PILOT_WORTH_TRIALS} trials of one movement): worn fraction / visible wear, "
              f"mildest excluded movement (power level 8)", "≥ 1 (visible wear)", cal["pilot_level8_mildest"], 1.0,
              np.inf, "ratio", "D ch. 6 (Fig. 6-7)", cal["pilot_mildest_by_level"], kind="calibrated",
              calibration="wear_power_exponent β (as above); without the power factor (β = 0, k set by the training "
                          "count) the mildest level-8 movement reaches 0.07 of visible wear",
              note="D excluded the lower-right half plane (levels above 7) 'due to the high wear rate'; the "
                   "mildest level-8 movement is 0.32 N @ 10 cm/s"),
    ]


def _trials(b: Bench, textures, movements, trials: int, stage: str, skin: Skin | None = None):
    """Rows of rig trials run in process, each on a fresh skin or, given ``skin``, on one as ``skin`` is (its
    ridges and serial; it does not wear); seeds from the trial's identity."""
    from dataclasses import replace

    from bench.experiments.trials import run_trial_task, sweep_tasks

    tasks = sweep_tasks(textures, movements, trials, b.seed, b.fidelity, stage=stage)
    if skin is not None:
        tasks = [replace(t, fingerprints=skin.fingerprints, ridge_height_m=skin.ridge_height_m,
                         skin_serial=skin.serial) for t in tasks]
    return [run_trial_task(t) for t in tasks]


#: skin wear rows: the texture (60-grit sandpaper) and movement whose roughness the skin's state changes
WEAR_TEXTURE, WEAR_MOVEMENT = 901, Movement(0.5, 0.025)
#: skin wear rows: a worn skin's ridge height (m; a quarter of a new one's)
WORN_RIDGE_M = 0.05e-3
#: skin wear rows: trials per skin for the spread of a fresh skin and of its replacement
SPREAD_TRIALS = 12


def _roughness_on(b: Bench, skin: Skin, trials: int, stage: str) -> list[float]:
    """Roughness (ln bits²) of ``trials`` rig trials of :data:`WEAR_MOVEMENT` on :data:`WEAR_TEXTURE` with ``skin``
    as it is; ``stage`` names the trials' seeds."""
    return [r["roughness"] for r in _trials(b, [WEAR_TEXTURE], [WEAR_MOVEMENT], trials, stage, skin=skin)]


def _replacement_spread(b: Bench, worn: Skin, fresh: list[float]) -> tuple[float, list[float]]:
    """The roughness spread (SD) of :data:`SPREAD_TRIALS` trials on ``worn.replace()`` (seeds of their own) over
    that of ``fresh`` (the first skin's trials), and the replacement's roughness values."""
    renewed = _roughness_on(b, worn.replace(), SPREAD_TRIALS, "claims-wear-replaced")
    return float(np.std(renewed) / np.std(fresh)), renewed


def _skin_wear_spread_claims(b: Bench) -> list[Claim]:
    """D ch. 6: worn ridges make roughness less repeatable, and a fresh skin restores it."""
    fresh = _roughness_on(b, Skin(), SPREAD_TRIALS, "claims-wear")
    worn_skin = Skin(ridge_height_m=WORN_RIDGE_M)
    worn = _roughness_on(b, worn_skin, 6, "claims-wear")
    ratio, renewed = _replacement_spread(b, worn_skin, fresh)
    return [
        Claim("worn ridges (25 % left): roughness spread over fresh", "grows", float(np.std(worn) / np.std(fresh)),
              1.0, np.inf, "ratio", "D ch. 6", {"fresh": fresh, "worn": worn}, kind="consistency",
              note="the per-trial ridge-gain scatter grows with wear by construction (irregularity)"),
        Claim("the worn skin replaced: roughness spread over the first skin's fresh spread", "back within [0.5, 2]",
              ratio, 0.5, 2.0, "ratio", "D ch. 6", {"fresh": fresh, "replaced": renewed, "worn": worn},
              kind="consistency",
              note=f"{SPREAD_TRIALS} trials of {WEAR_MOVEMENT.label()} on 60-grit on each skin, the replacement's "
                   "with seeds of their own; in the model a replaced skin is a new one by construction "
                   "(Skin.replace renews the ridges, and the ridge-gain scatter grows only with the worn fraction), "
                   f"so the ratio leaves 1 only by the sampling spread of two sets of {SPREAD_TRIALS} (the SD "
                   "ratio of two such samples of one normal distribution falls within [0.5, 2] ~97 % of the time); "
                   "the worn skin's spread, for comparison, in the detail"),
    ]


def _highest_rank(values: dict[int, float], textures) -> int:
    """The highest rank (0 = the lowest value of ``values``, texture → value) among ``textures``: all of them lie in
    the bottom half when it is below ``len(values) // 2``."""
    order = sorted(values, key=values.get)
    return max(order.index(t) for t in textures)


def _mean(rows, prop, **match):
    vals = [r[prop] for r in rows if all(np.isclose(r[k], v) for k, v in match.items())]
    return float(np.mean(vals))


@claim_group("texture-properties")
def texture_property_claims(b: Bench) -> list[Claim]:
    """D ch. 6's pilot observations among the named textures, and the force/velocity trends (rig trials)."""
    named = {43: "graphite", 46: "polished aluminum", 47: "rubber", 30: "foam", 84: "satin", 87: "rayon",
             100: "burlap", 10: "velcro hooks"}
    main = Movement(0.5, 0.025)
    rows = _trials(b, list(named), [main], 6, "claims-pilot")  # D's pilot: 6 trials per texture and movement
    by = {p: {t: _mean(rows, p, texture=t) for t in named} for p in ("traction", "roughness", "fineness")}
    # traction differs little between the grippiest surfaces: rank it on the mean over four movements
    spread = _trials(b, list(named), [Movement(0.2, 0.01), main, Movement(1.26, 0.01), Movement(2.0, 0.0631)], 2,
                     "claims-traction")
    by["traction"] = {t: _mean(spread, "traction", texture=t) for t in named}
    rank = {p: sorted(named, key=lambda t: by[p][t]) for p in by}  # ascending

    def position(p, t):  # 0 = lowest
        return rank[p].index(t)

    out = [
        Claim("graphite has the lowest traction (8 named textures, mean of 4 movements)", "lowest",
              position("traction", 43), 0, 0, "rank", "D ch. 6", {"traction_A": by["traction"]}, kind="derived",
              note="traction ∝ friction, and graphite's µ comes from published lubricant data"),
        Claim("polished aluminum and rubber have the highest traction", "the top two",
              min(position("traction", 46), position("traction", 47)), len(named) - 2, len(named) - 1, "rank",
              "D ch. 6", kind="derived", note="from the library's silicone-on-smooth-solid friction class"),
        Claim("foam, satin, rayon, burlap: the highest roughness", "the top four",
              min(position("roughness", t) for t in (30, 84, 87, 100)), len(named) - 4, len(named) - 1, "rank",
              "D ch. 6", {"roughness": by["roughness"]}, kind="prediction",
              deviation="satin is a smooth filament weave in the library (2 µm RMS, 1.4 mm relief): it slides "
                        "~3.6 ln units below rayon, as the ridges average relief finer than their pitch; and the "
                        "friction fluctuation every surface has (3 % RMS, 1/q) puts the grippiest smooth surfaces, "
                        "polished aluminum and rubber (µ ≈ 1.2–1.3), ~0.8 ln units above satin (µ 0.45): the "
                        "fluctuating force is ∝ µ·N, so high friction means more of it"),
        Claim("polished aluminum has the lowest roughness", "lowest", position("roughness", 46), 0, 0, "rank",
              "D ch. 6", kind="prediction",
              deviation="with the friction fluctuation (3 % RMS of µ, the amplitude from a finger on glass, "
                        "Derler et al. 2013) aluminum's µ = 1.2 makes a 1/f-like signal ~9 ln units over the floor, "
                        "above graphite (µ 0.3) and satin (µ 0.45); without it aluminum made no signal at all and "
                        "came lowest. D's lowest roughness on aluminum implies a smaller fluctuation of a silicone "
                        "skin on polished metal in the 20–700 Hz band than a finger's on glass; the amplitude was "
                        "taken from the literature and not adjusted toward this ordering"),
        Claim("graphite and satin: the highest spectral centroid", "the top two",
              min(position("fineness", 43), position("fineness", 84)), len(named) - 2, len(named) - 1, "rank",
              "D ch. 6", {"fineness": by["fineness"]}, kind="prediction",
              note="graphite and satin lead by small margins (~0.06 ln Hz over rubber, the third): the 330 Hz "
                   "skin/fluid resonance shapes every broadband signal; aluminum and rubber no longer keep the rest "
                   "floor's ~480 Hz since the friction fluctuation (power ∝ 1/f) makes them slide audibly, but "
                   "they sit mid-table (~280 Hz), not low as D found"),
        Claim("burlap and velcro: low spectral centroid (bottom half)", "bottom half",
              _highest_rank(by["fineness"], (100, 10)), 0, len(named) // 2 - 1, "rank", "D ch. 6",
              kind="prediction"),
        Claim("polished aluminum and rubber: low spectral centroid (bottom half; 1/f spectra)", "bottom half",
              _highest_rank(by["fineness"], (46, 47)), 0, len(named) // 2 - 1, "rank", "D ch. 6",
              {"fineness": by["fineness"]}, kind="prediction",
              deviation="their tangential force while sliding is 1/f-like as D describes (at 0.5 N @ 2.5 cm/s a "
                        "log-log slope of −1.3 and −1.1 over 20–200 Hz, centroids ~95 and ~116 Hz): aluminum's is "
                        "wholly the friction fluctuation (3 % RMS of µ, power ∝ 1/q; without it aluminum makes no "
                        "signal and keeps the rest floor's ~470 Hz), rubber's mostly its own micro-roughness (~316 "
                        "Hz without the fluctuation). But the coarse textures' forces sit lower still (rayon, "
                        "burlap, velcro, foam: centroids 72–88 Hz), so the two rank 5th and 6th of 8 already in the "
                        "force; and PAC sees every force through the 330 Hz skin/fluid resonance, which turns their "
                        "~10 % of force power within 200–400 Hz into ~85 % of PAC's: their centroids come out at "
                        "~290 Hz, beside graphite's and satin's (~300 Hz), while the coarse textures keep 27–54 % of "
                        "PAC power below 100 Hz (160–220 Hz). The fluctuation's spectrum matters: with power ∝ 1/q³ "
                        "instead of 1/q both fall into the bottom half (and aluminum to the lowest roughness), but "
                        "burlap or velcro leaves it; the 1/q is the literature's 1/f friction background, not "
                        "adjusted"),
    ]
    # centroid against velocity at 0.2 N: rises for coarse rough textures, falls for graphite
    vel = [Movement(0.2, 0.01), Movement(0.2, 0.0631)]
    rows_v = _trials(b, [10, 30, 87, 100, 43], vel, 4, "claims-velocity")
    rises = [_mean(rows_v, "fineness", texture=t, velocity_m_per_s=0.0631)
             - _mean(rows_v, "fineness", texture=t, velocity_m_per_s=0.01) for t in (10, 30, 87, 100)]
    graphite = (_mean(rows_v, "fineness", texture=43, velocity_m_per_s=0.0631)
                - _mean(rows_v, "fineness", texture=43, velocity_m_per_s=0.01))
    out += [
        Claim("centroid rises with velocity at 0.2 N: velcro, foam, rayon, burlap", "all four rise",
              float(sum(r > 0 for r in rises)), 4, 4, "textures", "D ch. 6", {"rise_ln_Hz": rises},
              kind="prediction"),
        Claim("graphite's centroid falls with velocity at 0.2 N", "falls", graphite, -np.inf, 0.0, "ln Hz",
              "D ch. 6", kind="prediction",
              deviation="graphite slides 17–24 dB above the rest floor, so its centroid is the resonance's and "
                        "rises a little with speed as the sub-100 Hz share shrinks; in the model a centroid falls "
                        "with speed only for a texture near the floor at low speed"),
    ]
    # across textures: faster sliding raises vibration amplitude; more force damps it (D ch. 6)
    trend = _trials(b, [2, 30, 43, 84, 100], [Movement(0.5, 0.01), Movement(0.5, 0.063), Movement(1.26, 0.025),
                                             Movement(0.2, 0.025)], 4, "claims-trends")
    faster = [_mean(trend, "roughness", texture=t, velocity_m_per_s=0.063)
              - _mean(trend, "roughness", texture=t, velocity_m_per_s=0.01, force_N=0.5) for t in (2, 30, 43, 84, 100)]
    heavier = [_mean(trend, "roughness", texture=t, force_N=1.26)
               - _mean(trend, "roughness", texture=t, force_N=0.2) for t in (2, 30, 43, 84, 100)]
    out += [
        Claim("faster sliding raises vibration power (5 textures, 0.5 N, 1 → 6.3 cm/s)", "rises on average",
              float(np.mean(faster)), 0.0, np.inf, "ln units", "D ch. 6", {"change_ln": faster},
              kind="prediction",
              note="per texture in the detail"),
        Claim("more force damps vibration power (5 textures, 0.2 → 1.26 N at 2.5 cm/s)", "falls on average",
              float(np.mean(heavier)), -np.inf, 0.0, "ln units", "D ch. 6", {"change_ln": heavier},
              kind="prediction", note="D ch. 3 saw the opposite on a coarse grating (see the grating rows)",
              deviation="below the 2 N knee the sliding vibration is tangential and grows ~N^1.7–1.9 (friction "
                        "∝ µN, the ridges' slope force ∝ N; a smooth skin rises as much); the one factor that "
                        "falls with force, the patch-averaged height on the normal load, carries < 1e-3 of the "
                        "power, and the power falls only above the knee, where the skin meets the core. Every "
                        "force-varying measurement found rises with force (D ch. 3 on the grating; an accelerometer "
                        "skin, Howe & Cutkosky 1989; human skin vibration at half and twice the spontaneous force); "
                        "D ch. 6 prints no roughness-against-force values, and no damping mechanism (ridge crests "
                        "widening, contact loss, fluid squeezed out under the patch) is sourced well enough to add "
                        "(docs/experiment/force_damping.md)"),
    ]
    # across the whole library at one movement: roughness and traction correlate negatively (D ch. 6)
    from bench.textures.library import dissertation_textures, load_library

    library = dissertation_textures(load_library())
    lib_rows = _trials(b, library, [main], 1, "claims-library")
    r = float(np.corrcoef([x["traction"] for x in lib_rows], [x["roughness"] for x in lib_rows])[0, 1])
    out.append(Claim("roughness and traction across the 117 textures (0.5 N @ 2.5 cm/s)", "negative correlation", r,
                     -1.0, 0.0, "Pearson r", "D ch. 6 (Table 6-3)", kind="derived",
                     note="partly built in: the library's friction falls with roughness for solids (its sources say "
                          "so), so this is not an independent prediction; the friction fluctuation (∝ µ) gives the "
                          "grippy smooth surfaces a signal and weakened r from −0.53 to −0.22"))
    # smooth surfaces give no harmonics; a grating does: a line is a narrow peak of the sliding PAC spectrum (Welch,
    # 256-sample segments, 8.6 Hz bins) over the spectrum's own running median (9 bins, ±34 Hz), 20–700 Hz; the
    # rise over the resting spectrum is kept in the detail (a broadband signal rises without any line)
    from scipy.ndimage import median_filter
    from scipy.signal import welch

    lines, rise = {}, {}
    for number in (46, 24, 902):
        s_ = Slide(2.0, texture(number), 0.5, 0.05, 0.1, approach_s=0.1, hold_s=0.3)
        t, pac = _pac(b, s_, s_.slide_end_s)
        x = pac[(t >= s_.slide_start_s + 0.1) & (t < s_.slide_end_s - 0.05)]
        rest = pac[t < 1.9]
        f, p_slide = welch(x - x.mean(), fs=PAC_RATE_HZ, nperseg=256)
        _, p_rest = welch(rest - rest.mean(), fs=PAC_RATE_HZ, nperseg=256)
        band = (f >= 20) & (f <= 700)
        lines[number] = float(10 * np.log10(np.max(p_slide[band] / median_filter(p_slide, 9, mode="nearest")[band])))
        rise[number] = float(10 * np.log10(np.max(p_slide[band] / p_rest[band])))
    detail = {"max_peak_over_median_dB": lines, "max_rise_over_rest_dB": rise}
    out.append(Claim("smooth surfaces (polished aluminum, glass): no spectral lines while sliding",
                     "no peak ≥ 10 dB over the spectrum's running median", max(lines[46], lines[24]), -np.inf, 10.0,
                     "dB", "D ch. 6", detail, kind="prediction",
                     note="smooth surfaces do make a broadband (1/f-like) signal from the friction fluctuation, ~53 "
                          "dB over rest, as D describes ('1/f-like spectra, no harmonics'); until the fluctuation "
                          "existed they made none, and this row measured the rise over rest instead; the 3 mm "
                          "grating (T902) in the detail shows the same detector finding a line (its harmonics: the "
                          "sliding group)"))
    # wear: after wear, roughness's trial-to-trial spread grows; a fresh skin restores it
    return out + _skin_wear_spread_claims(b)
