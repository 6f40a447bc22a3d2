"""Benchmarks of sliding, the texture rig and the experiment's campaigns: what each fidelity profile costs and how
wrong it is while sliding (each channel kind's error, measured as the fidelity table measures it), rig trials per
second, Dask scaling (1 vs 2 workers, overhead per task, an estimate for a larger cluster), and exploration steps
per second.  Printed by ``biotac-bench benchmark --textures``."""

from __future__ import annotations

import copy
import time

import numpy as np

from bench.experiments.trials import TrialTask, run_trial_task, trial_seed
from emulator.sensor import NoiseSources, Sensor
from emulator.sliding import Slide

PAC_RATE_HZ = 2200.0
TRIAL_REPEATS = 10  # a rig trial's cost: the shortest wall time of this many runs after a warm-up run (a shared
# machine's load only adds time; 10 runs of ~20 ms cost 0.2 s a row and find a quiet moment far more often than 3)


#: how long (s) the benchmark's slide scene runs on after the finger lifts
SLIDE_TAIL_S = 0.2


def slide_scene(texture):
    """The benchmark's slide on ``texture`` as a one-sensor scene built in code: from 0.2 s, 5 cm at 0.5 N and
    2.5 cm/s from 0.3 m along the texture (approach, hold, acceleration and lift the :class:`Slide`'s defaults), read
    through the default 44-slot frame at 4400 slots/s, ending :data:`SLIDE_TAIL_S` after the lift; no noise."""
    from bench.scenes.scene import Scene

    slide = Slide(0.2, texture, 0.5, 0.025, 0.05, start_position_m=0.3)
    return Scene(name=f"slide on {texture.name}", duration_s=slide.end_s + SLIDE_TAIL_S, seed=1, stimuli=[slide],
                 noise=NoiseSources.none())


def _slide_pac_bits(scene, fidelity: str) -> np.ndarray:
    """Noise-free analog PAC (LSB) of :func:`slide_scene`'s ``scene`` at ``fidelity``, sampled evenly at
    :data:`PAC_RATE_HZ` over the scene (its stimuli copied: the scene is left as it is)."""
    from emulator import conversions as conv

    t = np.arange(0.0, scene.duration_s, 1 / PAC_RATE_HZ)
    sensor = Sensor(stimuli=copy.deepcopy(scene.stimuli), channels_read=["PAC"], fidelity=fidelity,
                    noise=NoiseSources.none())
    return sensor.analog_trace("PAC", t) / conv.ADC_LSB_V


#: the profiles the sliding benchmark compares (each against ``reference``)
SLIDING_PROFILES = ("fast", "default", "reference")


def sliding_fidelity(textures=(901, 902, 30), say=lambda m: None) -> list[dict]:
    """Per texture and profile, on :func:`slide_scene`: ``error_bits``, each channel kind's noise-free RMS error
    against the reference profile (bits; the fidelity table's :func:`~bench.verification.benchmark.profile_errors`,
    so every kind of the default frame), PAC's also as ``pac_rms_error_bits``; PAC's spectral error (dB,
    20–700 Hz); and the rig trial's cost (lower, hold, slide 5 cm, full frame, noise on; the best of
    :data:`TRIAL_REPEATS` runs)."""
    from bench.textures.library import texture
    from bench.verification.benchmark import profile_errors

    rows = []
    for number in textures:
        tex = texture(number)
        scene = slide_scene(tex)
        say(f"… sliding on {tex.name}: noise-free errors")
        errors = profile_errors(scene, SLIDING_PROFILES)
        ref = _slide_pac_bits(scene, "reference")
        f = np.fft.rfftfreq(ref.size, 1 / PAC_RATE_HZ)
        band = (f >= 20) & (f <= 700)
        ref_spec = np.abs(np.fft.rfft(ref * np.hanning(ref.size)))[band] ** 2
        for profile in SLIDING_PROFILES:
            say(f"… sliding on {tex.name}, {profile}")
            x = ref if profile == "reference" else _slide_pac_bits(scene, profile)  # (the reference once)
            spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))[band] ** 2
            spectral = float(np.sqrt(np.mean((10 * np.log10((spec + 1e-12) / (ref_spec + 1e-12))) ** 2)))
            task = TrialTask(number, 0.5, 0.025, 0, trial_seed(1, "bench", number), fidelity=profile)
            run_trial_task(task)  # warm the caches (surface tracks, compiled kernels)
            wall = np.inf
            for _ in range(TRIAL_REPEATS):  # the best of a few runs: a shared machine's load only adds time
                t0 = time.perf_counter()
                row = run_trial_task(task)
                wall = min(wall, time.perf_counter() - t0)
            rows.append({"texture": tex.name, "profile": profile, "error_bits": errors[profile],
                         "pac_rms_error_bits": errors[profile]["PAC"], "spectral_error_dB": spectral,
                         "trial_simulated_s": row["simulated_s"], "trial_wall_s": wall,
                         "realtime_factor": row["simulated_s"] / wall})
    return rows


#: the Dask scaling runs 1 and 2 workers alternately this many times and keeps each one's shortest wall time (the
#: machine's speed drifts by tens of per cent within a minute; a single pair of runs measured 1.56–1.89×)
SCALING_ROUNDS = 3


def dask_scaling(repetitions: int = 4, say=lambda m: None) -> dict:
    """The same rig trials (6 textures × 4 movements × ``repetitions``) on a LocalCluster of 1 and of 2 workers,
    alternately :data:`SCALING_ROUNDS` times: the shortest wall time of each, speed-up, overhead per task."""
    from bench.campaigns.engine import ClusterSpec, close, connect, run_tasks

    moves = [(0.2, 0.01), (0.5, 0.025), (1.26, 0.0631), (2.0, 0.1)]
    tasks = [TrialTask(t, f, v, k, trial_seed(3, "scaling", t, f, v, k))
             for t in (2, 30, 43, 100, 901, 902) for f, v in moves for k in range(repetitions)]
    out = {"trials": len(tasks)}
    for _ in range(SCALING_ROUNDS):
        for workers in (1, 2):
            say(f"… Dask, {workers} worker(s)")
            client = connect(ClusterSpec(workers=workers))
            try:
                run_tasks(run_trial_task, tasks[:workers * 2], client=client, progress=False)  # warm every worker
                t0 = time.perf_counter()
                rows = run_tasks(run_trial_task, tasks, client=client, progress=False)
                wall = time.perf_counter() - t0
            finally:
                close(client)
            busy = sum(r["wall_s"] for r in rows)
            key = f"workers_{workers}"
            if key not in out or wall < out[key]["wall_s"]:
                out[key] = {"wall_s": wall, "task_s": busy,
                            "overhead_per_task_s": max(0.0, (wall * workers - busy) / len(rows))}
    w1, w2 = out["workers_1"], out["workers_2"]
    out["speedup"] = w1["wall_s"] / w2["wall_s"]
    mean_task = w1["task_s"] / len(tasks)
    # estimate (stated as such): 64 workers, same per-task cost and overhead, perfectly divisible work
    out["estimate_64_workers_trials_per_s"] = 64 / (mean_task + w2["overhead_per_task_s"])
    out["mean_task_s"] = mean_task
    return out


def exploration_speed() -> float:
    """Bayesian exploration steps per second over 117 synthetic textures (bench.experiments.bench_exploration
    prints its per-strategy lines to stdout)."""
    import contextlib
    import io

    from bench.experiments import bench_exploration

    with contextlib.redirect_stdout(io.StringIO()):
        return float(bench_exploration.main([]))


def results(say=lambda m: None) -> dict:
    """The sliding, rig, Dask-scaling and exploration measurements, as data (``benchmark --textures --json``)."""
    out = {"sliding": sliding_fidelity(say=say), "dask_scaling": dask_scaling(say=say)}
    say("… exploration steps")
    out["exploration_steps_per_s"] = exploration_speed()
    return out


def report(say=lambda m: None, measured: dict | None = None) -> str:
    """The measurements of :func:`results` (or ``measured``) as text: the sliding table with each channel kind's
    error (— where none was measured), the campaign engine's scaling, the exploration speed."""
    from bench.verification.benchmark import ERROR_KIND_COLUMNS, _fmt

    r_all = measured if measured is not None else results(say)
    lines = ["Sliding: a 5 cm slide at 0.5 N, 2.5 cm/s — error against the reference profile (noise-free RMS, bits, "
             "per channel kind of the default frame; PAC's spectrum, dB) and the cost of a rig trial (lower, hold, "
             f"slide, lift; full 44-slot frame, noise on; best of {TRIAL_REPEATS} runs):",
             f"  {'texture':20s} {'profile':10s} " + " ".join(f"{k:>9s}" for k in ERROR_KIND_COLUMNS.values())
             + f" {'PAC spectral (dB)':>18s} {'trial sim s':>12s} {'trial wall s':>13s} {'× real time':>12s}"]
    for r in r_all["sliding"]:
        err = r.get("error_bits") or {}
        lines.append(f"  {r['texture']:20s} {r['profile']:10s} "
                     + " ".join(_fmt(err.get(k), "9.4f") for k in ERROR_KIND_COLUMNS)
                     + f" {r['spectral_error_dB']:18.3f} {r['trial_simulated_s']:12.2f} {r['trial_wall_s']:13.3f} "
                     f"{r['realtime_factor']:12.0f}")
    d = r_all["dask_scaling"]
    lines += [f"\nCampaign engine (Dask LocalCluster), {d['trials']} rig trials "
              f"(best of {SCALING_ROUNDS} alternating runs each):",
              f"  1 worker: {d['workers_1']['wall_s']:.2f} s; 2 workers: {d['workers_2']['wall_s']:.2f} s; "
              f"speed-up {d['speedup']:.2f}×",
              f"  overhead per task: {d['workers_2']['overhead_per_task_s'] * 1e3:.1f} ms (2 workers), "
              f"{d['workers_1']['overhead_per_task_s'] * 1e3:.1f} ms (1 worker); mean trial {d['mean_task_s']:.3f} s",
              f"  estimate (not measured): 64 workers ≈ {d['estimate_64_workers_trials_per_s']:.0f} trials/s, so the "
              f"experiment's ~4000 trials in ≈ {4000 / d['estimate_64_workers_trials_per_s']:.0f} s"]
    lines.append(f"\nBayesian exploration over 117 textures × 36 movements × 3 properties: "
                 f"{r_all['exploration_steps_per_s']:,.0f} steps/s")
    return "\n".join(lines)
