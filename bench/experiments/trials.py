"""Sliding trials as independent tasks: one rig trial per (texture, movement, repetition), its properties out.

A :class:`TrialTask` says everything a trial depends on — texture, movement, repetition, the skin as it is at
that trial, fidelity, noise and a seed derived from the trial's identity — so trials run in any order on any
worker and give identical results.  Skin wear is deterministic (the wear law of :mod:`emulator.skin` on the
nominal movement), so the skin a trial meets is known before anything runs: :func:`schedule_skin` walks a
session's trials in order and hands each its skin, replacing the skin at the first visible wear, as D did.
:func:`wear_calibration` re-derives the wear law's two calibrated knobs from D's wear observations.

:func:`run_trial_task` is the pure, module-level function the campaign engine maps; :func:`sweep` runs a grid of
trials (the pilot's 36 movements × textures × repetitions) and returns a table of rows.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from bench.experiments.design import PILOT_WORTH_TRIALS
from bench.rigs.texture_rig import Movement, RigSettings, TextureRig, movement_grid, spi_faults_from_text
from bench.textures.properties import pac_at_rails, properties
from emulator.params import SensorParams
from emulator.sensor import NoiseSources
from emulator.skin import Skin, contact_patch_area_m2

#: fraction of the ridge height lost when the flat worn on a crest becomes visible (derived from the ridge geometry,
#: :attr:`emulator.skin.Skin.first_visible_wear_fraction`, 0.032): D replaced the skin "if there were any visible
#: signs of wear"
FIRST_VISIBLE_WEAR = Skin().first_visible_wear_fraction
#: D's training: the three movements D kept (grid ids: 1.26 N @ 1 cm/s, 0.2 N @ 6.31 cm/s, 0.5 N @ 2.5 cm/s, all
#: of power level 6) × 5 trials on each of 117 textures, texture after texture
D_TRAINING_MOVEMENTS = (24, 4, 14)
D_TRAINING_TRIALS = 5
#: the rig's sliding distance per trial (m)
TRIAL_DISTANCE_M = 0.05


@dataclass(frozen=True)
class TrialTask:
    """One rig trial (SI units)."""

    texture: int
    force_N: float
    velocity_m_per_s: float
    trial: int
    seed: int
    movement_id: int = -1
    fidelity: str = "default"
    fingerprints: bool = True
    ridge_height_m: float = Skin().ridge_height_new_m
    skin_serial: int = 1
    noise_scale: float = 1.0  # 2.0: every noise source doubled (an ablation)
    stepper_noise_Pa: float = 0.0  # the rig's stepper background, median RMS in the PAC band (RigSettings)
    stage: str = ""  # which stage of an experiment the trial belongs to (pilot, training, validation)
    library: str = ""  # the texture library file the texture comes from ("": the shipped one)
    #: SPI faults on the rig's bus for part of the trial (:func:`bench.rigs.texture_rig.spi_fault_text`'s form:
    #: ``start_s=0.25,end_s=0.35,miso_flip_bit=1``, windows joined by ``; ``; "": none)
    spi_faults: str = ""

    def movement(self) -> Movement:
        return Movement(self.force_N, self.velocity_m_per_s)


def trial_seed(base_seed: int, *identity) -> int:
    """A 63-bit seed from the experiment's seed and a trial's identity (texture, movement, repetition, stage)."""
    h = hashlib.sha256(repr((int(base_seed),) + tuple(identity)).encode()).digest()
    return int.from_bytes(h[:8], "little") >> 1


#: every noise amplitude of the sensor (SensorParams fields, scaled linearly by the noise ablation); the bridge's
#: Johnson noise scales as √R, so its resistance goes with the square (and the amplifier's current noise, which
#: flows through R, with the inverse); mains harmonics are ratios of the fundamental
NOISE_AMPLITUDES = ("adc_noise_rms_bits", "adc_reference_noise_ppm", "pac_path_noise_rms_bits",
                    "amp_voltage_noise_V_per_rtHz", "amp_current_noise_A_per_rtHz", "stage2_voltage_noise_V_per_rtHz",
                    "mains_amplitude_V", "spi_coupling_rms_V", "tdc_noise_V")


#: how each parameter the noise scale k changes goes with k: the amplitudes ×k, the bridge's resistance ×k² (its
#: Johnson noise goes as √R) and the amplifier's current noise ×1/k (it flows through R: ×k overall)
NOISE_SCALING = {**{name: 1 for name in NOISE_AMPLITUDES}, "amp_current_noise_A_per_rtHz": -1,
                 "bridge_resistance_ohm": 2}
_POWER = {1: "×k", 2: "×k²", -1: "×1/k"}
_WHY = {"bridge_resistance_ohm": "the bridge's resistance goes ×k² as its Johnson noise goes with √R",
        "amp_current_noise_A_per_rtHz": "the amplifier's current noise goes ×1/k as it flows through R ×k²"}


def _three_digits(x: float, up: bool) -> float:
    """``x`` (> 0) to three significant digits, rounded up or down (an end of a range stays inside it)."""
    scale = 10.0 ** (2 - math.floor(math.log10(x)))
    return (math.ceil if up else math.floor)(x * scale) / scale


def noise_scale_range(base: SensorParams | None = None) -> tuple[tuple[float, str, str], tuple[float, str, str]]:
    """The scales k > 0 the sensor ``base`` (default: nominal) takes, as its two ends (k, the scaled parameter
    that sets it, and why: how it goes with k and which end of its documented range it reaches there); an end no
    parameter sets is 0 or inf with no parameter.  k is dimensionless."""
    p = base or SensorParams()
    lo, hi = (0.0, "", ""), (math.inf, "", "")
    for name, power in NOISE_SCALING.items():
        v = getattr(p, name)
        if v <= 0:
            continue  # 0 stays 0 at every scale
        meta = SensorParams.__dataclass_fields__[name].metadata
        (r_lo, r_hi), unit = meta["range"], meta["unit"]
        at_min = (r_lo / v) ** (1 / power) if r_lo > 0 else (0.0 if power > 0 else math.inf)
        at_max = (r_hi / v) ** (1 / power)
        for k, limit, word in ((at_min, r_lo, "minimum"), (at_max, r_hi, "maximum")):
            grows = (word == "maximum") == (power > 0)  # this end bounds k from above
            why = f"{name} {_POWER[power]} passes its {word} {limit:g} {unit}"
            if grows and k < hi[0]:
                hi = (k, name, why)
            elif not grows and k > lo[0]:  # (0: no bound)
                lo = (k, name, why)
    return lo, hi


def noise_scale_problem(noise_scale: float, base: SensorParams | None = None,
                        most: tuple[float, str] | None = None, factor: float = 1.0) -> str | None:
    """Why the sensor ``base`` (default: nominal) cannot take ``noise_scale`` (None when it can): 0 turns every
    noise source off; any other scale must leave each scaled parameter inside its documented range
    (:func:`noise_scale_range`; the hint names the parameter that limits each end, and its ends, rounded inward
    to three digits, are scales the sensor takes; they hold 1, as ``base`` is a valid sensor). ``most``: the
    caller's own largest scale and what sets it (an experiment file's field), the hint's upper end when lower.
    ``factor``: ``noise_scale`` is the value a user gave × ``factor`` (an ablation's: double-noise, 2), and the
    hint gives the values the user can give, each taken both as it is and × ``factor``.
    ``noise_scale`` and ``factor`` are scale factors (dimensionless)."""
    try:
        _params(noise_scale, base)
    except ValueError as e:
        (lo, lo_name, lo_why), (hi, hi_name, hi_why) = noise_scale_range(base)
        once = f" once ×{factor:g}"
        if factor > 1:  # the given value's top: the sensor's top ÷ factor
            hi, hi_why = hi / factor, hi_why + once
        elif 0 < factor < 1:
            lo, lo_why = lo / factor, lo_why + once
        if most is not None and most[0] < hi:
            hi, hi_name, hi_why = most[0], "", most[1]
        notes = "".join(f"; {_WHY[n]}" for n in dict.fromkeys((lo_name, hi_name)) if n in _WHY)
        lo_s, hi_s = f"{_three_digits(lo, up=True):g}", f"{_three_digits(hi, up=False):g}"
        given = f"values before ×{factor:g}; " if factor != 1 else ""
        return (f"{e} — give 0 (every noise source off) or {lo_s}…{hi_s} ({given}below {lo_s}, {lo_why}; above "
                f"{hi_s}, {hi_why}{notes})")
    return None


def noise_sources(noise_scale: float) -> NoiseSources:
    """The noise sources a trial at ``noise_scale`` runs with: none at 0 (quantization remains), else all."""
    return NoiseSources.none() if noise_scale == 0 else NoiseSources()


def _params(noise_scale: float, base: SensorParams | None = None) -> SensorParams:
    """The parameters ``base`` (default: nominal) with every noise source scaled by ``noise_scale`` in amplitude
    (:data:`NOISE_SCALING`; 0: ``base`` as it is, the sources being switched off by :func:`noise_sources`)."""
    p = base or SensorParams()
    if noise_scale in (0.0, 1.0):
        return p
    return p.replace(**{name: getattr(p, name) * noise_scale ** power for name, power in NOISE_SCALING.items()})


def run_trial_task(task: TrialTask) -> dict:
    """Run one trial on the rig; returns a flat row: the task, the three properties, the PAC samples at the ADC's
    rails in their window (``pac_at_rails``), the samples the host rejected and the rig left out
    (``rejected_samples``, every channel's: 0 without SPI faults), the true force, timing."""
    from bench.textures.library import texture

    windows, problems = spi_faults_from_text(task.spi_faults, "spi_faults")
    if problems:
        raise ValueError("; ".join(problems))
    skin = Skin(fingerprints=task.fingerprints, ridge_height_m=task.ridge_height_m, serial=task.skin_serial)
    rig = TextureRig(skin=skin, params=_params(task.noise_scale), fidelity=task.fidelity,
                     noise=noise_sources(task.noise_scale),
                     settings=RigSettings(stepper_noise_Pa=task.stepper_noise_Pa), wear=False, spi_faults=windows)
    trial = rig.run_trial(texture(task.texture, task.library or None), task.movement(), seed=task.seed,
                          trial=task.trial)
    row = asdict(task)
    row.update(properties(trial.recording))
    row.update(pac_at_rails=pac_at_rails(trial.recording),
               rejected_samples=sum(n for by_status in trial.extra["rejected_samples"].values()
                                    for n in by_status.values()),
               true_normal_N=trial.true_normal_N, start_position_m=trial.start_position_m,
               simulated_s=float(trial.recording.pac_t[-1]), wall_s=trial.wall_s)
    return row


def clipped_note(rows: list[dict]) -> str:
    """A sentence on the trials whose PAC reached the ADC's rails in the measurement window (``pac_at_rails`` > 0),
    or "" when none did: their roughness and fineness are of a clipped vibration."""
    clipped = sum(1 for r in rows if r["pac_at_rails"])
    if not clipped:
        return ""
    return (f"{clipped} of {len(rows)} trials had PAC at the ADC's rails (code 0 or 4095) in their measurement window "
            f"(trials.csv: pac_at_rails, the samples there): their roughness and fineness are of a clipped vibration")


def schedule_skin(tasks: list[TrialTask], wear: bool = True, replace_at: float | None = FIRST_VISIBLE_WEAR,
                  params: SensorParams | None = None) -> tuple[list[TrialTask], list[dict]]:
    """Give each task (in the given order: the session's order) the skin it meets: wear after each trial and,
    with ``replace_at``, a fresh skin once the ridges lost that fraction of their height (default: the first
    visible wear). Returns the tasks and the skin's history (one row per trial: serial, ridge height before)."""
    p = params or SensorParams()
    skin = Skin(fingerprints=tasks[0].fingerprints if tasks else True)
    out, history = [], []
    for t in tasks:
        if replace_at is not None and skin.fingerprints and skin.worn_fraction >= replace_at:
            skin = skin.replace()
        out.append(replace(t, fingerprints=skin.fingerprints, ridge_height_m=skin.ridge_height_m,
                           skin_serial=skin.serial))
        history.append({"trial_index": len(out) - 1, "skin": skin.serial, "ridge_height_m": skin.ridge_height_m})
        if wear:
            area = contact_patch_area_m2(t.force_N, p.contact_radius_at_1N_m)
            skin.wear(t.force_N, TRIAL_DISTANCE_M, area, velocity_m_per_s=t.velocity_m_per_s)
    return out, history


def listed_twice(values) -> list:
    """The values that occur more than once in ``values``, sorted."""
    values = list(values)
    return sorted({v for v in values if values.count(v) > 1})


def _movement_ids(movements: list[Movement], movement_ids) -> list[int]:
    """The ids naming ``movements``: ``movement_ids`` (checked: one per movement, none twice) or, without them, the
    positions (the grid ids when ``movements`` is the whole grid)."""
    if movement_ids is None:
        return list(range(len(movements)))
    ids = [int(i) for i in movement_ids]
    if len(ids) != len(movements):
        raise ValueError(f"{len(ids)} movement ids for {len(movements)} movements")
    if listed_twice(ids):
        raise ValueError(f"movement id(s) {listed_twice(ids)} listed twice")
    return ids


def sweep_tasks(textures, movements: list[Movement] | None = None, trials: int = 6, seed: int = 0,
                fidelity: str = "default", fingerprints: bool = True, stage: str = "sweep",
                noise_scale: float = 1.0, movement_ids: list[int] | None = None,
                stepper_noise_Pa: float = 0.0, library: str = "", spi_faults: str = "") -> list[TrialTask]:
    """Tasks for every texture × movement × repetition, each on a fresh skin (wear is shown apart, by
    :func:`wear_per_movement`).  ``movement_ids`` name the movements (grid ids; default their positions, which are
    the grid ids for the whole grid); a trial's seed comes from its identity (``seed``, ``stage``, texture,
    movement id, repetition), whatever the order of the lists.  ``spi_faults``: every trial's
    (:attr:`TrialTask.spi_faults`).  A texture or movement id listed twice is refused
    (ValueError)."""
    movements = list(movements) if movements is not None else movement_grid()
    ids = _movement_ids(movements, movement_ids)
    textures = [int(t) for t in textures]
    if listed_twice(textures):
        raise ValueError(f"texture(s) {listed_twice(textures)} listed twice")
    out = []
    for tex in textures:
        for m_id, m in zip(ids, movements):
            for k in range(trials):
                out.append(TrialTask(tex, m.force_N, m.velocity_m_per_s, k, trial_seed(seed, stage, tex, m_id, k),
                                     m_id, fidelity, fingerprints, stage=stage, noise_scale=noise_scale,
                                     stepper_noise_Pa=stepper_noise_Pa, library=library, spi_faults=spi_faults))
    return out


def wear_per_movement(movements: list[Movement] | None = None, trials: int = PILOT_WORTH_TRIALS,
                      distance_m: float = TRIAL_DISTANCE_M, params: SensorParams | None = None,
                      movement_ids: list[int] | None = None) -> list[dict]:
    """Each movement's wear on a fresh skin: ridge height lost (m) and worn fraction after ``trials`` trials (default
    a pilot's worth), whether that is visible, and the trials it takes to reach the first visible wear; rows named
    by ``movement_ids`` (grid ids; default the positions, as :func:`sweep_tasks`)."""
    p = params or SensorParams()
    movements = list(movements) if movements is not None else movement_grid()
    rows = []
    for m_id, m in zip(_movement_ids(movements, movement_ids), movements):
        skin = Skin()
        area = contact_patch_area_m2(m.force_N, p.contact_radius_at_1N_m)
        per_trial = skin.height_lost(m.force_N, distance_m, area, m.velocity_m_per_s)
        for _ in range(trials):
            skin.wear(m.force_N, distance_m, area, velocity_m_per_s=m.velocity_m_per_s)
        lost = skin.ridge_height_new_m - skin.ridge_height_m
        visible_m = skin.first_visible_wear_fraction * skin.ridge_height_new_m
        rows.append({"movement_id": m_id, "force_N": m.force_N, "velocity_m_per_s": m.velocity_m_per_s,
                     "trials": trials, "ridge_lost_m": lost, "worn_fraction": lost / skin.ridge_height_new_m,
                     "visible_wear": bool(skin.worn_fraction >= skin.first_visible_wear_fraction),
                     "trials_to_visible_wear": int(np.ceil(visible_m / per_trial)) if per_trial > 0 else -1,
                     # the trial lasts distance / v at the rig: a fast trial is shorter
                     "lost_per_second_m": per_trial * m.velocity_m_per_s / distance_m})
    return rows


def d_training_tasks(textures=None) -> list[TrialTask]:
    """D's training session in the shipped experiment's order: texture after texture (default the library's 117),
    D's three movements × 5 trials each (seeds 0: only the skin schedule is of interest)."""
    from bench.textures.library import dissertation_textures, load_library

    grid = movement_grid()
    textures = textures if textures is not None else dissertation_textures(load_library())
    return [TrialTask(int(tex), grid[m].force_N, grid[m].velocity_m_per_s, k, 0, m)
            for tex in textures for m in D_TRAINING_MOVEMENTS for k in range(D_TRAINING_TRIALS)]


def wear_calibration(params: SensorParams | None = None) -> dict:
    """What the wear law gives for D's two wear observations, and the (k, β) that meet them at their centres.

    (a) training: skins used over D's training session replaced at the first visible wear (D: 3 skins, "replaced
    two times"); centre: the session wears 2.5 skins' worth of visible wear.  (b) pilot: worn fraction / first
    visible wear after a pilot's worth of each movement on a fresh skin, worst of the kept levels (≤ 7) and mildest
    of level 8 (D: level ≤ 7 kept, level 8 excluded for wear); centre: the visible wear at the geometric mean of the
    two.  ``solved`` holds (k, β) meeting both centres; the shipped Skin defaults are those, rounded."""
    from scipy.optimize import brentq

    from bench.experiments.exploration import movement_grid as levels

    p = params or SensorParams()
    skin, grid, lv = Skin(), movement_grid(), levels()["power_level"]
    tasks, history = schedule_skin(d_training_tasks(), params=p)
    pilot = wear_per_movement(params=p)
    seen = np.array([r["worn_fraction"] for r in pilot]) / skin.first_visible_wear_fraction

    def per_trial(m, k, beta):  # height lost per trial of movement m (m) with knobs k, β
        area = contact_patch_area_m2(m.force_N, p.contact_radius_at_1N_m)
        return replace(skin, wear_coefficient=k, wear_power_exponent=beta).height_lost(
            m.force_N, TRIAL_DISTANCE_M, area, m.velocity_m_per_s)

    visible_m = skin.first_visible_wear_fraction * skin.ridge_height_new_m
    worst7 = grid[int(np.argmax(np.where(lv <= 7, seen, -np.inf)))]
    mildest8 = grid[int(np.argmin(np.where(lv == 8, seen, np.inf)))]

    def k_for(beta):  # (a) at its centre: the session wears 2.5 × the visible wear
        unit = sum(per_trial(grid[t.movement_id], 1.0, beta) for t in tasks)
        return 2.5 * visible_m / unit

    def gap(beta):  # (b) at its centre, in log units
        k = k_for(beta)
        return np.log(PILOT_WORTH_TRIALS * np.sqrt(per_trial(worst7, k, beta) * per_trial(mildest8, k, beta))
                      / visible_m)

    def margin(beta, which):  # (b)'s two inequalities at β, k from (a)'s centre: > 0 when met
        k = k_for(beta)
        m = worst7 if which == "kept" else mildest8
        return np.log(visible_m / (PILOT_WORTH_TRIALS * per_trial(m, k, beta))) * (1 if which == "kept" else -1)

    beta = brentq(gap, 1.5, 8.0)
    return {"first_visible_wear_fraction": skin.first_visible_wear_fraction,
            "training_trials": len(tasks), "training_skins": history[-1]["skin"],
            "pilot_worth_trials": PILOT_WORTH_TRIALS,
            "pilot_kept_worst": float(np.max(seen[lv <= 7])), "pilot_level8_mildest": float(np.min(seen[lv == 8])),
            "pilot_mildest_by_level": {int(L): float(np.min(seen[lv == L])) for L in np.unique(lv)},
            "solved": {"wear_coefficient": k_for(beta), "wear_power_exponent": beta},
            "beta_range": (brentq(margin, 0.5, beta, args=("level8",)), brentq(margin, beta, 8.0, args=("kept",)))}


def sweep(tasks: list[TrialTask], spec=None, client=None, progress: bool = True) -> list[dict]:
    """Run ``tasks`` on the campaign engine (Dask); rows in task order."""
    from bench.campaigns.engine import run_tasks

    return run_tasks(run_trial_task, tasks, spec=spec, client=client, progress=progress, desc="trials")


def rows_to_arrays(rows: list[dict]) -> dict[str, np.ndarray]:
    """Column arrays of a list of row dicts (same keys in every row)."""
    if not rows:
        return {}
    return {k: np.array([r[k] for r in rows]) for k in rows[0]}
