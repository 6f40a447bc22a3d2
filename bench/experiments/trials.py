"""Sliding trials as independent tasks: one rig trial per (texture, movement, repetition), its properties out.

A :class:`TrialTask` says everything a trial depends on — texture, movement, repetition, the skin as it is at
that trial, fidelity, noise and a seed derived from the trial's identity — so trials run in any order on any
worker and give identical results.  Skin wear is deterministic (Archard's law on the nominal movement), so the
skin a trial meets is known before anything runs: :func:`schedule_skin` walks a session's trials in order and
hands each its skin, replacing the skin when wear becomes detectable, as D did.

:func:`run_trial_task` is the pure, module-level function the campaign engine maps; :func:`sweep` runs a grid of
trials (the pilot's 36 movements × textures × repetitions) and returns a table of rows.
"""

from __future__ import annotations

import hashlib
from dataclasses import asdict, dataclass, replace

import numpy as np

from bench.rigs.texture_rig import Movement, TextureRig, movement_grid
from bench.textures.properties import properties
from emulator.params import SensorParams
from emulator.sensor import NoiseSources
from emulator.skin import Skin, contact_patch_area_m2

#: relative ridge height lost at which wear counts as detectable and the skin is replaced (model choice: D
#: replaced the skin "when wear was visible")
DETECTABLE_WEAR = 0.5


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
    stage: str = ""  # which stage of an experiment the trial belongs to (pilot, training, validation)

    def movement(self) -> Movement:
        return Movement(self.force_N, self.velocity_m_per_s)


def trial_seed(base_seed: int, *identity) -> int:
    """A 63-bit seed from the experiment's seed and a trial's identity (texture, movement, repetition, stage)."""
    h = hashlib.sha256(repr((int(base_seed),) + tuple(identity)).encode()).digest()
    return int.from_bytes(h[:8], "little") >> 1


def _params(noise_scale: float) -> SensorParams:
    if noise_scale == 1.0:
        return SensorParams()
    p = SensorParams()
    return p.replace(adc_noise_rms_bits=p.adc_noise_rms_bits * noise_scale,
                     adc_reference_noise_ppm=p.adc_reference_noise_ppm * noise_scale,
                     pac_path_noise_rms_bits=p.pac_path_noise_rms_bits * noise_scale,
                     amp_voltage_noise_V_per_rtHz=p.amp_voltage_noise_V_per_rtHz * noise_scale,
                     amp_current_noise_A_per_rtHz=p.amp_current_noise_A_per_rtHz * noise_scale,
                     mains_amplitude_V=p.mains_amplitude_V * noise_scale,
                     bridge_resistance_ohm=p.bridge_resistance_ohm * noise_scale ** 2)


def run_trial_task(task: TrialTask) -> dict:
    """Run one trial on the rig; returns a flat row: the task, the three properties, the true force, timing."""
    from bench.textures.library import texture

    skin = Skin(fingerprints=task.fingerprints, ridge_height_m=task.ridge_height_m, serial=task.skin_serial)
    rig = TextureRig(skin=skin, params=_params(task.noise_scale), fidelity=task.fidelity, noise=NoiseSources(),
                     wear=False)
    trial = rig.run_trial(texture(task.texture), task.movement(), seed=task.seed, trial=task.trial)
    row = asdict(task)
    row.update(properties(trial.recording))
    row.update(true_normal_N=trial.true_normal_N, start_position_m=trial.start_position_m,
               simulated_s=float(trial.recording.pac_t[-1]), wall_s=trial.wall_s)
    return row


def schedule_skin(tasks: list[TrialTask], wear: bool = True, replace_at: float | None = DETECTABLE_WEAR,
                  params: SensorParams | None = None) -> tuple[list[TrialTask], list[dict]]:
    """Give each task (in the given order: the session's order) the skin it meets: Archard wear after each trial
    and, with ``replace_at``, a fresh skin once the ridges lost that fraction of their height. Returns the tasks
    and the skin's history (one row per trial: serial, ridge height before)."""
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
            skin.wear(t.force_N, 0.05, area, velocity_m_per_s=t.velocity_m_per_s)
    return out, history


def sweep_tasks(textures, movements: list[Movement] | None = None, trials: int = 6, seed: int = 0,
                fidelity: str = "default", fingerprints: bool = True, stage: str = "sweep",
                noise_scale: float = 1.0) -> list[TrialTask]:
    """Tasks for every texture × movement × repetition, each on a fresh skin (wear is shown apart, by
    :func:`wear_per_movement`), seeds from the trial's identity."""
    movements = movements if movements is not None else movement_grid()
    out = []
    for tex in textures:
        for m_id, m in enumerate(movements):
            for k in range(trials):
                out.append(TrialTask(int(tex), m.force_N, m.velocity_m_per_s, k,
                                     trial_seed(seed, stage, int(tex), m_id, k), m_id, fidelity, fingerprints,
                                     stage=stage, noise_scale=noise_scale))
    return out


def wear_per_movement(movements: list[Movement] | None = None, trials: int = 100, distance_m: float = 0.05,
                      params: SensorParams | None = None) -> list[dict]:
    """Ridge height lost (m) after ``trials`` trials of each movement on a fresh skin (Archard's law)."""
    p = params or SensorParams()
    rows = []
    for m_id, m in enumerate(movements if movements is not None else movement_grid()):
        skin = Skin()
        area = contact_patch_area_m2(m.force_N, p.contact_radius_at_1N_m)
        for _ in range(trials):
            # the trial lasts distance / v at the rig; a high-speed trial is shorter, so wear per second grows
            skin.wear(m.force_N, distance_m, area, velocity_m_per_s=m.velocity_m_per_s)
        rows.append({"movement_id": m_id, "force_N": m.force_N, "velocity_m_per_s": m.velocity_m_per_s,
                     "ridge_lost_m": skin.ridge_height_new_m - skin.ridge_height_m,
                     "lost_per_second_m": (skin.ridge_height_new_m - skin.ridge_height_m)
                     / (trials * distance_m / m.velocity_m_per_s)})
    return rows


def sweep(tasks: list[TrialTask], spec=None, client=None, progress: bool = True) -> list[dict]:
    """Run ``tasks`` on the campaign engine (Dask); rows in task order."""
    from bench.campaigns.engine import run_tasks

    return run_tasks(run_trial_task, tasks, spec=spec, client=client, progress=progress, desc="trials")


def rows_to_arrays(rows: list[dict]) -> dict[str, np.ndarray]:
    """Column arrays of a list of row dicts (same keys in every row)."""
    if not rows:
        return {}
    return {k: np.array([r[k] for r in rows]) for k in rows[0]}
