"""Scene commands: run a scene, validate scene files, list scenes, fidelity profiles and sensor parameters."""

from __future__ import annotations

import argparse
import os
import signal
import sys
from pathlib import Path

from bench.cli.args import Terminated, sigterm_like_ctrl_c, stimuli_count
from bench.errors import escaped
from bench.paths import REPO, SCENES_DIR
from emulator.fidelity import PROFILES


RUN_HELP = """\
Runs a scene through sensor -> SPI peripheral -> host sampler.  The scene is a scene file, or the name of a
shipped scene (`biotac-bench scenes` lists them): `taps` is fixtures/scenes/taps.toml when no file "taps" is in
the current folder.  It writes, into --out:
  samples.h5    every sample, streamed to disk as the run goes (HDF5): /<CH>/t (s), /<CH>/code (12-bit),
                /<CH>/status (0 ok, 1 parity error, 2 error word); the scene, seed, fidelity and status as
                attributes
  codes.npz     export of the same (<CH>_t, <CH>_code, <CH>_status) plus physical units (PAC_Pa, PDC_kPa,
                PDC_force_N, ...) using the published conversions; runs up to 600 simulated s (--npz: any)
  samples.csv   the same in long format (with --csv; same length rule)
  record.json   everything about the run: scene, parameters, effects that ran and their cost, results,
                status ("ok", "failed" with the error, "interrupted" with the signal); written last
  report.md     a short human-readable report
  traces.png, spectrogram.png   (from min/max envelopes and an averaged spectrogram: any run length)
  electrode_map.png   with a placed touch, tap or press and any electrode read
  forces.png, properties.png    a sliding run's forces and slip, and each trial's texture properties

The out folder is checked and locked before anything runs; a folder that is not empty is refused unless
--force (which first removes an earlier run's files, and nothing else). Without --out, a fresh folder
out/<scene name>[-2, -3, ...] is used. Every file is written under a temporary name and renamed into place.
Ctrl-C (SIGINT) or SIGTERM stops the run at the next chunk and writes everything recorded so far with
status "interrupted"; exit status 130 / 143.

scene file (TOML):
  [scene]    name, duration_s, seed (0), fidelity ("fast" | "default" | "reference"), description,
             library = "my_textures.toml" (the library file every slide's texture comes from, relative to the
             scene file; default the shipped one; record.json and report.md state its path and SHA-256)
  [sensor]   sensor 1: unit = 17 | "nominal" | "BT..." (a sensor unit: `biotac-bench units`), variant = "biotac" |
             "biotac-sp", and any sensor parameter by name on top of the unit, e.g. inflation_volume_mL = 0.6
             (see `biotac-bench params`)
  [[sensors]] one table per further finger: index = 2..5, unit, variant, parameters (sensors not described are
             sensor 1's twin, at rest)
  [sensor.faults] / [sensors.faults] (after its [[sensors]] table): that finger's own faults, keys as [faults]
  [host]     sequence = "default" (44-slot frame) or ["PAC", "PDC"]; slot_rate_Hz (4400); spi_clock_Hz (4.4e6);
             spi = "software" (the Python model) | "rtl" (the Verilog twin, run by the C++ Verilator harness)
  [noise]    johnson, amplifier, mains_hum, adc, spi_coupling = true | false
  [analysis] impact_detection = true   (applies D ch. 5's rule to every sphere drop)
  [[stimulus]] one table per stimulus, by kind:
     tap          at_s (s or list), peak_N, duration_s (0.03); optional place as a touch's (then the electrodes
                  there feel it; without one only PDC/PAC move)
     press        start_s, force_N, ramp_s (0.5), hold_s (1.0); optional place as a touch's (as for tap)
     sphere_drop  at_s, sphere ("0.45 mm solder ball", ...) or mass_mg, height_m (0.07; falls through air);
                  no place (its impulse reaches the fluid only)
     vibration    start_s, duration_s, amplitude_um, frequency_Hz  | f_start_Hz + f_stop_Hz (log sweep), fade_s
                  (0.01, at most duration_s / 2: a raised-cosine fade-in and fade-out)
     pressure     start_s, duration_s, offset_kPa, amplitude_Pa, frequency_Hz, fade_s  (calibrator on the liquid)
     touch        start_s, force_N, ramp_s, hold_s; where: electrode ("E17") or x_mm + angle_deg;
                  indenter_radius_mm (3), tangential_N (at most 1.3 × force_N: beyond, the skin would slip;
                  use a slide), shear_angle_deg (0 toward the tip, 90 around); material ("aluminum", "glass",
                  "wood", "polystyrene foam", ...) and object_temperature_C for thermal contact
     power_on     at_s   (heaters start from ambient)        ambient_step  at_s, temperature_C
     heater_failure  at_s
     slide        start_s (s or list: one trial each), texture (library number, "T30" or name; biotac-bench
                  textures), force_N, velocity_mm_per_s, distance_mm; approach_s (0.3), hold_s (0.5),
                  accel_s (0.05), lift_s (0.2), start_position_mm (default: drawn from the seed)
     replace_skin at_s   (a fresh skin between slides)
  [skin]     fingerprints = true | false, ridge_height_um (200 = new), wear = true, wear_coefficient (7.7e-6)
  [faults]   electrode_open = [3], electrode_short = [5], mux_stuck = 7, thermistor = "open" | "short",
             heater_failed = true, fluid_leak_mL_per_min (0..60) from fluid_leak_start_s (0): a leak
             (every sensor of the scene has these; a finger's own go in its [sensor.faults] / [sensors.faults],
             each fault in one place)

Every at_s / start_s may be a list: one stimulus per instant (power_on and heater_failure happen once per sensor).
Every [[stimulus]] may name its sensor: sensor = 2 (default 1); it reaches that sensor only.
Every stimulus must end within the scene (a press ends at start_s + 2·ramp_s + hold_s): one that would run past
duration_s is refused, never cut off.

Several sensors: each runs through its own SPI side and host sampler (the scene's [host], seed + k - 1); --out
holds sensor 1's files as for one sensor, and sensor<k>/ the same files for sensor k (its own report, traces,
samples; the sliding trials of a finger that slides).
The file (UTF-8, at most 1 MB) is validated before anything runs, with --seed/--fidelity/--spi applied; every
problem is listed with its field, value and allowed range, and so is a scene whose analysis could not run
(impact_detection without PAC, slides without PAC and PDC, a sequence the scene is too short to read); exit
status 2. A run that fails part-way still writes what it recorded (record.json says "failed" and why); exit
status 1.

examples:
  biotac-bench run taps                                   # a shipped scene by name: out/taps/
  biotac-bench run my_scene.toml --out out/mine --csv     # your own scene file, also samples.csv
  biotac-bench run sphere_drops --fidelity reference --seed 3 --no-plots
  biotac-bench run taps --spi rtl                         # the same scene over the Verilog RTL
"""

SCENES_HELP = """\
Lists the shipped scenes (fixtures/scenes/*.toml): each one's name, its file (a path that works from the current
folder), what it does and how many simulated seconds it lasts.  Give the name or the path to run or validate:

  biotac-bench scenes
  biotac-bench run taps          # the same as: biotac-bench run <the path printed for taps>
  biotac-bench validate rest
"""

PROFILES_HELP = """\
Lists the fidelity profiles: each one's simulation grid rate and what it resolves.  A scene picks one in
[scene] fidelity (default "default"); run --fidelity overrides it; `biotac-bench benchmark` measures what each
costs and how far it is from "reference".

  biotac-bench profiles
  biotac-bench run taps --fidelity fast
"""

PARAMS_HELP = """\
Lists every sensor parameter, one a line: name, nominal value, unit, [allowed range], (source: D = the
dissertation, model = this emulator's choice) and what it is.  Any of them can be set by name in a scene's
[sensor] table (or a [[sensors]] table) on top of the sensor unit, within its range:

  biotac-bench params
  biotac-bench params | grep -i inflation
  # in a scene file:   [sensor]
  #                    inflation_volume_mL = 0.6
"""

VALIDATE_HELP = """\
Validates each scene completely (nothing runs) and prints "ok" with its name, duration, stimuli and fidelity (and
the SPI side if it is the RTL, the texture library's path and SHA-256 prefix if the scene slides), or every
problem with its field, value and allowed range.  Exit status 0 if every scene is valid, 1 if any is not,
2 for bad arguments.

  biotac-bench validate my_scene.toml
  biotac-bench validate fixtures/scenes/*.toml
  biotac-bench validate taps rest          # shipped scenes by name
"""


def _cmd_run(a) -> int:
    from bench.cli.args import say_leftovers
    from bench.reporting.outdir import OutFolder, fresh_folder
    from bench.reporting.session import run_to_folder
    from bench.running.runner import check_buildable
    from bench.scenes.scene import load_scene

    # the command line's values replace the file's before validation: the scene that runs is the one validated
    overrides = {k: v for k, v in (("scene.fidelity", a.fidelity), ("scene.seed", a.seed), ("host.spi", a.spi))
                 if v is not None}
    scene = load_scene(a.scene, overrides)  # validated completely, then the out folder checked: both before running
    check_buildable(scene)
    folder = say_leftovers(OutFolder.open(a.out, force=a.force) if a.out is not None
                           else fresh_folder(Path("out") / scene.name, force=a.force))
    res = None
    try:
        try:
            res = run_to_folder(scene, folder, force=a.force, csv=a.csv, npz=True if a.npz else None,
                                plots=not a.no_plots, progress=not a.quiet, compression=a.compression)
        finally:
            folder.close()
        _print_run(a, scene, res)
    except KeyboardInterrupt as e:  # (SIGTERM too: Terminated)
        if res is None:
            raise
        res.late_signal = "SIGTERM" if isinstance(e, Terminated) else "SIGINT"  # only the summary was cut short
    if res.late_signal:
        print(f"{res.late_signal} after the run's files were written: {res.folder}/ holds them all (record.json "
              f"status \"{res.record['status']}\")", file=sys.stderr)
        return 128 + signal.Signals[res.late_signal].value
    return res.exit_code


def _print_run(a, scene, res) -> None:
    """The report and what was written where, and a line for an interrupted or failed run."""
    from bench.reporting.report import identity_words, sensor_identity

    out, record = res.folder, res.record
    if not a.quiet:
        print((out / "report.md").read_text())
    print(f"wrote {escaped(str(out))}/ ({', '.join(record['outputs'])})" + (" for sensor 1" if scene.n_sensors > 1 else ""))
    for k, sub_record in sorted(res.sensor_records.items()):
        spec = scene.sensor_spec(k)
        print(f"wrote {escaped(str(out / f'sensor{k}'))}/ ({', '.join(sub_record['outputs'])}) for sensor {k} "
              f"({identity_words(sensor_identity(spec, k))}, {stimuli_count(len(spec.stimuli))}"
              + "".join(f", {n} = {v}" for n, v in spec.faults.items()) + ")")
        for name, why in sub_record.get("skipped_outputs", {}).items():
            print(f"note: sensor{k}/{name} {why}", file=sys.stderr)
    for name, why in record.get("skipped_outputs", {}).items():
        print(f"note: {name} {why}", file=sys.stderr)
    if record["status"] == "interrupted":
        print(f"interrupted by {record.get('interrupted_by')} at {record['simulated_s']:.3f} s of "
              f"{scene.duration_s:g} s: wrote what was recorded", file=sys.stderr)
    elif record["status"] != "ok":
        simulated = record["simulated_s"]
        when = (f"after all {scene.duration_s:g} s were simulated" if simulated >= scene.duration_s - 1e-9
                else f"at {simulated:.3f} s of {scene.duration_s:g} s")
        print(f"error: the run failed {when}: {record['error']}", file=sys.stderr)


def _cmd_validate(a) -> int:
    from bench.running.runner import check_buildable
    from bench.scenes.scene import SceneError, load_scene

    bad = 0
    for f in a.scenes:
        try:
            sc = load_scene(scene_file(f))
            check_buildable(sc)
            in_all = sum(len(sc.sensor_spec(k).stimuli) for k in range(1, sc.n_sensors + 1))
            more = f", {sc.n_sensors} sensors ({stimuli_count(in_all)} in all)" if sc.n_sensors > 1 else ""
            n = f"{stimuli_count(len(sc.stimuli))}{' on sensor 1' if sc.n_sensors > 1 else ''}"
            print(f"{escaped(f)}: ok ({sc.name}, {sc.duration_s} s, {n}, fidelity "
                  f"{sc.fidelity}{more}{_before_running(sc)})")
        except SceneError as e:
            print(e, file=sys.stderr)
            bad += 1
    return 1 if bad else 0


def _before_running(sc) -> str:
    """What else a user should know before running a valid scene, for the "ok" line: the SPI side when it is the
    RTL (built and run under Verilator), and the texture library its slides use (path and the first 16 hex digits
    of its SHA-256, as report.md shows them) when any sensor slides; "" otherwise."""
    from emulator.sliding import Slide

    parts = [f"SPI {sc.spi}"] if sc.spi != "software" else []
    slides = any(isinstance(st, Slide) for k in range(1, sc.n_sensors + 1) for st in sc.sensor_spec(k).stimuli)
    if slides and sc.library is not None:
        parts.append(f"textures {shown_path(Path(sc.library['path']))} sha256 {sc.library['sha256'][:16]}")
    return "".join(f", {p}" for p in parts)


def shipped_scenes() -> dict[str, Path]:
    """The shipped scene files by name (the file's stem, which ``biotac-bench run NAME`` accepts)."""
    return {f.stem: f for f in sorted(SCENES_DIR.glob("*.toml"))}


def shown_path(path: Path) -> str:
    """``path`` as it works from the current folder: relative to it when inside it, else absolute (for a message:
    :func:`bench.errors.escaped`)."""
    path = path.resolve()
    try:
        return escaped(str(path.relative_to(Path.cwd().resolve())))
    except ValueError:
        return escaped(str(path))


def scene_file(text: str) -> str:
    """A scene argument as a path: a file that exists as given; else the shipped scene of that name ("taps", or
    "taps.toml" or a folder of that name here with a note on stderr saying which file it is — never a path with a
    folder, "./taps.toml" included); else :class:`SceneError` with the shipped scenes that come close."""
    import difflib

    from bench.errors import SceneError

    given = Path(text)
    folder = given.is_dir()
    if (given.exists() or given.is_symlink()) and not folder:
        return text  # a file or device: the scene loader says what is wrong with it, if anything
    shipped = shipped_scenes()
    name = given.name.removesuffix(".toml")
    if "/" not in text and os.sep not in text and name in shipped:
        if text != name or folder:
            here = f"{text} here is a folder" if folder else f"no {text} here"
            print(f"note: {here}: the shipped scene {shipped[name]}", file=sys.stderr)
        return str(shipped[name])
    hint = "give a scene file, or a shipped scene's name (`biotac-bench scenes` lists them"
    near = difflib.get_close_matches(name, list(shipped), n=3, cutoff=0.6)
    hint += f"; close matches: {', '.join(near)})" if near else ")"
    if not given.is_absolute() and (REPO / given).is_file():
        hint = f"did you mean {REPO / given} (that path in the repository)?"
    why = "Is a directory" if folder else "No such file or directory"
    raise SceneError(text, [f"cannot read the file: {why}; {hint}"])


def scene_argument(text: str) -> str:
    """argparse type: a scene file or a shipped scene's name, as a path (:func:`scene_file`); a path that names
    nothing is refused in one line."""
    from bench.errors import SceneError

    text = _path("a scene file")(text)
    try:
        return scene_file(text)
    except SceneError as e:
        raise argparse.ArgumentTypeError(f"{text}: {e.problems[0]}") from None


def _cmd_scenes(a) -> int:
    from bench.scenes.scene import load_scene

    shipped = shipped_scenes()
    width = max(map(len, shipped))
    for name, f in shipped.items():
        sc = load_scene(f)
        print(f"{name:<{width}}  {shown_path(f)}\n    {sc.description or sc.name} ({sc.duration_s:g} s)")
    return 0


def _cmd_profiles(a) -> int:
    from emulator.fidelity import PROFILES

    for p in PROFILES.values():
        print(f"{p.name:10s} {p.description}")
    return 0


def _cmd_params(a) -> int:
    from emulator.params import PARAMETER_FIELDS, SensorParams

    d = SensorParams()
    for name, f in PARAMETER_FIELDS.items():
        m = f.metadata
        print(f"{name:38s} {getattr(d, name)!r:>24} {m['unit']:10s} [{m['range'][0]}, {m['range'][1]}] "
              f"({m['source']}) {m['doc']}")
    return 0


def _path(what: str):
    """argparse type: a non-empty path without a NUL byte (what the path names is checked by the command)."""

    def parse(text: str) -> str:
        if not text:
            raise argparse.ArgumentTypeError(f"an empty path: give {what}")
        if "\0" in text:
            raise argparse.ArgumentTypeError(f"{escaped(text)}: the path contains a NUL byte")
        return text

    parse.__name__ = what
    return parse


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    from bench.cli.args import any_seed

    r = sub.add_parser("run", help="run a scene and write samples, codes, record, report and plots",
                       description=RUN_HELP, formatter_class=fmt)
    r.add_argument("scene", type=scene_argument,
                   help="scene file (TOML) or a shipped scene's name, e.g. sphere_drops or my_scene.toml")
    r.add_argument("--out", help="output folder (default: a fresh out/<scene name>[-n])")  # checked by OutFolder
    r.add_argument("--csv", action="store_true", help="also write samples.csv")
    r.add_argument("--force", action="store_true",
                   help="run into a folder that is not empty: an earlier run's files are removed first")
    r.add_argument("--npz", action="store_true",
                   help="export codes.npz (and samples.csv with --csv) even for runs longer than 600 simulated s")
    r.add_argument("--compression", choices=["gzip", "lzf", "none"], default="gzip",
                   help="samples.h5 compression (default gzip: level 1 with shuffle, readable everywhere)")
    r.add_argument("--fidelity", choices=list(PROFILES),
                   help="override the scene's profile (default: the scene's [scene] fidelity; biotac-bench profiles)")
    r.add_argument("--seed", type=any_seed,
                   help="override the scene's seed, 0 to 2^63 - 1 (default: the scene's [scene] seed)")
    r.add_argument("--spi", choices=["software", "rtl"],
                   help="the sensor's SPI side: the software model or the RTL via the C++ harness (default: the "
                        "scene's [host] spi, else software)")
    r.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    r.add_argument("--quiet", action="store_true", help="no progress bar, no report on the terminal")
    r.set_defaults(func=sigterm_like_ctrl_c(_cmd_run))  # (outside the run's own guard: before and after it)

    v = sub.add_parser("validate", help="check scene files without running them",
                       description=VALIDATE_HELP, formatter_class=fmt)
    v.add_argument("scenes", nargs="+", type=_path("a scene file"),
                   help="scene file (TOML) or a shipped scene's name; several are checked one after another")
    v.set_defaults(func=_cmd_validate)

    for name, help_line, description, func in (
            ("scenes", "list the shipped scenes: name, file, what each does", SCENES_HELP, _cmd_scenes),
            ("profiles", "list the fidelity profiles", PROFILES_HELP, _cmd_profiles),
            ("params", "list every sensor parameter with unit, range and source", PARAMS_HELP, _cmd_params)):
        sub.add_parser(name, help=help_line, description=description, formatter_class=fmt).set_defaults(func=func)
