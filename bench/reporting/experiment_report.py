"""What the texture experiment leaves behind: trial tables, accuracy and movement tables, the confusion matrix,
plots like D Figs 6-5 and 6-10, and a Markdown report beside D's numbers.  Every file is written to a temporary
name and renamed into place (:func:`bench.atomic.atomic_write`)."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from bench.experiments import exploration as ex
from bench.experiments.experiment import (D_FIGURES, ExperimentResult, beats_baselines, d_best_movement_ids,
                                          excluded_movements, identified_among, movement_label, summary,
                                          table_from_rows)
from bench.experiments.pairs import pair_separation_sigma
from bench.experiments.trials import clipped_note
from bench.atomic import atomic_write
from bench.cli.args import strict_json
from bench.reporting.figures import figure_file
from bench.reporting.sweep_plots import PROPERTIES as PROPERTY_LABELS
from bench.reporting.trials_file import trials_json

#: every file :func:`write_outputs` may write (what ``explore --force`` may replace)
OUTPUT_FILES = ("trials.csv", "trials.json", "pilot_uncertainty.csv", "accuracy.csv", "accuracy_per_texture.csv",
                "confusion.csv", "summary.json", "properties_at_optimal_movements.png", "probability_evolution.png",
                "report.md")
#: decimals kept in the accuracy tables (a percentage to 1e-4 %, a fraction to 1e-6): no float noise such as
#: 56.49999999999999
PERCENT_DECIMALS = 4


def write_text(path: Path, text: str) -> None:
    """``text`` into ``path`` (UTF-8), under a temporary name renamed into place."""
    with atomic_write(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def write_rows_csv(path: Path, rows: list[dict]) -> None:
    """A table of row dicts as CSV (columns: every key, in first-seen order; a row without one leaves it empty; a
    value that is a table or a list — a trial's ``undefined``, {property: why} — as its JSON text, which any reader
    parses back), written under a temporary name and renamed into place."""
    if not rows:
        return
    columns = list(dict.fromkeys(k for r in rows for k in r))
    with atomic_write(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=columns, restval="")
        w.writeheader()
        w.writerows({k: strict_json(v) if isinstance(v, (dict, list)) else v for k, v in r.items()} for r in rows)


def pilot_status(result: ExperimentResult) -> dict[int, str]:
    """Per grid movement, what the pilot did with it: ``run`` (its U counts), ``excluded-high-power`` (run, but
    left out of the choice for its wear) or ``not-run`` (not among the pilot's movements)."""
    ran = sorted({int(r["movement_id"]) for r in result.pilot_rows})
    excluded = set(excluded_movements(result.spec, ran))
    return {m: "not-run" if m not in ran else "excluded-high-power" if m in excluded else "run"
            for m in range(result.pilot_uncertainty.shape[0])}


def pilot_pick_comparison(result: ExperimentResult) -> dict[str, dict]:
    """Per property: U of the pilot's pick and of D's pick (D ch. 6), and D's pick's rank (1 = least uncertain)
    among the movements the pilot kept (None if the pilot excluded or did not run it); ``tied_with``: the other kept
    movements whose U equals the pick's (the pick is then the lowest grid id of them, not a better movement)."""
    status = pilot_status(result)
    kept = [m for m, st in status.items() if st == "run"]
    out = {}
    for prop, d_id in d_best_movement_ids().items():
        u = result.pilot_uncertainty[:, ex.PROPERTIES.index(prop)]
        order = sorted(kept, key=lambda m: u[m])
        pick = int(result.best_movements[ex.PROPERTIES.index(prop)])
        out[prop] = {"pick_U": float(u[pick]),
                     "tied_with": [movement_label(m) for m in kept if m != pick and u[m] == u[pick]],
                     "d_U": float(u[d_id]) if np.isfinite(u[d_id]) else None, "d_status": status[d_id],
                     "d_rank": order.index(d_id) + 1 if d_id in kept else None, "kept": len(kept)}
    return out


def trial_rows(result: ExperimentResult) -> list[dict]:
    """Every trial of an experiment, pilot, training and validation in that order (trials.csv and trials.json)."""
    return result.pilot_rows + result.training_rows + result.validation_rows


#: the stages whose wall time trials.json's ``wall_s`` counts: those that run trials
TRIAL_STAGES = ("pilot", "training", "validation")


def experiment_trials_json(result: ExperimentResult) -> str:
    """trials.json of an experiment (:mod:`bench.reporting.trials_file`): its trial rows, the library, the trial
    stages' wall time and where they ran."""
    return trials_json("explore", trial_rows(result), result.library,
                       sum(result.wall_s.get(stage, 0.0) for stage in TRIAL_STAGES), result.workers)


def write_outputs(result: ExperimentResult, out: Path) -> list[str]:
    """Write every output of an experiment into ``out``; returns the file names."""
    from bench.textures.library import load_library

    out.mkdir(parents=True, exist_ok=True)
    lib = load_library(result.spec.library)
    names = []
    rows = trial_rows(result)
    write_rows_csv(out / "trials.csv", rows)
    write_text(out / "trials.json", experiment_trials_json(result))
    names += ["trials.csv", "trials.json"]
    status = pilot_status(result)
    u = [{"movement_id": m, "movement": movement_label(m), "status": status[m],
          "U_traction": result.pilot_uncertainty[m, 0],
          "U_roughness": result.pilot_uncertainty[m, 1], "U_fineness": result.pilot_uncertainty[m, 2],
          "ridge_lost_um_per_pilot_worth": result.wear[m]["ridge_lost_m"] * 1e6,
          "trials_to_visible_wear": result.wear[m]["trials_to_visible_wear"]}
         for m in range(result.pilot_uncertainty.shape[0])]
    write_rows_csv(out / "pilot_uncertainty.csv", u)
    names.append("pilot_uncertainty.csv")
    s = summary(result)
    acc_rows = [{"task": k.split("/")[0], "strategy": k.split("/")[1],
                 "accuracy_%": round(100 * v["accuracy"], PERCENT_DECIMALS),
                 "median_moves": v["median_moves"], "simulations": v["simulations"]} for k, v in s.items()]
    write_rows_csv(out / "accuracy.csv", acc_rows)
    write_rows_csv(out / "accuracy_per_texture.csv", accuracy_per_texture_rows(s, lib))
    names += ["accuracy.csv", "accuracy_per_texture.csv"]
    if "bayesian" in result.identification_results:
        write_rows_csv(out / "confusion.csv", confusion_rows(result.identification_results["bayesian"]))
        names.append("confusion.csv")
    record = {"spec": {k: v for k, v in vars(result.spec).items()}, "library": result.library, "best_movements":
              {p: movement_label(m) for p, m in zip(ex.PROPERTIES, result.best_movements)},
              "pairs": result.pairs, "pair_separation_sigma": _pair_separation(result), "summary": s,
              "bayesian_beats_baselines_on": beats_baselines(result),
              "bayesian_strictly_beats_baselines_on": beats_baselines(result, strict=True),
              "pilot_picks_against_d": pilot_pick_comparison(result),
              "skin_replacements": max((h["skin"] for h in result.skin_history), default=1) - 1,
              "skin_wear": _skin_wear(result.spec),
              "trials_with_pac_at_rails": sum(1 for r in trial_rows(result) if r["pac_at_rails"]),
              "spread_check": ex.spread_check(table_from_rows(result.training_rows),
                                              table_from_rows(result.validation_rows))
              if result.validation_rows else None,
              "wall_s": result.wall_s, "dissertation": D_FIGURES}
    write_text(out / "summary.json", strict_json(record, indent=2))  # standard JSON: a NaN (say, no spread) is null
    names.append("summary.json")
    names += _plots(result, out, lib)
    write_text(out / "report.md", markdown(result, record, lib))
    names.append("report.md")
    return names


def accuracy_per_texture_rows(s: dict, lib) -> list[dict]:
    """accuracy_per_texture.csv from :func:`summary` ``s``: a row per texture (number, ``lib[number].name``), a column
    ``<task>/<strategy>_accuracy_%`` per run, in percent as accuracy.csv (empty where the texture was not a truth)."""
    return [{"texture": t, "name": lib[t].name,
             **{f"{k}_accuracy_%": round(100 * v["per_texture_accuracy"][t], PERCENT_DECIMALS) for k, v in s.items()
                if t in v["per_texture_accuracy"]}}
            for t in sorted({t for v in s.values() for t in v["per_texture_accuracy"]})]


#: how the report introduces the validation pairs, per ``pair_choice``
PAIR_TEXT = {
    "similar-description": "Disjoint pairs of similar textures, chosen from the library's descriptions alone as D's "
                           "experimenter chose them by eye and touch: same group, same thermal material, same "
                           "compliance, both ridged or both not, nearest in roughness, correlation length, Hurst "
                           "exponent, friction and ridge period/amplitude, one pair per group "
                           "(bench/experiments/pairs.py):",
    "random-within-group": "Disjoint pairs drawn at random (from the experiment's seed) within the library's texture "
                           "groups: textures of one kind (D's pairs were chosen by people):",
    "most-confused": "The disjoint pairs within a texture group that the training model confuses most at the three "
                     "optimal movements (a harder test than D's, whose pairs were chosen by people):",
}


def posterior_lines(r, most: int = 5) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The probability-evolution plot of simulation ``r``'s first run: (label "T<n>", movements made 0..n, P(texture)
    after each) for the ``most`` textures that were ever likeliest — from the prior (0 movements) through the
    posterior after its last movement."""
    h = r.posterior[0]
    steps = int(r.n_moves[0]) + 1
    top = np.argsort(-np.nanmax(h[:steps], axis=0))[:most]
    return [(f"T{int(r.candidates[k])}", np.arange(steps), h[:steps, k]) for k in top]


def confusion_rows(results) -> list[dict]:
    """confusion.csv: a row per true texture (``true``) with a column per texture decided (the simulations that
    decided it), over every texture that is either."""
    labels = np.array(sorted({int(r.true_texture) for r in results} | {int(d) for r in results for d in r.decided}))
    lab, cm = ex.confusion_matrix(results, labels=labels)
    return [{"true": int(t), **{str(int(d)): int(cm[i, j]) for j, d in enumerate(lab)}} for i, t in enumerate(lab)]


def _pair_separation(result: ExperimentResult) -> list[list[float]] | None:
    """Per pair, its textures' training separation in pooled σ per property (diagnostic; None without training)."""
    if not result.training_rows or not result.pairs:
        return None
    model = ex.fit_model(table_from_rows(result.training_rows))
    return pair_separation_sigma(model, result.pairs)


def _plots(result: ExperimentResult, out: Path, lib) -> list[str]:
    names = []
    # properties per texture at the optimal movements (like D Fig. 6-5)
    rows = result.training_rows
    with figure_file(out / "properties_at_optimal_movements.png", 1, 3, figsize=(15, 4.5)) as (_, axes):
        for p, (prop, m) in enumerate(zip(ex.PROPERTIES, result.best_movements)):
            sel = [r for r in rows if r["movement_id"] == int(m)]
            tex = sorted({r["texture"] for r in sel})
            vals = [[r[prop] for r in sel if r["texture"] == t] for t in tex]
            # one slot per texture, labelled with its number: T1..T117 as before, a library's own T950 beside T46
            # rather than 900 numbers away, where its neighbours' bars ran together
            slots = np.arange(len(tex))
            axes[p].errorbar(slots, [np.mean(v) for v in vals], yerr=[np.std(v) for v in vals], fmt=".", ms=3,
                             lw=0.7)
            every = max(1, -(-len(tex) // 30))  # at most 30 labels
            axes[p].set_xticks(slots[::every], [str(t) for t in tex[::every]],
                               rotation=90 if len(tex) > 12 else 0, fontsize=7)
            axes[p].set_xlabel("texture number")
            axes[p].set_ylabel(dict(PROPERTY_LABELS)[prop])
            axes[p].set_title(f"{prop} at {movement_label(m)}")
            axes[p].grid(alpha=0.3)
    names.append("properties_at_optimal_movements.png")
    # probability evolution of a few simulations (like D Fig. 6-10)
    if "bayesian" in result.identification_results:
        rs = result.identification_results["bayesian"][:4]
        from matplotlib.ticker import MaxNLocator

        with figure_file(out / "probability_evolution.png", 1, len(rs), figsize=(4 * len(rs), 3.8),
                         squeeze=False) as (fig, axes):
            fig.suptitle(f"Bayesian exploration ({identified_among(result)}-way): the posterior of the five likeliest "
                         f"textures after each movement, first simulations", fontsize=10)
            for ax, r in zip(axes[0], rs):
                for label, moves, probability in posterior_lines(r):
                    ax.plot(moves, probability, marker=".", label=label)
                ax.set_title(f"true T{int(r.true_texture)} ({lib[int(r.true_texture)].name})", fontsize=9)
                ax.set_xlabel("movements made")
                ax.xaxis.set_major_locator(MaxNLocator(integer=True))
                ax.set_ylabel("P(texture)")
                ax.set_ylim(0, 1.02)
                ax.legend(fontsize=7)
                ax.grid(alpha=0.3)
        names.append("probability_evolution.png")
    return names


def _skin_wear(spec) -> dict:
    """The skin policy and wear-law knobs an experiment ran with (fractions of the ridge height; k, β: 1)."""
    from emulator.skin import Skin

    skin = Skin()
    return {"wear": spec.wear, "replace_at": spec.replace_at if spec.replace_skin else None,
            "first_visible_wear_fraction": skin.first_visible_wear_fraction,
            "wear_coefficient": skin.wear_coefficient, "wear_power_exponent": skin.wear_power_exponent,
            "calibrated": "k: D's training session (3 skins); β: D's pilot boundary (level 8 visible, ≤ 7 not)"}


def _z(x) -> str:
    """A spread-check figure, or "—" where it is undefined (NaN or None)."""
    return "—" if x is None or not math.isfinite(x) else f"{x:.2f}"


def markdown(result: ExperimentResult, record: dict, lib) -> str:
    s = record["summary"]
    d = D_FIGURES
    lines = [f"# Texture experiment: {result.spec.name}", "",
             "Bayesian exploration (D ch. 6) run end to end on the emulated BioTac: every value below comes from "
             "sliding trials of the texture rig read over SPI. Nothing was tuned toward these numbers.", ""]
    if result.library:
        lib_rec = result.library
        where = "the shipped fixtures/textures/library.toml" if lib_rec["shipped"] else lib_rec["path"]
        lines += [f"Texture library: {where} (SHA-256 {lib_rec['sha256'][:16]}…).", ""]
    lines += ["## Optimal movements (pilot)", "",
              "Expected uncertainty U over the pilot's textures (lower is better); D's pick's rank is among the "
              "movements this pilot kept (high-power ones excluded for wear).", "",
              "| property | emulator's pick (U) | dissertation's pick | its U here | its rank here |",
              "|---|---|---|---|---|"]
    for p, row in pilot_pick_comparison(result).items():
        rank = {"excluded-high-power": "excluded (high power)", "not-run": "not in this pilot"}.get(
            row["d_status"], f"{row['d_rank']} of {row['kept']}")
        d_u = "—" if row["d_U"] is None else f"{row['d_U']:.3g}"
        tie = (f"; tied with {', '.join(row['tied_with'])}, the lowest grid id taken" if row["tied_with"] else "")
        lines.append(f"| {p} | {record['best_movements'][p]} (U = {row['pick_U']:.3g}{tie}) | {d['best movements'][p]} "
                     f"| {d_u} | {rank} |")
    lines += ["", "## Accuracy and movements to converge", "",
              "| task | strategy | accuracy | median movements | dissertation |", "|---|---|---|---|---|"]
    among = identified_among(result)  # the identification's N-way beside D's 117-way, never one for the other
    for k, v in s.items():
        task, strat = k.split("/")
        ref = ""
        if strat == "bayesian":
            ref = (f"{d['pairs accuracy %']} %, median {d['pairs median moves']} (humans {d['human pairs accuracy %']} %)"
                   if task == "pairs" else f"{d['117-way accuracy %']} %, median {d['117-way median moves']} (117-way)")
        label = task if task == "pairs" else f"{task} ({among}-way)"
        lines.append(f"| {label} | {strat} | {100 * v['accuracy']:.1f} % | {v['median_moves']:g} | {ref} |")
    n_val = len({int(r.true_texture) for r in result.identification_results.get("bayesian", ())})  # identified
    baselines = [words for name, words in (("cycle", "cycling"), ("random", "random choice"))
                 if name in result.identification_results]
    if not baselines:
        lines += ["", "No baseline strategy (cycle, random) was run: Bayesian exploration is compared with none."]
    else:
        good, strict = record["bayesian_beats_baselines_on"], record["bayesian_strictly_beats_baselines_on"]
        lines += ["", f"In identification, Bayesian exploration is at least as accurate as {' and '.join(baselines)} "
                      f"and converges in no more movements on {good} of {n_val} identified textures; it is strictly "
                      f"better than {'both' if len(baselines) == 2 else 'it'} (better in accuracy or in movements, no "
                      f"worse in the other) on {strict} of them, and ties with "
                      f"{'one of them' if len(baselines) == 2 else 'it'} on the other {good - strict}; on "
                      f"{n_val - good} it is less accurate or slower than {'one of them' if len(baselines) == 2 else 'it'}."]
    lines += ["", "## Pairs of similar textures", "",
              "The pairs as the experiment file lists them:" if result.spec.pairs
              else PAIR_TEXT[result.spec.pair_choice],
              "", "Beside each pair, as a diagnostic only (the choice does not use it): how far apart its two "
                  "textures are in the training data: per property, the largest |difference of means| / pooled σ "
                  "over the trained movements (traction / roughness / fineness).", ""]
    sep = record.get("pair_separation_sigma") or [None] * len(result.pairs)
    lines += [f"- T{a} {lib[a].name} / T{b} {lib[b].name}"
              + ("" if d is None else " — " + " / ".join(f"{x:.1f}" for x in d) + " σ")
              for (a, b), d in zip(result.pairs, sep)]
    if record.get("spread_check"):
        lines += ["", "## Do the validation trials look like the training trials?", "",
                  "Median |z| of each validation trial against its texture's training normal, beside each training "
                  "trial against the normal of the other training trials of its texture and movement (leave-one-out). "
                  "A ratio near 1: validation scatters as training does; well above 1: the validation trials are "
                  "shifted (e.g. another skin state).", "",
                  "| property | validation | leave-one-out | ratio |", "|---|---|---|---|"]
        lines += [f"| {k} | {_z(v['validation_median_abs_z'])} | {_z(v['leave_one_out_median_abs_z'])} | "
                  f"{_z(v['ratio'])} |" for k, v in record["spread_check"].items()]
        if any(_z(x) == "—" for v in record["spread_check"].values() for x in v.values()):
            lines += ["", "— : undefined (with 2 training trials per texture and movement, each trial's leave-one-out "
                          "normal rests on one trial: no spread)."]
    w = record["skin_wear"]
    visible = f"{100 * w['first_visible_wear_fraction']:.1f} %"
    policy = ("skin wear off" if not w["wear"] else "never replaced" if w["replace_at"] is None else
              f"at the first visible wear, {visible} of the ridge height lost"
              if w["replace_at"] == w["first_visible_wear_fraction"] else
              f"once the ridges lost {100 * w['replace_at']:.1f} % of their height; first visible wear: {visible}")
    lines += ["", f"Skin replacements in the training and validation session: {record['skin_replacements']} "
              f"({policy}). Wear law: worn volume k·N·d/H·(N·v/P_ref)^β with k = {w['wear_coefficient']:.2g} and "
              f"β = {w['wear_power_exponent']:.2g}, both calibrated to D's wear observations (k: two replacements "
              f"over D's training session at the first visible wear; β: after 60 trials of one movement, visible "
              f"wear at power level 8 and none at ≤ 7, D Fig. 6-7).",
              "Wall time per stage (s): " + ", ".join(f"{k} {v:.1f}" for k, v in result.wall_s.items()), ""]
    clipped = clipped_note(trial_rows(result))
    if clipped:
        lines[-1:-1] = [f"Clipped: {clipped}."]
    return "\n".join(lines)
