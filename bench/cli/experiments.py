"""Experiment commands: the texture sweep (the rig over textures × movements × repetitions) and the Bayesian
exploration experiment of D ch. 6, both on Dask."""

from __future__ import annotations

import argparse
import json
import sys
import time

from bench.cli.args import whole
from emulator.fidelity import PROFILES

SWEEP_HELP = """\
Runs the texture rig (lower until the PDC target, hold, slide 5 cm, lift) over chosen textures × movements ×
repetitions — each trial an independent task on Dask (a LocalCluster on this machine's cores, or an existing
scheduler with --scheduler / DASK_SCHEDULER_ADDRESS) — and computes traction, roughness and fineness per trial.

Writes into --out: trials.csv and trials.json (one row per trial: texture, movement, repetition, seed, skin,
the three properties, the true normal force, simulated and wall time), wear.csv (ridge height each movement
wears off in 100 trials on a fresh skin), properties.png (each property against force and velocity).

Every trial runs on a fresh skin with a seed derived from its identity, so the table is identical for any number
of workers.  Examples:
  biotac-bench texture-sweep --textures 43,46,47,30,84,87,100,10,2,3 --trials 6      # D ch. 6's pilot (2160 trials)
  biotac-bench texture-sweep --textures 902 --movements 7,14,21 --trials 2 --workers 1
"""


def _int_list(flag: str, text: str, lo: int, hi: int) -> list[int]:
    try:
        values = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise ValueError(f"{flag} = {text!r}: give comma-separated whole numbers, e.g. 2,10,30") from None
    bad = [v for v in values if not lo <= v <= hi]
    if not values or bad:
        raise ValueError(f"{flag} = {text!r}: every value must be within {lo} and {hi}")
    return values


def _cmd_texture_sweep(a) -> int:
    from dataclasses import replace

    from bench.campaigns.engine import ClusterSpec
    from bench.experiments.trials import rows_to_arrays, sweep, sweep_tasks, wear_per_movement
    from bench.reporting.experiment_report import write_rows_csv
    from bench.reporting.sweep_plots import properties_vs_movement
    from bench.rigs.texture_rig import movement_grid
    from bench.textures.library import load_library, texture

    from bench.reporting.outdir import writable_folder

    if a.trials < 1:
        raise ValueError(f"--trials = {a.trials}: must be at least 1")
    if a.workers is not None and a.workers < 1:
        raise ValueError(f"--workers = {a.workers}: must be at least 1")
    grid = movement_grid()
    textures = [texture(t).number for t in (a.textures.split(",") if a.textures else [])]
    if not textures:
        raise ValueError("--textures: give at least one texture (numbers or names, comma-separated)")
    ids = list(range(len(grid))) if a.movements == "all" else _int_list("--movements", a.movements, 0, len(grid) - 1)
    movements = [grid[i] for i in ids]
    out = writable_folder(a.out, "--out")  # checked before anything runs
    tasks = sweep_tasks(textures, movements, a.trials, a.seed, a.fidelity, not a.smooth_skin)
    # keep the grid's own movement ids in the table
    tasks = [replace(t, movement_id=ids[t.movement_id]) for t in tasks]
    spec = ClusterSpec.from_env(a.scheduler, a.workers)
    print(f"{len(tasks)} trials ({len(textures)} textures × {len(movements)} movements × {a.trials}) on "
          f"{spec.describe()}", file=sys.stderr)
    t0 = time.perf_counter()
    rows = sweep(tasks, spec=spec, progress=not a.quiet)
    wall = time.perf_counter() - t0
    write_rows_csv(out / "trials.csv", rows)
    tmp = out / "trials.json.tmp"
    tmp.write_text(json.dumps({"wall_s": wall, "workers": spec.describe(), "rows": rows}, indent=1))
    tmp.replace(out / "trials.json")
    write_rows_csv(out / "wear.csv", wear_per_movement(movements))
    lib = load_library()
    properties_vs_movement(rows_to_arrays(rows), {n: lib[n].name for n in textures}, out / "properties.png")
    sim = sum(r["simulated_s"] for r in rows)
    print(f"wrote {out}/ (trials.csv, trials.json, wear.csv, properties.png): {len(rows)} trials, "
          f"{sim:.0f} simulated s in {wall:.1f} s wall ({sim / wall:.0f}× real time)")
    return 0


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    s = sub.add_parser("texture-sweep", help="the texture rig over textures × movements × repetitions (Dask)",
                       description=SWEEP_HELP, formatter_class=fmt)
    s.add_argument("--textures", required=True, help="comma-separated texture numbers or names (biotac-bench textures)")
    s.add_argument("--movements", default="all", help="'all' (the 36 of D eqs 6.20–6.21) or grid ids 0..35 "
                                                      "(id = 6 × force step + velocity step)")
    s.add_argument("--trials", type=int, default=6, help="repetitions per texture and movement (6)")
    s.add_argument("--seed", type=whole(0), default=0, help="the sweep's seed; each trial's seed derives from it")
    s.add_argument("--fidelity", default="default", choices=list(PROFILES))
    s.add_argument("--smooth-skin", action="store_true", help="a skin without fingerprint ridges")
    s.add_argument("--out", default="out/texture-sweep", help="output folder (out/texture-sweep)")
    s.add_argument("--workers", type=int, help="LocalCluster worker processes (default: one per core)")
    s.add_argument("--scheduler", help="address of an existing Dask scheduler (or DASK_SCHEDULER_ADDRESS)")
    s.add_argument("--quiet", action="store_true", help="no progress bar")
    s.set_defaults(func=_cmd_texture_sweep)
    add_explore_command(sub, fmt)


EXPLORE_HELP = """\
Runs the dissertation's texture experiment (D ch. 6) end to end on the bench from an experiment file:
pilot (dissimilar textures × 36 movements) → the movement of least uncertainty per property → training (every
texture × those movements, one skin that wears and is replaced) → validation trials for pairs of similar
textures → virtual exploration (Monte Carlo: pairs, and 117-way identification) for each strategy.

The pairs ([validation] pair_choice): "similar-description" (default; as D's experimenter chose them, from the
library's descriptions: same group, thermal material and compliance, nearest in surface and friction),
"random-within-group" (drawn from the seed), "most-confused" (the training model's hardest), or
pairs = [[a, b], ...].

Trials run on Dask (a LocalCluster on this machine's cores, or --scheduler / DASK_SCHEDULER_ADDRESS) and each
stage's trials are cached in out/cache by content hash, so changing the classifier settings re-runs no sliding.

Writes into --out: report.md (beside D's numbers), summary.json, accuracy.csv, accuracy_per_texture.csv,
confusion.csv, pilot_uncertainty.csv, trials.csv/json, properties_at_optimal_movements.png,
probability_evolution.png.  --ablation NAME runs a variant (smooth-skin, unreplaced-wear, fewer-trials,
double-noise; or all) into --out/<name>/ and adds a comparison table to --out/ablations.md.

  biotac-bench explore fixtures/experiments/fishel2012.toml
  biotac-bench explore fixtures/experiments/quick.toml --ablation smooth-skin
"""


def _cmd_explore(a) -> int:
    from dataclasses import replace

    from bench.campaigns.engine import ClusterSpec
    from bench.experiments.experiment import ABLATIONS, load_experiment, run_experiment, summary
    from bench.reporting.experiment_report import write_outputs

    spec = load_experiment(a.experiment)
    if a.workers is not None and a.workers < 1:
        raise ValueError(f"--workers = {a.workers}: must be at least 1")
    names = [] if not a.ablation else (list(ABLATIONS) if a.ablation == "all" else [a.ablation])
    from bench.reporting.outdir import writable_folder

    out = writable_folder(a.out or f"out/explore/{spec.name}", "--out")  # both checked before anything runs
    cluster = ClusterSpec.from_env(a.scheduler, a.workers)
    cache = None if a.no_cache else writable_folder(a.cache, "--cache")
    variants = [("baseline", spec)] + [(n, replace(spec, **ABLATIONS[n][1])) for n in names]
    rows = []
    for label, sp in variants:
        t0 = time.perf_counter()
        print(f"== {label}: {cluster.describe()}", file=sys.stderr)
        result = run_experiment(sp, cache_dir=cache, cluster=cluster, progress=not a.quiet,
                                log=lambda m: print(m, file=sys.stderr))
        folder = out if label == "baseline" else out / label
        files = write_outputs(result, folder)
        s = summary(result)
        rows.append((label, s, time.perf_counter() - t0))
        print(f"wrote {folder}/ ({', '.join(files)}) in {time.perf_counter() - t0:.0f} s")
    if names:
        lines = ["# Ablations", "", "| variant | pairs (bayesian) | 117-way (bayesian) | median movements |",
                 "|---|---|---|---|"]
        for label, s, _ in rows:
            what = "as specified" if label == "baseline" else ABLATIONS[label][0]
            lines.append(f"| {label} ({what}) | {100 * s['pairs/bayesian']['accuracy']:.1f} % | "
                         f"{100 * s['identification/bayesian']['accuracy']:.1f} % | "
                         f"{s['identification/bayesian']['median_moves']:g} |")
        (out / "ablations.md").write_text("\n".join(lines) + "\n")
        print("\n".join(lines))
    else:
        print((out / "report.md").read_text())
    return 0


def add_explore_command(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    from bench.experiments.experiment import ABLATIONS

    e = sub.add_parser("explore", help="the texture experiment of D ch. 6: pilot, training, validation, "
                                       "Bayesian exploration (Dask)", description=EXPLORE_HELP, formatter_class=fmt)
    e.add_argument("experiment", help="experiment file (TOML), e.g. fixtures/experiments/fishel2012.toml")
    e.add_argument("--out", help="output folder (default out/explore/<name>)")
    e.add_argument("--ablation", choices=list(ABLATIONS) + ["all"], help="also run a variant and compare")
    e.add_argument("--workers", type=int, help="LocalCluster worker processes (default: one per core)")
    e.add_argument("--scheduler", help="address of an existing Dask scheduler (or DASK_SCHEDULER_ADDRESS)")
    e.add_argument("--cache", default="out/cache", help="where stage results are cached (out/cache)")
    e.add_argument("--no-cache", action="store_true", help="run every trial again")
    e.add_argument("--quiet", action="store_true", help="no progress bars")
    e.set_defaults(func=_cmd_explore)
