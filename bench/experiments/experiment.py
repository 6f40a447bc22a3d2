"""The dissertation's texture experiment (D ch. 6) end to end on the bench, from a declarative experiment file.

Stages, each a set of independent rig trials (:mod:`bench.experiments.trials`) run on the campaign engine and
cached by content hash (the stage's tasks, the texture library, the model's source files), so changing the
classifier or the strategies re-runs no sliding:

1. **pilot** — dissimilar textures × the 36 movements × repetitions on fresh skins; expected uncertainty U per
   property and movement with equal priors; the movement of least U per property, high-power movements
   excluded (their wear is shown, from the skin-wear law);
2. **training** — every texture × the three chosen movements × repetitions, in one session on one skin that
   wears and is replaced at the first visible wear (as D did);
3. **validation** — a separate set of trials (other seeds, so other start positions), on the same skin as the
   session goes on, for pairs of similar textures: by default (``pair_choice = "similar-description"``) the
   disjoint pairs nearest in physical description that share group, thermal material and compliance
   (:mod:`bench.experiments.pairs`, standing for D's hand choice); ``"random-within-group"`` draws pairs of one
   library group from the seed, ``"most-confused"`` takes the within-group pairs the training model confuses most
   (a harder test), or the file lists ``pairs``;
4. **virtual exploration** — Monte Carlo as D: pairs (1000 simulations each, threshold 99.9 %) and 117-way
   identification of the validation textures (threshold 99 %), for each strategy (bayesian, cycle, random).

:func:`run_experiment` returns an :class:`ExperimentResult`; :func:`write_outputs` writes tables, plots and a
Markdown report side by side with D's numbers.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from bench import tomlfile
from bench.tomlfile import spelled
from bench.errors import FileProblems
from bench.experiments import design
from bench.experiments import exploration as ex
from bench.experiments.pairs import PAIR_CHOICES, similar_description_pairs, why_not_pairs
from bench.experiments.trials import (
    FIRST_VISIBLE_WEAR, TrialTask, listed_twice, noise_scale_problem, schedule_skin, sweep, sweep_tasks, trial_seed,
    wear_per_movement,
)
from bench.paths import FIXTURES, OUT, REPO, folder_name_problem
from bench.atomic import atomic_write, release_lock, take_lock
from bench.rigs.texture_rig import movement_grid, spi_fault_text, spi_fault_windows
from bench.scenes.limits import MAX_SEED
from bench.textures.library import ALL_TEXTURES, LIBRARY_TEXTURES, texture_word

EXPERIMENTS_DIR = FIXTURES / "experiments"
#: D's published figures, for the report (Tables 6-4, 6-5; ch. 6 text)
D_FIGURES = {"pairs accuracy %": 99.6, "pairs median moves": 3, "117-way accuracy %": 95.4,
             "117-way median moves": 5, "human pairs accuracy %": 81.3,
             "best movements": {"traction": "1.26 N @ 1 cm/s", "roughness": "0.2 N @ 6.31 cm/s",
                                "fineness": "0.5 N @ 2.5 cm/s"}}
STRATEGY_NAMES = ("bayesian", "cycle", "random")
#: the largest [sensor] noise_scale an experiment file may give (dimensionless; the sensor's own ranges allow 14.1)
MAX_NOISE_SCALE = 10.0
_MOST_NOISE_WHY = "the largest an experiment file takes"
#: D's pilot picks (ch. 6) as (normal force N, velocity m/s), per property
D_BEST_MOVEMENTS = {"traction": (1.26, 0.01), "roughness": (0.2, 0.0631), "fineness": (0.5, 0.025)}


def d_best_movement_ids() -> dict[str, int]:
    """D's pilot picks as grid movement ids (the grid movement nearest each in log force and log velocity)."""
    grid = movement_grid()
    return {p: min(range(len(grid)), key=lambda m: abs(math.log(grid[m].force_N / f))
                   + abs(math.log(grid[m].velocity_m_per_s / v)))
            for p, (f, v) in D_BEST_MOVEMENTS.items()}


class ExperimentError(FileProblems):
    """An experiment file is invalid; ``problems`` lists every problem (field, value, what is allowed)."""


@dataclass
class ExperimentSpec:
    """An experiment (see ``fixtures/experiments/fishel2012.toml`` for every field and its meaning)."""

    name: str = "experiment"
    seed: int = 2012
    fidelity: str = "default"
    pilot_textures: list[int] = field(default_factory=lambda: list(design.D_PILOT_TEXTURES))
    pilot_trials: int = 6
    pilot_movements: list[int] | None = None  # grid ids; None = all 36
    exclude_high_power: bool = True
    training_textures: list[int] | None = None  # None = "all": D's 117 (T1..T117) of the library
    training_trials: int = 5
    wear: bool = True
    replace_skin: bool = True
    replace_at: float = FIRST_VISIBLE_WEAR  # fraction of the ridge height lost at which the skin is replaced
    pairs: list[tuple[int, int]] | None = None  # None = chosen from the training model
    n_pairs: int = 8
    pair_choice: str = "similar-description"  # one of pairs.PAIR_CHOICES
    validation_trials: int = 5
    strategies: tuple[str, ...] = STRATEGY_NAMES
    pair_threshold: float = 0.999
    identification_threshold: float = 0.99
    max_moves: int = 10
    pair_simulations: int = 1000
    identification_simulations: int = 8000  # in all, over the textures identified (D: its 16 validation textures)
    identify_all_textures: bool = False  # beyond D: 117-way for every texture (validation trials for all)
    fingerprints: bool = True
    noise_scale: float = 1.0
    stepper_noise_Pa: float = 0.0  # the rig's stepper background ([rig] stepper_noise_Pa; RigSettings)
    #: SPI faults on the rig's bus in every trial ([rig] spi_faults), as TrialTask.spi_faults holds them ("": none)
    spi_faults: str = ""
    library: str | None = None  # a texture library file of one's own ([experiment] library; None: the shipped one)
    source: str = "<experiment>"

    def key(self) -> str:
        return hashlib.sha256(repr(self).encode()).hexdigest()[:12]


#: the ablation variants (``explore --ablation``); defined in :mod:`bench.experiments.design`, light for the help
ABLATIONS = design.ABLATIONS


def ablated(spec: ExperimentSpec, name: str) -> tuple[ExperimentSpec, str]:
    """The experiment ``spec`` as ablation ``name`` changes it, and what changed in words ("field old → new"; a
    variant that changes nothing says so, rather than passing the baseline off as the variant)."""
    what, change = ABLATIONS[name]
    fields = change(spec)
    same = all(getattr(spec, k) == v for k, v in fields.items())
    diffs = ", ".join(f"{k} {getattr(spec, k)!r} → {v!r}" for k, v in fields.items()
                      if same or getattr(spec, k) != v)  # the fields it changes (all of them when none)
    problem = None
    if "noise_scale" in fields:  # the hint: what the file's own value may be (the variant scales it)
        factor = fields["noise_scale"] / spec.noise_scale if spec.noise_scale else 1.0
        problem = noise_scale_problem(fields["noise_scale"], most=(MAX_NOISE_SCALE, _MOST_NOISE_WHY), factor=factor)
    if problem:
        raise ExperimentError(f"--ablation {name}", [f"sensor.noise_scale {spec.noise_scale!r} → "
                                                     f"{fields['noise_scale']!r}: {problem}"])
    return replace(spec, **fields), f"{what}: {diffs}" + (" (the same as the baseline)" if same else "")


def load_experiment(path: str | Path) -> ExperimentSpec:
    """Read and validate an experiment file (TOML); every problem is reported at once."""
    text = tomlfile.read_text(path, ExperimentError, 1_000_000,
                              "an experiment needs at least an [experiment] table with its name")
    return parse_experiment(tomlfile.parse(text, str(path), ExperimentError, 8, "an experiment needs 3 levels"),
                            str(path))


#: how a message names the kind of value a field of an experiment file takes (as the scene's messages do)
_KIND_NAMES = {int: "a whole number", float: "a number", bool: "true or false"}
#: at most this many bad items of one list are named, each a problem of its own (then how many more)
MAX_ITEMS_NAMED = 5


def _whole(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def item_problems(where: str, items: list, ok, what: str) -> list[str]:
    """One problem per item of ``items`` (the list ``where`` of a file) that ``ok`` refuses, naming it by index and
    value and saying ``what`` an item is; at most :data:`MAX_ITEMS_NAMED`, then how many more."""
    bad = [(i, v) for i, v in enumerate(items) if not ok(v)]
    out = [f"{where}[{i}] = {spelled(v)}: must be {what}" for i, v in bad[:MAX_ITEMS_NAMED]]
    if len(bad) > MAX_ITEMS_NAMED:
        out.append(f"{where}: {len(bad) - MAX_ITEMS_NAMED} more item(s) refused for the same reason")
    return out


def _default_texture_problems(t: dict, spec: ExperimentSpec, lib, every: list[int], listing: str) -> list[str]:
    """What a library lacking D's textures makes of ``textures = "all"`` (D's 1-117; training's default too) and of
    the pilot's default (D's pilot textures): a problem each, rather than an empty stage or a pilot that fails on its
    workers over textures the library does not hold (a library of its own groups alone, say)."""
    out = []
    for table in ("pilot", "training"):
        given = t[table].get("textures")
        if texture_word(given) == ALL_TEXTURES or (given is None and table == "training"):
            if not every:
                shown = spelled(given) if given else '"all" (the default)'
                out.append(f"{table}.textures = {shown}: D's textures, numbered 1 to 117, and the library holds none; "
                           f"give {spelled(LIBRARY_TEXTURES)} for every texture it holds, or list the textures to use "
                           f"(`{listing}` lists them)")
        elif given is None:  # the pilot's default
            missing = [n for n in spec.pilot_textures if n not in lib]
            if missing:
                out.append(f"pilot.textures (the default, D's pilot textures {list(design.D_PILOT_TEXTURES)}): no "
                           f"texture {missing} in the library; list the textures to use (`{listing}` lists them)")
    return out


def all_leaves_out_note(spec: ExperimentSpec) -> str | None:
    """What a stage on "all" (D's T1..T117: the file's ``"all"``, or training's default) leaves out of the library
    beyond the test surfaces — its own groups' textures — and how to take them (``"library"``); None when nothing."""
    from bench.textures.library import LIBRARY_SIZE, TEST_GROUP, dissertation_textures, load_library

    lib = load_library(spec.library)
    every = dissertation_textures(lib)
    own = [n for n in lib if n not in every and not TEST_GROUP[1] <= n <= TEST_GROUP[2]]
    stages = [name for name, textures in (("pilot", spec.pilot_textures), ("training", spec.training_textures))
              if textures is None or (every and textures == every)]
    if not own or not stages:
        return None
    shown = ", ".join(f"T{n}" for n in own[:MAX_ITEMS_NAMED]) + (f" and {len(own) - MAX_ITEMS_NAMED} more"
                                                                    if len(own) > MAX_ITEMS_NAMED else "")
    return (f"{' and '.join(f'{s}.textures' for s in stages)}: D's T1..T{LIBRARY_SIZE} ({spelled(ALL_TEXTURES)}), "
            f"so the library's own {shown} {'is' if len(own) == 1 else 'are'} left out ({spelled(LIBRARY_TEXTURES)} "
            f"takes every texture it holds)")


def parse_experiment(data: dict, source: str = "<experiment>") -> ExperimentSpec:
    from bench.errors import TextureError
    from bench.textures.library import (LIBRARY_SIZE, dissertation_textures, library_path, listing_command,
                                        load_library, named_problems)
    from emulator.fidelity import PROFILES

    problems: list[str] = []
    known = {"experiment": {"name", "seed", "fidelity", "library"},
             "pilot": {"textures", "trials", "movements", "exclude_high_power"},
             "training": {"textures", "trials", "wear", "replace_skin", "replace_at"},
             "validation": {"pairs", "n_pairs", "trials", "pair_choice"},
             "exploration": {"strategies", "pair_threshold", "identification_threshold", "max_moves",
                             "pair_simulations", "identification_simulations", "identify_all_textures"},
             "skin": {"fingerprints"}, "sensor": {"noise_scale"}, "rig": {"stepper_noise_Pa", "spi_faults"}}
    if not isinstance(data, dict):
        raise ExperimentError(source, ["the file must hold tables"])
    for k, v in data.items():
        if k not in known:
            problems.append(f"unknown table [{k}]; known: {', '.join(known)}")
        elif not isinstance(v, dict):
            problems.append(f"[{k}] must be a table")
        else:
            problems += [f"{k}: unknown field {spelled(f)}; known: {', '.join(sorted(known[k]))}" for f in v if f not in known[k]]
    if problems:
        raise ExperimentError(source, problems)
    spec = ExperimentSpec(source=source)
    t = {k: data.get(k, {}) for k in known}
    if "library" in t["experiment"]:  # a texture library of the user's own, relative to the experiment file
        try:  # (the rules every file that names a library follows: bench.textures.library.library_path)
            spec.library = library_path(t["experiment"]["library"], "experiment.library", source)
        except TextureError as e:
            raise ExperimentError(source, e.problems) from None
    try:
        lib = load_library(spec.library)
    except TextureError as e:
        if spec.library is None:
            raise
        raise ExperimentError(source, named_problems("experiment.library", t["experiment"]["library"], spec.library,
                                                     e)) from None

    def get(table, key, kind, lo=None, hi=None, default=None):
        if key not in t[table]:
            return default
        v = t[table][key]
        if kind is float and isinstance(v, int) and not isinstance(v, bool):
            v = float(v)  # 2 means 2.0
        ok = isinstance(v, kind) and not isinstance(v, bool) if kind is not bool else isinstance(v, bool)
        if not ok:
            rng = f" ({lo} to {hi})" if lo is not None else ""
            problems.append(f"{table}.{key} = {spelled(v)}: must be {_KIND_NAMES[kind]}{rng}")
            return default
        if lo is not None and not (lo <= v <= hi):
            problems.append(f"{table}.{key} = {spelled(v)}: allowed range is {lo} to {hi}")
            return default
        return v

    def textures(table, key, default):
        if key not in t[table]:
            return default
        v = t[table][key]
        if texture_word(v) == ALL_TEXTURES:  # (any case, as --textures reads it)
            return None
        if texture_word(v) == LIBRARY_TEXTURES:
            return sorted(lib)
        if not isinstance(v, list) or not v:
            problems.append(f"{table}.{key} = {spelled(v)}: a list of texture numbers, {spelled(ALL_TEXTURES)} (D's "
                            f"T1..T{LIBRARY_SIZE}) or {spelled(LIBRARY_TEXTURES)} (every texture the library holds: "
                            f"D's, the test surfaces, groups of its own)")
            return default
        if bad := item_problems(f"{table}.{key}", v, lambda n: _whole(n), "a texture number (a whole number)"):
            problems.extend(bad)
            return default
        missing = [n for n in v if n not in lib]
        if missing:
            problems.append(f"{table}.{key}: no texture {missing} in the library (`{listing_command(spec.library)}`)")
        if listed_twice(v):
            problems.append(f"{table}.{key}: texture(s) {listed_twice(v)} listed twice")
        return v

    if "name" in t["experiment"] and (problem := folder_name_problem(t["experiment"]["name"], "experiment.name")):
        problems.append(problem)
    else:
        spec.name = t["experiment"].get("name", spec.name)
    spec.seed = get("experiment", "seed", int, 0, MAX_SEED, spec.seed)
    fid = t["experiment"].get("fidelity", spec.fidelity)
    if not isinstance(fid, str) or fid not in PROFILES:
        problems.append(f"experiment.fidelity = {spelled(fid)}: one of {', '.join(PROFILES)}")
    else:
        spec.fidelity = fid
    every = dissertation_textures(lib)  # "all": the 117 textures of D's library ("library": every one it holds)
    spec.pilot_textures = textures("pilot", "textures", spec.pilot_textures) or every
    problems += _default_texture_problems(t, spec, lib, every, listing_command(spec.library))
    if len(spec.pilot_textures) < 2 and (spec.pilot_textures or every):
        problems.append(f"pilot.textures = {spelled(spec.pilot_textures)}: at least 2 textures (the pilot measures how "
                        f"well each movement tells textures apart)")
    spec.pilot_trials = get("pilot", "trials", int, 2, 100, spec.pilot_trials)
    mv = t["pilot"].get("movements")
    if mv is not None and mv != "all":
        if not isinstance(mv, list) or len(mv) < 3:
            problems.append(f"pilot.movements = {spelled(mv)}: \"all\" or a list of at least 3 grid ids 0..35")
        elif bad := item_problems("pilot.movements", mv, lambda m: _whole(m) and 0 <= m < 36,
                                  "a grid id, a whole number 0 to 35"):
            problems.extend(bad)
        elif listed_twice(mv):
            problems.append(f"pilot.movements: grid id(s) {listed_twice(mv)} listed twice")
        else:
            spec.pilot_movements = mv
    spec.exclude_high_power = get("pilot", "exclude_high_power", bool, default=spec.exclude_high_power)
    if spec.exclude_high_power and spec.pilot_movements is not None:
        kept = [m for m in spec.pilot_movements if m not in excluded_movements(spec, spec.pilot_movements)]
        if not kept:
            problems.append(f"pilot.movements = {spelled(spec.pilot_movements)}: every one is a high-power movement, "
                            f"which pilot.exclude_high_power = true leaves out of the choice (their wear); list others "
                            f"too, or set exclude_high_power = false")
    spec.training_textures = textures("training", "textures", None)
    spec.training_trials = get("training", "trials", int, 2, 100, spec.training_trials)
    spec.wear = get("training", "wear", bool, default=spec.wear)
    spec.replace_skin = get("training", "replace_skin", bool, default=spec.replace_skin)
    spec.replace_at = get("training", "replace_at", float, 0.01, 1.0, spec.replace_at)
    if "replace_at" in t["training"] and (spec.wear is False or spec.replace_skin is False):
        off = "training.wear = false" if spec.wear is False else "training.replace_skin = false"
        problems.append(f"training.replace_at = {spelled(t['training']['replace_at'])} with {off}: no skin is replaced "
                        f"then, so replace_at would be ignored; give one or the other")
    pairs = t["validation"].get("pairs")
    chosen_by = [k for k in ("n_pairs", "pair_choice") if k in t["validation"]]
    if pairs is not None and chosen_by:
        problems.append(f"validation.pairs is given, with validation.{' and '.join(chosen_by)}: those choose the pairs "
                        f"when none are given; give one or the other")
    if pairs is not None:
        if not isinstance(pairs, list) or not pairs or not all(isinstance(p, list) and len(p) == 2 and all(
                isinstance(n, int) and not isinstance(n, bool) for n in p) for p in pairs):
            problems.append(f"validation.pairs = {spelled(pairs)}: a list of at least one [a, b] texture-number pair "
                            f"(leave pairs out to have n_pairs chosen by pair_choice)")
        else:
            spec.pairs = [tuple(p) for p in pairs]
            bad = [n for p in pairs for n in p if n not in lib]
            if bad:
                problems.append(f"validation.pairs: no texture {bad} in the library")
            same = [p for p in pairs if p[0] == p[1]]
            if same:
                problems.append(f"validation.pairs: {same} pair a texture with itself")
            listed = [n for p in pairs for n in p]
            twice = listed_twice(listed)
            if twice and not same:
                problems.append(f"validation.pairs: texture(s) {twice} in more than one pair (pairs must be disjoint)")
            untrained = sorted({n for n in listed if n in lib} - set(spec.training_textures or
                                                                    dissertation_textures(lib)))
            if untrained:
                problems.append(f"validation.pairs: texture(s) {untrained} not among the training textures (the "
                                f"classifier knows only those)")
    spec.n_pairs = get("validation", "n_pairs", int, 1, 58, spec.n_pairs)
    if spec.pairs is not None:  # the pairs listed are the pairs validated: summary.json's spec says how many
        spec.n_pairs = len(spec.pairs)
    choice = t["validation"].get("pair_choice", spec.pair_choice)
    if choice not in PAIR_CHOICES:
        problems.append(f"validation.pair_choice = {spelled(choice)}: one of "
                        + ", ".join(f'"{c}"' for c in PAIR_CHOICES))
    else:
        spec.pair_choice = choice
    trained = [n for n in (spec.training_textures or every) if n in lib]
    if spec.pairs is None and not problems:  # how many pairs the training textures can give, known before any trial
        if spec.pair_choice == "similar-description":
            available = len(similar_description_pairs(trained, spec.n_pairs, lib))
        else:
            groups = [lib[n].group for n in trained]
            available = sum(groups.count(g) // 2 for g in set(groups))
        if available < spec.n_pairs:
            why = ""
            if spec.pair_choice == "similar-description":
                refused = why_not_pairs(trained, lib)
                why = (" (a pair shares group, thermal material and compliance, both ridged or both not"
                       + (f"; within a group here: {', '.join(refused)}" if refused else "") + ")")
            problems.append(f"validation.n_pairs = {spec.n_pairs}: the training textures hold only {available} "
                            f"disjoint pairs for pair_choice = {spelled(spec.pair_choice)}{why}; name them with "
                            f"pairs = [[a, b], ...], or train on more textures")
    spec.validation_trials = get("validation", "trials", int, 1, 100, spec.validation_trials)
    strategies = t["exploration"].get("strategies", list(spec.strategies))
    if not isinstance(strategies, list) or not strategies or any(not isinstance(s, str) or s not in ex.STRATEGIES
                                                                  for s in strategies):
        problems.append(f"exploration.strategies = {spelled(strategies)}: a list of {', '.join(ex.STRATEGIES)}")
    elif "bayesian" not in strategies or listed_twice(strategies):
        problems.append(f"exploration.strategies = {spelled(strategies)}: \"bayesian\" and, to compare with it, any of "
                        f"{', '.join(s for s in ex.STRATEGIES if s != 'bayesian')}, each once (the experiment, its "
                        f"report and the ablations measure Bayesian exploration)")
    else:
        spec.strategies = tuple(strategies)
    spec.pair_threshold = get("exploration", "pair_threshold", float, 0.5, 0.999999, spec.pair_threshold)
    spec.identification_threshold = get("exploration", "identification_threshold", float, 0.01, 0.999999,
                                        spec.identification_threshold)
    spec.max_moves = get("exploration", "max_moves", int, 1, 100, spec.max_moves)
    spec.pair_simulations = get("exploration", "pair_simulations", int, 2, 10**6, spec.pair_simulations)
    if spec.pair_simulations % 2:
        problems.append(f"exploration.pair_simulations = {spec.pair_simulations}: an even number (per pair, half "
                        f"with each of its textures as the truth)")
    spec.identification_simulations = get("exploration", "identification_simulations", int, 1, 10**7,
                                          spec.identification_simulations)
    spec.identify_all_textures = get("exploration", "identify_all_textures", bool, default=False)
    spec.fingerprints = get("skin", "fingerprints", bool, default=True)
    spec.noise_scale = get("sensor", "noise_scale", float, 0.0, MAX_NOISE_SCALE, 1.0)
    noise_problem = noise_scale_problem(spec.noise_scale, most=(MAX_NOISE_SCALE, _MOST_NOISE_WHY))
    if noise_problem:
        problems.append(f"sensor.noise_scale = {spelled(spec.noise_scale)}: {noise_problem}")
    spec.stepper_noise_Pa = get("rig", "stepper_noise_Pa", float, 0.0, 100.0, 0.0)
    if "spi_faults" in t["rig"]:
        windows, bad = spi_fault_windows(t["rig"]["spi_faults"], "rig.spi_faults")
        problems += bad
        spec.spi_faults = spi_fault_text(windows)
    if "name" not in t["experiment"]:
        problems.append("[experiment] table with a name is missing (e.g. name = \"my-variant\")")
    if problems:
        raise ExperimentError(source, problems)
    return spec


# ----------------------------------------------------------------------------------------------- stages


def digest_files() -> list[Path]:
    """The files a stage's cache key digests: every module a trial runs through (the emulator, the rig, the
    texture library and properties, the runner, the bench's shared modules) and the data files it reads (the
    texture library, the electrode positions)."""
    packages = ("emulator", "bench/rigs", "bench/textures", "bench/running")
    files = sorted(f for d in packages for f in (REPO / d).rglob("*.py") if "tests" not in f.relative_to(REPO).parts)
    return files + sorted((REPO / "bench").glob("*.py")) + [
        REPO / "bench" / "experiments" / "trials.py", REPO / "bench" / "experiments" / "design.py",
        FIXTURES / "textures" / "library.toml", FIXTURES / "electrodes.csv"]


def _code_digest() -> str:
    """A digest of everything a trial's outcome depends on besides its task: the model's and rig's sources and
    the texture library."""
    h = hashlib.sha256()
    for f in digest_files():
        h.update(f.relative_to(REPO).as_posix().encode() + b"\0" + f.read_bytes())
    return h.hexdigest()[:16]


#: the counts beyond its task and properties every cached trial row must hold (a whole number each): a row cached
#: before the rows had one is run again, never read with the count missing
CACHED_ROW_COUNTS = ("rejected_samples",)


def _cached_rows(path: Path, tasks: list[TrialTask]) -> tuple[list[dict] | None, str]:
    """A stage's rows from its cache file, or (None, why not): the file must hold one row per task, each naming its
    task and carrying the three properties and :data:`CACHED_ROW_COUNTS` (a truncated, foreign or older file is run
    again, never trusted)."""
    from dataclasses import asdict

    try:
        rows = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as e:
        return None, f"unreadable ({e})"
    if not isinstance(rows, list) or len(rows) != len(tasks):
        return None, f"not {len(tasks)} trial rows"
    for row, task in zip(rows, tasks):
        undefined = row.get("undefined", {}) if isinstance(row, dict) else {}
        if not isinstance(row, dict) or any(row.get(k) != v for k, v in asdict(task).items()) or not all(
                isinstance(row.get(p), (int, float)) or (row.get(p) is None and isinstance(undefined, dict)
                                                         and p in undefined) for p in ex.PROPERTIES):
            return None, "a row that is not its task's trial"
        missing = [k for k in CACHED_ROW_COUNTS if not _whole(row.get(k))]
        if missing:
            return None, f"a row without {', '.join(missing)} (cached before the rows had it)"
    return rows, ""


def run_stage(name: str, tasks: list[TrialTask], cache_dir: Path | None, spec=None, progress: bool = True,
              client=None, log=print) -> list[dict]:
    """Run a stage's trials, or read them from the cache when the same tasks ran before with the same code (a
    cache file that does not hold them is said and replaced; one that cannot be written, a full disk, is said).
    Explores sharing a cache run each stage once: the cache entry is locked while it is read or run and written
    (:func:`_entry_lock`), and one that finds it locked waits, then reads what the other cached."""
    from bench.textures.library import read_library

    libraries = [read_library(f) for f in sorted({t.library for t in tasks if t.library})]  # as read now
    key = hashlib.sha256((repr(tasks) + _code_digest() + "".join(lib.sha256 for lib in libraries)).encode()
                         ).hexdigest()[:16]
    path = None if cache_dir is None else cache_dir / f"{name}-{key}.json"
    with _entry_lock(path, name, log):
        return _stage_rows(name, tasks, path, libraries, spec, progress, client, log)


def _stage_rows(name: str, tasks: list[TrialTask], path: Path | None, libraries, spec, progress: bool, client,
                log) -> list[dict]:
    """:func:`run_stage`'s work, its cache entry ``path`` (None: no cache) locked by the caller: the rows from the
    entry, or the trials run (their ``libraries`` checked unchanged) and cached."""
    from bench.textures.library import check_unchanged

    if path is not None and path.exists():
        rows, why = _cached_rows(path, tasks)
        if rows is not None:
            return rows
        log(f"note: the cached {name} stage {path} is {why}: its trials run again and replace it")
    rows = sweep(tasks, spec=spec, client=client, progress=progress) if tasks else []
    for lib in libraries:  # the trials read it on their workers: an edit meanwhile is refused, never cached
        check_unchanged(lib, f"the {name} stage")
    if path is not None:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            with atomic_write(path) as tmp:  # a unique temporary name: explores sharing a cache never collide
                tmp.write_text(json.dumps(rows))
        except OSError as e:  # a full disk: the trials are in hand, the experiment needs no cache to go on
            log(f"note: the {name} stage's trials could not be cached at {path} ({e.strerror or e}): the experiment "
                f"goes on; a re-run runs them again")
    return rows


#: how many times :func:`_entry_lock` makes the cache folder again when it vanishes as the lock is taken
ENTRY_LOCK_ATTEMPTS = 5


@contextlib.contextmanager
def _entry_lock(path: Path | None, name: str, log):
    """Hold the lock of the stage cache entry ``path`` (the file ``.<entry>.lock`` beside it, removed when released)
    while the ``name`` stage is read from it or run and written into it.  An explore sharing the cache that wants
    the same stage meanwhile says so through ``log`` and waits, then reads the trials this one cached (or runs them,
    if this one ended without caching them): no trial runs twice, no entry is written twice.  The cache folder is
    made again if it vanished (an explore that made it removes it, empty, as it fails — as this does: a cache folder
    this call made is removed again, if empty, when the stage fails).  Without a cache, or where no lock can be
    taken (said: the cache folder is not writable, so no entry can be written either), nothing is held."""
    if path is None:
        yield
        return
    lock_path = path.with_name(f".{path.name}.lock")

    def waiting(holder: str) -> None:
        who = f"another explore (pid {holder})" if holder else "another explore"
        log(f"note: {who} sharing the cache {path.parent} is running the {name} stage's trials; waiting for it to "
            f"finish, then reading them from the cache (or running them, if it ends without caching them)")

    fd, made = None, not path.parent.exists()
    for _ in range(ENTRY_LOCK_ATTEMPTS):
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            fd = take_lock(lock_path, wait=waiting)
            break
        except FileNotFoundError:  # the folder removed between making it and locking: made again
            continue
        except OSError as e:
            log(f"note: the {name} stage's cache entry {path} could not be locked ({e.strerror or e}): an explore "
                f"sharing the cache may run its trials too")
            break
    done = False
    try:
        yield
        done = True
    finally:
        if fd is not None:
            release_lock(fd, lock_path)
        if made and not done:  # (nothing cached: the folder it made goes, unless another explore holds an entry)
            with contextlib.suppress(OSError):
                path.parent.rmdir()


def table_from_rows(rows: list[dict], movement_ids: dict | None = None) -> ex.TrialTable:
    """A long-format :class:`~bench.experiments.exploration.TrialTable` from trial rows.

    Every property of every trial must have a value: a trial whose codes leave one undefined (null, with the
    reason, e.g. a PAC constant over the window with every noise source off) is refused with the trials named —
    leaving it out would bias its texture's normal, and the exploration has no use for a missing value."""
    undefined = [r for r in rows if r.get("undefined")]
    if undefined:
        raise ExperimentError(f"{undefined[0].get('stage') or 'the'} trials", [
            f"{len(undefined)} of {len(rows)} trials leave a property undefined, which the per-texture normals "
            f"cannot take (a stage cache keeps the trials; with every noise source off, noise_scale = 0, a quiet "
            f"slide's PAC can be one code); e.g. " + "; ".join(
                f"T{r['texture']} movement {r['movement_id']} trial {r['trial']}: "
                + ", ".join(f"{p} ({why})" for p, why in r["undefined"].items()) for r in undefined[:3])])
    n = len(rows)
    texture = np.repeat([r["texture"] for r in rows], 3)
    movement = np.repeat([r["movement_id"] for r in rows], 3)
    trial = np.repeat([r["trial"] for r in rows], 3)
    prop = np.tile(np.arange(3), n)
    value = np.array([[r["traction"], r["roughness"], r["fineness"]] for r in rows]).ravel()
    return ex.TrialTable(texture, movement, prop, trial, value)


def excluded_movements(spec: ExperimentSpec, movement_ids) -> list[int]:
    """The pilot movements (grid ids, of ``movement_ids``) left out of the choice of the best: the high-power ones
    when ``spec.exclude_high_power`` (their wear, D Fig. 6-7)."""
    high = ex.movement_grid()["high_power"]
    return [int(m) for m in movement_ids if high[m]] if spec.exclude_high_power else []


@dataclass
class ExperimentResult:
    spec: ExperimentSpec
    pilot_rows: list[dict]
    pilot_uncertainty: np.ndarray  # (36, 3), NaN where excluded or not run
    best_movements: np.ndarray  # grid id per property
    wear: list[dict]
    training_rows: list[dict]
    skin_history: list[dict]
    pairs: list[tuple[int, int]]
    validation_rows: list[dict]
    pair_results: dict  # strategy -> list of ExplorationResult (one per true texture of each pair)
    identification_results: dict  # strategy -> list of ExplorationResult
    wall_s: dict = field(default_factory=dict)
    library: dict = field(default_factory=dict)  # the texture library as read at the start: path, sha256, shipped
    workers: str = ""  # where the trials ran (ClusterSpec.describe(): a LocalCluster's size or a scheduler)


def _pick_pairs(model: ex.TextureModel, best: np.ndarray, n_pairs: int, choice: str, seed: int,
                source: str = "<experiment>", library: str | None = None) -> list[tuple[int, int]]:
    """``n_pairs`` disjoint pairs of textures of one library group: nearest in description
    (``similar-description``, :mod:`bench.experiments.pairs`), drawn at random (``random-within-group``), or those
    with the highest mean confusion at the best movements (``most-confused``). ExperimentError if the training
    textures hold fewer such pairs."""
    from bench.textures.library import load_library

    lib = load_library(library)
    if choice == "similar-description":
        pairs = similar_description_pairs(model.textures, n_pairs, lib)
        if len(pairs) < n_pairs:
            raise ExperimentError(source, [f"validation.n_pairs = {n_pairs}: the training textures hold only "
                                           f"{len(pairs)} disjoint similar pairs (pair_choice = {spelled(choice)})"])
        return pairs
    conf = model.confusion()  # (K, K, M, P)
    mi = model.movement_index(best)
    c = np.mean([conf[:, :, mi[p], p] for p in range(3)], axis=0)
    if choice == "random-within-group":
        c = np.random.default_rng(np.random.SeedSequence([seed, 0x9A125])).random(c.shape)
    ids = model.textures
    cands = []
    for i in range(len(ids)):
        for j in range(i + 1, len(ids)):
            if lib[int(ids[i])].group == lib[int(ids[j])].group:
                cands.append((c[i, j], int(ids[i]), int(ids[j])))
    used, pairs = set(), []
    for _, a, b in sorted(cands, reverse=True):
        if a not in used and b not in used:
            pairs.append((a, b))
            used |= {a, b}
        if len(pairs) == n_pairs:
            return pairs
    raise ExperimentError(source, [f"validation.n_pairs = {n_pairs}: the training textures hold only {len(pairs)} "
                                   f"disjoint pairs within one library group (pair_choice = {spelled(choice)})"])


def run_experiment(spec: ExperimentSpec, cache_dir: Path | None = OUT / "cache", cluster=None,
                   progress: bool = True, log=print) -> ExperimentResult:
    """Pilot → training → validation → virtual exploration (see the module docstring)."""
    import time

    from bench.campaigns.engine import ClusterSpec, close, connect
    from bench.textures.library import check_unchanged, dissertation_textures, read_library

    wall = {}
    library = read_library(spec.library)  # (complete when shipped, as load_library)
    lib = library.textures
    grid = movement_grid()
    cluster = cluster or ClusterSpec.from_env()
    client = connect(cluster)
    try:
        # 1. pilot
        t0 = time.perf_counter()
        ids = spec.pilot_movements if spec.pilot_movements is not None else list(range(len(grid)))
        tasks = sweep_tasks(spec.pilot_textures, [grid[i] for i in ids], spec.pilot_trials, spec.seed,
                            spec.fidelity, spec.fingerprints, stage="pilot", noise_scale=spec.noise_scale,
                            movement_ids=ids, stepper_noise_Pa=spec.stepper_noise_Pa, library=spec.library or "",
                            spi_faults=spec.spi_faults)
        log(f"pilot: {len(tasks)} trials")
        pilot_rows = run_stage("pilot", tasks, cache_dir, client=client, progress=progress, log=log)
        model = ex.fit_model(table_from_rows(pilot_rows))
        exclude = excluded_movements(spec, ids)
        u = ex.pilot_uncertainty(model, exclude_movements=exclude)
        best = ex.least_uncertain_movements(model, exclude_movements=exclude)
        u_full = np.full((len(grid), 3), np.nan)
        u_full[model.movements] = u
        wall["pilot"] = time.perf_counter() - t0
        # 2. training: one session on one skin, in texture order, replaced at the first visible wear
        t0 = time.perf_counter()
        textures = spec.training_textures or dissertation_textures(lib)
        tasks = []
        for tex in textures:
            for p, m in enumerate(best):
                for k in range(spec.training_trials):
                    tasks.append(TrialTask(tex, grid[m].force_N, grid[m].velocity_m_per_s, k,
                                           trial_seed(spec.seed, "training", tex, int(m), k), int(m), spec.fidelity,
                                           spec.fingerprints, stage="training", noise_scale=spec.noise_scale,
                                           stepper_noise_Pa=spec.stepper_noise_Pa, library=spec.library or "",
                                           spi_faults=spec.spi_faults))
        # the same movement may be best for two properties: run it once
        tasks = list({(t.texture, t.movement_id, t.trial): t for t in tasks}.values())
        replace_at = spec.replace_at if spec.replace_skin else None
        tasks, history = schedule_skin(tasks, wear=spec.wear, replace_at=replace_at)
        log(f"training: {len(tasks)} trials on {history[-1]['skin'] if history else 1} skin(s)")
        training_rows = run_stage("training", tasks, cache_dir, client=client, progress=progress, log=log)
        train = ex.fit_model(table_from_rows(training_rows))
        wall["training"] = time.perf_counter() - t0
        # 3. validation: the session goes on with the same skin
        t0 = time.perf_counter()
        pairs = spec.pairs or _pick_pairs(train, best, spec.n_pairs, spec.pair_choice, spec.seed, spec.source,
                                          spec.library)
        val_textures = sorted({n for p in pairs for n in p} | (set(textures) if spec.identify_all_textures else set()))
        val_tasks = [TrialTask(tex, grid[m].force_N, grid[m].velocity_m_per_s, k,
                               trial_seed(spec.seed, "validation", tex, int(m), k), int(m), spec.fidelity,
                               spec.fingerprints, stage="validation", noise_scale=spec.noise_scale,
                               stepper_noise_Pa=spec.stepper_noise_Pa, library=spec.library or "",
                               spi_faults=spec.spi_faults)
                     for tex in val_textures for m in sorted(set(best.tolist())) for k in range(spec.validation_trials)]
        session, history = schedule_skin(tasks + val_tasks, wear=spec.wear, replace_at=replace_at)
        tasks = session[len(tasks):]
        log(f"validation: {len(tasks)} trials for {len(val_textures)} textures")
        validation_rows = run_stage("validation", tasks, cache_dir, client=client, progress=progress, log=log)
        val_table = table_from_rows(validation_rows)
        wall["validation"] = time.perf_counter() - t0
    finally:
        close(client)
    check_unchanged(library, "the experiment's stages")  # the library the outputs name is the one every stage ran
    # 4. virtual exploration
    t0 = time.perf_counter()
    pair_results, ident_results = {}, {}
    all_ctx = ex.prepare(train, best_movements=best)
    share = dict(zip(val_textures, simulation_shares(spec.identification_simulations, len(val_textures))))
    for s in spec.strategies:
        pair_results[s] = []
        for a, b in pairs:
            ctx = ex.prepare(train, candidates=[a, b], best_movements=best)
            for true in (a, b):
                pair_results[s].append(ex.simulate(train, val_table, true, strategy=s,
                                                   threshold=spec.pair_threshold, max_moves=spec.max_moves,
                                                   n_sims=spec.pair_simulations // 2, seed=spec.seed, context=ctx))
        ident_results[s] = [ex.simulate(train, val_table, true, strategy=s, threshold=spec.identification_threshold,
                                        max_moves=spec.max_moves, n_sims=share[true], seed=spec.seed + 1,
                                        context=all_ctx)
                            for true in val_textures]
    wall["exploration"] = time.perf_counter() - t0
    return ExperimentResult(spec, pilot_rows, u_full, best, wear_per_movement(), training_rows, history, pairs,
                            validation_rows, pair_results, ident_results, wall, library.record(), cluster.describe())


def simulation_shares(total: int, n: int) -> list[int]:
    """``total`` simulations shared among ``n`` textures: as equal as whole numbers allow (the first ``total % n``
    one more), so the file's number is the number run; at least one each."""
    return [max(1, total // n + (k < total % n)) for k in range(n)]


def identified_among(result: ExperimentResult) -> int:
    """How many textures the identification chooses among: the training textures (D: 117)."""
    return len({int(r["texture"]) for r in result.training_rows})


def summary(result: ExperimentResult) -> dict:
    """Accuracy and movements to converge per strategy, for pairs and 117-way identification."""
    out = {}
    for task, res in (("pairs", result.pair_results), ("identification", result.identification_results)):
        for s, rs in res.items():
            per_texture = {int(r.true_texture): float(np.mean(r.correct)) for r in rs}
            med = {int(r.true_texture): float(ex.median_moves(r)) for r in rs}
            out[f"{task}/{s}"] = {"accuracy": ex.accuracy(rs), "median_moves": ex.median_moves(rs),
                                  "per_texture_accuracy": per_texture, "per_texture_median_moves": med,
                                  "simulations": int(sum(len(r) for r in rs))}
    return out


def beats_baselines(result: ExperimentResult, strict: bool = False) -> int | None:
    """Validation textures on which Bayesian exploration is at least as accurate as cycling and as random choice,
    and converges in no more movements (medians).  ``strict``: and, against each baseline, strictly better in at
    least one of the two (a tie — say 100 % in the same median number of movements — does not count).  None when
    the experiment ran no baseline to compare with."""
    s = summary(result)
    bay = s["identification/bayesian"]
    baselines = [f"identification/{other}" for other in ("cycle", "random") if f"identification/{other}" in s]
    if not baselines:
        return None
    count = 0
    for tex, acc in bay["per_texture_accuracy"].items():
        moves = bay["per_texture_median_moves"][tex]
        ok = True
        for key in baselines:
            acc_b, moves_b = s[key]["per_texture_accuracy"][tex], s[key]["per_texture_median_moves"][tex]
            if acc < acc_b or moves > moves_b or (strict and acc == acc_b and moves == moves_b):
                ok = False
        count += ok
    return count


def movement_label(m: int) -> str:
    g = movement_grid()[int(m)]
    return f"{g.force_N:.2f} N @ {g.velocity_m_per_s * 100:.2f} cm/s"


def _finite(x: float) -> str:
    return "∞" if not math.isfinite(x) else f"{x:g}"
