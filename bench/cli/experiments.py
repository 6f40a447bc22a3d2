"""Experiment commands: the texture sweep (the rig over textures × movements × repetitions) and the Bayesian
exploration experiment of D ch. 6, both on Dask."""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
from pathlib import Path

from bench.cli.args import add_cluster_arguments, any_seed, say_leftovers, sigterm_like_ctrl_c, whole
from bench.errors import escaped
from bench.experiments.design import ABLATIONS, D_PILOT_TEXTURES, PILOT_WORTH_TRIALS
from bench.tomlfile import spelled
from emulator.fidelity import PROFILES

#: what texture-sweep writes into its out folder (what --force may replace)
SWEEP_FILES = ("trials.csv", "trials.json", "wear.csv", "properties.png")
#: D ch. 6's pilot textures: the experiment's default (fixtures/experiments/fishel2012.toml)
PILOT_TEXTURES = ",".join(map(str, D_PILOT_TEXTURES))

SWEEP_HELP = f"""\
Runs the texture rig (lower until the PDC target, hold, slide 5 cm, lift) over chosen textures × movements ×
repetitions — each trial an independent task on Dask (a LocalCluster on this machine's cores, or an existing
scheduler with --scheduler / DASK_SCHEDULER_ADDRESS) — and computes traction, roughness and fineness per trial.

The textures come from the shipped library, or from one of your own: --library FILE (relative to the current
folder; the format of fixtures/textures/library.toml, or .json as `biotac-bench textures --json` prints; the
workers must be able to read the file).  Scenes name one with [scene] library, experiments with [experiment]
library, each relative to its own file.

Writes into --out (default: a fresh out/texture-sweep[-n]): trials.csv and trials.json (one row per trial:
texture, movement, repetition, seed, skin, the library file, the SPI faults, the three properties, the samples at
the ADC's rails (pac_at_rails) and those the host rejected (rejected_samples: 0 without SPI faults), the true
normal force, simulated and wall time; trials.json, the same rows in the schema explore writes too — format,
version, command, library (path, SHA-256 of the file, shipped or not), wall_s, workers, rows — see
bench/reporting/trials_file.py),
wear.csv (ridge height each movement wears off in {PILOT_WORTH_TRIALS} trials, a pilot's worth, on a fresh skin),
properties.png (each property against force and velocity).  Movements keep their grid ids in every file.  An
--out folder that holds anything is refused; --force replaces an earlier sweep's files there.

Every trial runs on a fresh skin with a seed derived from its identity (sweep seed, texture, grid movement id,
repetition), so a trial's result is the same in any selection of textures and movements and for any number of
workers.  --spi-fault puts SPI faults on the rig's bus for part of every trial (as an experiment file's [rig]
spi_faults): the rig leaves out each sample the host flags bad and counts it (rejected_samples).  Ctrl-C stops
the sweep (exit 130; SIGTERM: 143) and writes nothing — or, once the writing has begun, finishes every file
first.  Examples:
  biotac-bench texture-sweep --textures {PILOT_TEXTURES} --trials 6      # D ch. 6's pilot (2160 trials)
  biotac-bench texture-sweep --textures 902 --movements 7,14,21 --trials 2 --workers 1
  biotac-bench texture-sweep --library my_textures.toml --textures 950 --movements 7 --trials 2
"""


def _int_list(flag: str, text: str, lo: int, hi: int) -> list[int]:
    """Comma-separated whole numbers within [lo, hi], none twice (ValueError naming ``flag`` otherwise)."""
    from bench.experiments.trials import listed_twice

    try:
        values = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise ValueError(f"{flag} = {spelled(text)}: give comma-separated whole numbers, e.g. 2,10,30") from None
    bad = [v for v in values if not lo <= v <= hi]
    if not values or bad:
        raise ValueError(f"{flag} = {spelled(text)}: every value must be within {lo} and {hi}")
    if listed_twice(values):
        raise ValueError(f"{flag} = {spelled(text)}: {listed_twice(values)} listed twice")
    return values


def _texture_numbers(text: str, library=None) -> list[int]:
    """--textures: texture numbers or names, comma-separated, each in ``library`` (a
    :class:`~bench.textures.library.LibraryFile`; None: the shipped one) and none twice, or "all" (D's T1..T117)
    or "library" (every texture it holds: :func:`~bench.textures.library.textures_named`); ValueError naming
    --textures and the value otherwise."""
    from bench.errors import TextureError
    from bench.experiments.trials import listed_twice
    from bench.textures.library import (ALL_TEXTURES, LIBRARY_TEXTURES, LIBRARY_SIZE, listing_command, texture_word,
                                        textures_named)

    from bench.cli.args import library_option

    library = library or library_option(None)
    named = textures_named(text, library.textures)
    if named:
        return named
    # "library" on a library of no texture (a file of none is refused as it is read; a LibraryFile built so is not)
    if named is not None and texture_word(text) == LIBRARY_TEXTURES:
        raise ValueError(f"--textures {LIBRARY_TEXTURES}: every texture the library {escaped(library.path)} holds, "
                         f"and it holds none: name a library with textures (--library)")
    if named is not None:  # "all" on a library without D's textures
        raise ValueError(f"--textures {ALL_TEXTURES}: D's T1..T{LIBRARY_SIZE}, and the library holds none; --textures "
                         f"{LIBRARY_TEXTURES} takes every texture it holds "
                         f"(`{listing_command(None if library.shipped else library.path)}` lists them)")
    numbers = []
    for item in (x.strip() for x in text.split(",")):
        if not item:
            continue
        try:
            numbers.append(library.texture(item).number)
        except TextureError as e:
            lists = listing_command(None if library.shipped else library.path)
            raise ValueError(f"--textures: {'; '.join(e.problems)} ({lists} lists them)") from None
    if not numbers:
        raise ValueError("--textures: give at least one texture (numbers or names, comma-separated)")
    if listed_twice(numbers):
        raise ValueError(f"--textures = {spelled(text)}: texture(s) {listed_twice(numbers)} listed twice")
    return numbers


def _spi_faults(given: list[str] | None) -> str:
    """--spi-fault (given once per window): the windows as :attr:`~bench.experiments.trials.TrialTask.spi_faults`
    holds them, checked as an experiment file's ``[rig] spi_faults`` (ValueError naming --spi-fault[i], the field,
    its value and what is allowed; a value declaring no window at all too, as "" or ";": not taken as no fault)."""
    from bench.rigs.texture_rig import SPI_FAULT_FORM, spi_fault_text, spi_faults_from_text

    for i, text in enumerate(given or ()):
        if not text.replace(";", "").strip():
            raise ValueError(f"--spi-fault[{i}] = {spelled(text)}: declares no window; write {SPI_FAULT_FORM}")
    windows, problems = spi_faults_from_text("; ".join(given or ()), "--spi-fault")
    if problems:
        raise ValueError("; ".join(problems))
    return spi_fault_text(windows)


def _open_out(path, default, force: bool, kind, keep=()):
    """The out folder, checked and locked: ``path`` (refused if it holds anything but ``keep``, unless ``force``;
    temporary files an interrupted run left are removed, :func:`say_leftovers` says which)
    or, without it, a fresh ``default[-n]`` (``default`` itself with ``force``) — as ``run`` does.  The earlier
    results ``force`` replaces stay until ``clear_earlier()``, called as the new ones are written: a sweep or an
    experiment that fails or is stopped first leaves them as they were."""
    from pathlib import Path

    from bench.reporting.outdir import OutFolder, fresh_folder

    if path is None:
        return fresh_folder(Path(default), force=force, kind=kind, defer_clearing=True)
    return OutFolder.open(path, force=force, kind=kind, keep=keep, defer_clearing=True)


def _results_not_written(e: OSError, out: Path, files, trials_json: str):
    """The error for results that could not all be written into ``out`` (a full disk): the file and the disk's
    words, which of ``files`` are in place, and where the trials are — ``out``'s trials.json, else a trials.json
    (``trials_json``, its text) saved in the system's temporary folder, else lost.  Exit status 1."""
    from bench.atomic import save_in_temp_folder
    from bench.errors import OutputNotWritten

    written = [f for f in files if (out / f).is_file()]
    if "trials.json" in written:
        where = f"the trials are in {escaped(str(out / 'trials.json'))}"
    else:
        try:
            saved = save_in_temp_folder(lambda path: path.write_text(trials_json, encoding="utf-8"),
                                        "biotac-trials-", ".json")
            where = f"the trials were saved to {escaped(str(saved))} instead"
        except OSError as lost:
            where = f"the trials could not be saved in the temporary folder either ({lost.strerror or lost}): lost"
    failed = Path(e.filename).name if e.filename else "a file"
    return OutputNotWritten(f"{escaped(str(out / failed))} could not be written ({e.strerror or e}); written: "
                            f"{', '.join(written) or 'nothing'}; {where}")


def _cmd_texture_sweep(a) -> int:
    from bench.campaigns.engine import ClusterSpec, signals_held
    from bench.experiments.trials import clipped_note, rows_to_arrays, sweep, sweep_tasks, wear_per_movement
    from bench.reporting.experiment_report import write_rows_csv, write_text
    from bench.reporting import trials_file
    from bench.reporting.outdir import FolderKind
    from bench.reporting.sweep_plots import properties_vs_movement
    from bench.cli.args import library_option
    from bench.rigs.texture_rig import movement_grid
    from bench.errors import TextureError
    from bench.textures.library import check_unchanged

    grid = movement_grid()
    spi_faults = _spi_faults(a.spi_fault)
    library = library_option(a.library)
    textures = _texture_numbers(a.textures, library)
    ids = list(range(len(grid))) if a.movements == "all" else _int_list("--movements", a.movements, 0, len(grid) - 1)
    movements = [grid[i] for i in ids]
    kind = FolderKind("an earlier sweep's files", SWEEP_FILES)
    folder = say_leftovers(_open_out(a.out, "out/texture-sweep", a.force, kind))  # checked, locked before anything
    try:
        out = folder.path
        tasks = sweep_tasks(textures, movements, a.trials, a.seed, a.fidelity, not a.smooth_skin, movement_ids=ids,
                            library="" if library.shipped else library.path, spi_faults=spi_faults)
        spec = ClusterSpec.from_env(a.scheduler, a.workers)
        print(f"{len(tasks)} trials ({len(textures)} textures × {len(movements)} movements × {a.trials}) on "
              f"{spec.describe()}", file=sys.stderr)
        t0 = time.perf_counter()
        rows = sweep(tasks, spec=spec, progress=not a.quiet)
        wall = time.perf_counter() - t0
        try:  # (each trial read the file on its worker)
            check_unchanged(library, "the sweep")
        except TextureError as e:
            raise ValueError(f"{library.path}: {'; '.join(e.problems)}") from None  # (one line)
        trials_json = trials_file.trials_json("texture-sweep", rows, library.record(), wall, spec.describe())
        with signals_held():  # a signal meanwhile: every file finished first, then the stop
            folder.clear_earlier()
            try:
                write_rows_csv(out / "trials.csv", rows)
                write_text(out / "trials.json", trials_json)
                write_rows_csv(out / "wear.csv", wear_per_movement(movements, movement_ids=ids))
                properties_vs_movement(rows_to_arrays(rows), {n: library.textures[n].name for n in textures},
                                       out / "properties.png")
            except OSError as e:
                raise _results_not_written(e, out, SWEEP_FILES, trials_json) from None
    finally:
        folder.close()
    from bench.reporting.report import realtime_said

    sim = sum(r["simulated_s"] for r in rows)
    print(f"wrote {escaped(str(out))}/ ({', '.join(SWEEP_FILES)}): {len(rows)} trials, "
          f"{sim:.0f} simulated s in {wall:.1f} s wall ({realtime_said(sim / wall)} real time)")
    if clipped_note(rows):
        print(f"note: {clipped_note(rows)}")
    return 0


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    s = sub.add_parser("texture-sweep", help="the texture rig over textures × movements × repetitions (Dask)",
                       description=SWEEP_HELP, formatter_class=fmt)
    s.add_argument("--textures", required=True,
                   help="comma-separated texture numbers or names (biotac-bench textures), \"all\" (D's T1..T117) or "
                        "\"library\" (every texture of the library: D's, the test surfaces, groups of its own)")
    s.add_argument("--movements", default="all", help="'all' (the 36 of D eqs 6.20–6.21) or grid ids 0..35 "
                                                      "(id = 6 × force step + velocity step)")
    s.add_argument("--trials", type=whole(1, 1000), default=6, help="repetitions per texture and movement, 1 to "
                                                                   "1000 (D's pilot: 6)")
    s.add_argument("--seed", type=any_seed, default=0,
                   help="the sweep's seed; each trial's seed derives from it")
    s.add_argument("--fidelity", default="default", choices=list(PROFILES),
                   help="fidelity profile of every trial (biotac-bench profiles)")
    s.add_argument("--smooth-skin", action="store_true", help="a skin without fingerprint ridges")
    s.add_argument("--library", metavar="FILE",
                   help="the textures come from this library file (TOML as fixtures/textures/library.toml, or .json "
                        "as `biotac-bench textures --json` prints; default: the shipped library)")
    s.add_argument("--spi-fault", action="append", metavar="start_s=S,end_s=S,SETTING=VALUE",
                   help="SPI faults on the rig's bus in every trial from start_s to end_s (s from the trial's start), "
                        "e.g. start_s=0.3,end_s=0.4,miso_flip_bit=1; settings: miso_flip_bit and mosi_flip_bit "
                        "(0 to 15), miso_stuck (0 or 1), bad_parity and slow_response (true or false); once per "
                        "window, windows not overlapping (an experiment file: [rig] spi_faults)")
    s.add_argument("--out", help="output folder (default: a fresh out/texture-sweep[-n]); refused if it holds "
                                 "anything, unless --force")
    s.add_argument("--force", action="store_true", help="replace an earlier sweep's files in --out as the new ones "
                                                        "are written (anything else there is still refused)")
    add_cluster_arguments(s)
    s.add_argument("--quiet", action="store_true", help="no progress bar")
    s.set_defaults(func=sigterm_like_ctrl_c(_cmd_texture_sweep))
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

The textures come from the shipped library, or from one of your own: [experiment] library = "my_textures.toml"
(relative to the experiment file; the format of fixtures/textures/library.toml, or .json as `biotac-bench textures
--json` prints; the workers must be able to read the file).  pilot.textures and training.textures take a list of
numbers, "all" (D's T1..T117, the dissertation's experiment, whatever else the library holds) or "library" (every
texture the library holds: D's, the test surfaces, groups of its own), either word in any case.  [rig] spi_faults
= [{start_s = 0.25, end_s = 0.35, miso_flip_bit = 1}, ...] puts SPI faults on the rig's bus in every trial
(trials.csv: rejected_samples, the samples the host rejected).

Trials run on Dask (a LocalCluster on this machine's cores, or --scheduler / DASK_SCHEDULER_ADDRESS) and each
stage's trials are cached in --cache (out/cache) by content hash, so changing the classifier settings re-runs no
sliding.  Ctrl-C stops the experiment (exit 130; SIGTERM: 143); the stages already finished stay cached, and a
file being written is finished first.

Writes into --out (default: a fresh out/explore/<name>[-n]): report.md (beside D's numbers), summary.json,
accuracy.csv, accuracy_per_texture.csv, confusion.csv, pilot_uncertainty.csv, trials.csv/json (trials.json in
texture-sweep's schema: bench/reporting/trials_file.py),
properties_at_optimal_movements.png, probability_evolution.png.  --ablation NAME runs a variant into
--out/<name>/ and adds a comparison table to --out/ablations.md:
{ablations}
  all: every one of them.
An --out folder that holds anything is refused: to re-run into it (say, after changing the classifier settings),
add --force — it replaces the earlier results and keeps the stage cache, so no trial runs
again.

  biotac-bench explore fixtures/experiments/fishel2012.toml
  biotac-bench explore fixtures/experiments/quick.toml --ablation smooth-skin
  biotac-bench explore fixtures/experiments/quick.toml --out out/quick --force   # re-run, the trials from the cache
""".replace("{ablations}", "\n".join(f"  {name}: {what}" for name, (what, _) in ABLATIONS.items()))


def _entry_inside(path, folder) -> str | None:
    """The name of the entry of ``folder`` that holds ``path`` (or is it), if ``path`` lies inside ``folder`` —
    as written (a symbolic link in ``folder``, wherever it points) or once links are resolved."""
    import os
    from pathlib import Path

    for where, inside in ((os.path.abspath(path), os.path.abspath(folder)), (Path(path).resolve(),
                                                                             Path(folder).resolve())):
        try:
            rel = Path(where).relative_to(inside)
        except ValueError:
            continue
        return rel.parts[0] if rel.parts else None
    return None


#: explore's stage cache unless --cache says otherwise
DEFAULT_CACHE = "out/cache"


def _cmd_explore(a) -> int:
    from bench.campaigns.engine import ClusterSpec, signals_held
    from bench.experiments.experiment import (ablated, all_leaves_out_note, identified_among, load_experiment,
                                              run_experiment, summary)
    from bench.reporting.experiment_report import OUTPUT_FILES, experiment_trials_json, write_outputs, write_text
    from bench.reporting.outdir import FolderKind, folder_named, made_folders, writable_folder

    if a.no_cache and a.cache is not None:
        raise ValueError(f"{folder_named(a.cache, '--cache')} with --no-cache: --no-cache runs every trial again and "
                         f"caches nothing; give one or the other")
    cache_defaulted = a.cache is None  # (messages name it as the default folder, not as a --cache not given)
    a.cache = a.cache or DEFAULT_CACHE
    spec = load_experiment(a.experiment)
    if note := all_leaves_out_note(spec):
        print(f"note: {note}", file=sys.stderr)
    if not a.no_cache and a.out is not None and Path(a.cache).resolve() == Path(a.out).resolve():
        raise ValueError(f"{folder_named(a.cache, '--cache')} is --out: the results and the stage cache need folders of "
                         f"their own (the cache's entries would make a later --force refuse the folder); the cache may "
                         f"sit inside --out, e.g. {folder_named(Path(a.out) / 'cache', '--cache')}")
    names = [] if not a.ablation else (list(ABLATIONS) if a.ablation == "all" else [a.ablation])
    variants = [("baseline", spec, "as specified")] + [(n, *ablated(spec, n)) for n in names]  # (checked first)
    cache_kept = "" if a.no_cache else f" (the stage cache {escaped(a.cache)} is kept: no trial runs again)"
    kind = FolderKind("the earlier results" + cache_kept, OUTPUT_FILES + ("ablations.md",), tuple(ABLATIONS))
    keep = () if a.no_cache or a.out is None else tuple(filter(None, [_entry_inside(a.cache, a.out)]))
    # both checked before anything runs; the out folder is locked while the experiment runs
    folder = say_leftovers(_open_out(a.out, f"out/explore/{spec.name}", a.force, kind, keep))
    # a cache folder this command makes, then refused or failed, is removed if empty (before --out is closed)
    with contextlib.closing(folder), made_folders() as made:
        out = folder.path
        cache = None if a.no_cache else writable_folder(a.cache, "--cache", made, default=cache_defaulted)
        cluster = ClusterSpec.from_env(a.scheduler, a.workers)
        rows = []
        for label, sp, what in variants:
            t0 = time.perf_counter()
            print(f"== {label}: {cluster.describe()}", file=sys.stderr)
            result = run_experiment(sp, cache_dir=cache, cluster=cluster, progress=not a.quiet,
                                    log=lambda m: print(m, file=sys.stderr))
            where = out if label == "baseline" else out / label
            with signals_held():
                folder.clear_earlier()  # (once: the baseline's results come first)
                try:
                    files = write_outputs(result, where)
                except OSError as e:
                    raise _results_not_written(e, where, OUTPUT_FILES, experiment_trials_json(result)) from None
            rows.append((label, what, summary(result), identified_among(result)))
            print(f"wrote {where}/ ({', '.join(files)}) in {time.perf_counter() - t0:.0f} s")
        if names:
            lines = ["# Ablations", "", f"| variant | pairs (bayesian) | {rows[0][3]}-way (bayesian) | "
                                        f"median movements |", "|---|---|---|---|"]
            for label, what, s, _ in rows:
                lines.append(f"| {label} ({what}) | {100 * s['pairs/bayesian']['accuracy']:.1f} % | "
                             f"{100 * s['identification/bayesian']['accuracy']:.1f} % | "
                             f"{s['identification/bayesian']['median_moves']:g} |")
            with signals_held():
                write_text(out / "ablations.md", "\n".join(lines) + "\n")
            print("\n".join(lines))
        else:
            print((out / "report.md").read_text())
    return 0


def add_explore_command(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    e = sub.add_parser("explore", help="the texture experiment of D ch. 6: pilot, training, validation, "
                                       "Bayesian exploration (Dask)", description=EXPLORE_HELP, formatter_class=fmt)
    e.add_argument("experiment", help="experiment file (TOML), e.g. fixtures/experiments/fishel2012.toml")
    e.add_argument("--out", help="output folder (default: a fresh out/explore/<name>[-n]); refused if it holds "
                                 "anything, unless --force")
    e.add_argument("--force", action="store_true", help="replace the earlier results in --out as the new ones "
                                                        "are written (its ablation folders too; anything else there "
                                                        "is still refused); the "
                                                        "stage cache is kept, so no trial runs again")
    e.add_argument("--ablation", choices=list(ABLATIONS) + ["all"], help="also run a variant and compare")
    add_cluster_arguments(e)
    e.add_argument("--cache", help=f"where stage results are cached, kept across runs (default: {DEFAULT_CACHE})")
    e.add_argument("--no-cache", action="store_true", help="run every trial again")
    e.add_argument("--quiet", action="store_true", help="no progress bars")
    e.set_defaults(func=sigterm_like_ctrl_c(_cmd_explore))
