"""Verification commands: the published-figure claims, the noise budget, the benchmark."""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path

from bench.cli.args import (MAX_LOCAL_WORKERS, any_seed, local_workers, number, replaceable_report,
                            say_leftovers, scheduler_address, sigterm_like_ctrl_c, strict_json, unit_choice, whole)
from bench.errors import OutputNotWritten, escaped
from bench.verification.claim_names import CLAIM_GROUP_NAMES
from emulator.channels import DEFAULT_VARIANT, VARIANTS
from emulator.fidelity import PROFILES


class ClaimGroupChoices:
    """``claims --only``'s choices: the claim registry (:data:`bench.verification.claims.CLAIM_GROUPS`, where a new
    group module registers itself), which a given value is checked against.  Until the registry is loaded (it loads
    the whole emulator) they are listed from :data:`CLAIM_GROUP_NAMES`, the groups it registers, so that
    ``claims --help`` stays light."""

    def __contains__(self, name) -> bool:
        from bench.verification.claims import CLAIM_GROUPS

        return name in CLAIM_GROUPS

    def __iter__(self):
        claims = sys.modules.get("bench.verification.claims")
        return iter(CLAIM_GROUP_NAMES if claims is None else list(claims.CLAIM_GROUPS))


def _cmd_noise_budget(a) -> int:
    from emulator.noise_budget import budget, format_budget
    from emulator.spi.model import serial_variant_problem
    from emulator.units import unit

    u = unit(a.unit)
    if problem := serial_variant_problem(u.serial, a.variant):  # as a scene, a port and the plugin refuse it
        raise ValueError(f"--unit {u.serial} --variant {a.variant}: {problem}")
    lines = budget(u.params, a.variant)
    if a.json:
        print(strict_json([vars(x) for x in lines], indent=2))
    else:
        print(f"unit {u.name} (serial {u.serial}), variant {a.variant}")
        print(format_budget(lines, u.params))
    return 0


def _cmd_claims(a) -> int:
    from bench.reporting.outdir import made_folders

    # a --plots folder this command made, left empty by a refusal: removed (made_folders)
    with made_folders() as made, contextlib.ExitStack() as held:
        return _claims(a, made, held)


def _claims(a, made: list, held: contextlib.ExitStack) -> int:
    """``claims``; ``made``: where the folders it makes are noted (:func:`bench.reporting.outdir.made_folders`);
    ``held``: what stays open until the command ends (the plot's lock, :class:`~bench.reporting.outdir.OutFile`:
    the temporary plot a killed claims left is removed and named)."""
    from bench.verification.claims import (CLAIM_GROUPS, Bench, format_spread_table, format_table, run_claims,
                                           run_claims_over_seeds)

    from bench.reporting.outdir import folder_named
    from emulator.units import unit

    groups = a.only or list(CLAIM_GROUPS)
    plots = folder_named(a.plots or "", "--plots")  # the folder as messages name it (--plots DIR, DIR escaped)
    if a.plots:  # checked before anything runs: the plot needs the vibration group, and a folder it can write
        from bench.reporting.outdir import writable_folder

        if "vibration" not in groups:
            raise ValueError(f"{plots}: the frequency-sensitivity plot needs the vibration claims; add "
                             f"--only vibration")
        writable_folder(a.plots, "--plots", made)
        from bench.reporting.plots import SENSITIVITY_PLOT

        try:  # only a plot this command wrote is replaced
            replaceable_report(b"\x89PNG", "a PNG plot")(str(Path(a.plots) / SENSITIVITY_PLOT))
        except argparse.ArgumentTypeError as e:
            raise ValueError(f"{plots}: {escaped(str(e))}") from None
        from bench.reporting.outdir import OutFile

        held.enter_context(say_leftovers(OutFile.open(Path(a.plots) / SENSITIVITY_PLOT, "--plots", "claims run",
                                                      "this plot", where=plots)))
    unit_kw = {} if a.unit is None else {"params": unit(a.unit).params}  # default: the Bench's (nominal) sensor
    progress = None if a.json else (lambda g: print(f"… {g}", file=sys.stderr))
    if a.seeds is not None:
        from bench.campaigns.engine import ClusterSpec

        spec = ClusterSpec.from_env(a.scheduler, a.workers)
        if progress:
            progress(f"{a.seeds} seed(s) × {len(groups)} group(s) on {spec.describe()}")
        rows = run_claims_over_seeds(lambda s: Bench(fidelity=a.fidelity, seed=s, quick=a.quick, cluster=spec,
                                                     **unit_kw),
                                     range(a.seed, a.seed + a.seeds), groups, progress, spec=spec)
        if a.json:
            print(strict_json([r.as_dict() for r in rows], indent=2))
        else:
            print(format_spread_table(rows))
        return 0 if not any(r.failed_seeds for r in rows) else 1
    cluster = None
    if a.workers is not None or a.scheduler is not None:
        from bench.campaigns.engine import ClusterSpec
        from bench.verification.claims.core import STARTS_A_CLUSTER

        if not STARTS_A_CLUSTER.intersection(groups):  # (an error: a --plots folder made is removed)
            raise ValueError(f"--workers and --scheduler go with --seeds or a group that runs a campaign of its own "
                             f"({', '.join(sorted(STARTS_A_CLUSTER))}); one seed of the other groups runs in this "
                             f"process")
        cluster = ClusterSpec.from_env(a.scheduler, a.workers)
    bench = Bench(fidelity=a.fidelity, seed=a.seed, quick=a.quick, cluster=cluster, **unit_kw)
    claims = run_claims(bench, groups, progress=progress)
    if a.json:
        print(strict_json([c.as_dict() for c in claims], indent=2))
    else:
        print(format_table(claims))
    if a.plots:
        from bench.reporting.plots import SENSITIVITY_PLOT, sensitivity_plot

        try:
            out = sensitivity_plot(claims, Path(a.plots))
        except OSError as e:
            raise OutputNotWritten(f"{plots}: {SENSITIVITY_PLOT} could not be written "
                                   f"({e.strerror or e}); the claims above ran and are reported") from None
        print(f"wrote {escaped(str(out))}", file=sys.stderr)
    return 0 if all(c.ok for c in claims) else 1


def _cmd_benchmark(a) -> int:
    from bench.verification.benchmark import main as bench_main

    return bench_main(a)


NOISE_BUDGET_HELP = """\
The PAC noise budget at rest, source by source: bridge Johnson noise, amplifier noise, mains hum and its
harmonics, the ADC's quantization, input and reference noise, the calibrated extra path noise, SPI coupling.
Each row gives µV referred to the input (over the 1040 Hz band), Pa and PAC bits RMS, and they add up (in
quadrature) to the total at the ADC output, beside the published 1.4 ± 0.1 bits; then every other channel's
noise at rest in LSB RMS.  Computed from the model's parameters: nothing is simulated, it takes a second.
A unit's own resting codes set its reference noise channel by channel (--unit); an SP lists E20..E24 too.

  biotac-bench noise-budget
  biotac-bench noise-budget --unit 17 --variant biotac-sp
  biotac-bench noise-budget --json > budget.json
"""

CLAIMS_HELP = """\
Runs each claim (a figure of the dissertation D or a § of docs/SENSOR.md) on the emulator's output and prints the
claim, its kind (prediction, calibrated, derived, consistency), its source, expected, measured, accepted range
and PASS / FAIL / DEVIATES (a known deviation, explained below the table).  Exit status 1 if any claim fails.

Time on the project's 2 cores: about 1 min (55 s measured) once out/cache holds the exploration's stages; a
first run also slides D ch. 6's texture experiment and two ablations from an empty cache, several minutes more
(12 min in a test-suite run on busy cores).  --only picks groups; --seeds N repeats the seeded runs N times.

With --seeds, each group for each seed is an independent task on Dask (a LocalCluster on this machine's cores, or
an existing scheduler with --scheduler / DASK_SCHEDULER_ADDRESS); the rows are the same for any number of workers.
The exploration group runs the texture experiment as a campaign of its own, from this process after the others,
on the same --scheduler / --workers (also without --seeds).  Without --seeds the other claims run in this process.

  biotac-bench claims
  biotac-bench claims --only noise --only impact          # two groups, seconds
  biotac-bench claims --seeds 5 --only vibration          # each row's spread over seeds 2012..2016
  biotac-bench claims --seeds 20 --scheduler tcp://10.0.0.5:8786   # on an existing Dask cluster
  biotac-bench claims --unit 17 --json > unit17.json      # on sensor unit 17 (biotac-bench units)
"""

BENCHMARK_HELP = """\
For every fidelity profile and shipped scene: the noise-free RMS error (bits) of each kind of channel the scene
reads (PAC, PDC, TDC, TAC, electrodes; every sensor) and PAC's spectral error (dB) against the reference profile,
and wall time per simulated second; then throughput (× real time), memory (MB, streaming 600 simulated
s, or an hour with --hour), demand-driven savings, and the cost of each of issue 10's effects (viscoelastic skin,
per-channel ADC noise, hum harmonics, a drawn unit, the BioTac SP's frame: the full frame with and without it).
Takes about 2-3 min on the project's 2 cores (2 min 17 s measured on an idle machine); --textures instead runs the
sliding, rig, Dask and exploration benchmarks; --effects only the per-effect table (about 10 s).

  biotac-bench benchmark
  biotac-bench benchmark --no-rtl --seconds 10      # quicker: no Verilator build, shorter throughput runs
  biotac-bench benchmark --json > benchmark.json
  biotac-bench benchmark --effects                  # each effect's cost, with and without it
"""


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    nb = sub.add_parser("noise-budget", help="the PAC noise budget, source by source",
                        description=NOISE_BUDGET_HELP, formatter_class=fmt)
    nb.add_argument("--json", action="store_true",
                    help="print the budget's rows as JSON (source, channel, rti_uV, pac_bits, note; a non-finite "
                         "number is null)")
    nb.add_argument("--unit", type=unit_choice, default=None,
                    help="the sensor unit: a unit seed, \"nominal\" (default) or a serial number \"BT...\" "
                         "(biotac-bench units)")
    nb.add_argument("--variant", choices=VARIANTS, default=DEFAULT_VARIANT,
                    help=f"the sensor variant (default {DEFAULT_VARIANT}; biotac-sp has E20..E24)")
    nb.set_defaults(func=_cmd_noise_budget)

    c = sub.add_parser("claims", help="measure every published figure on the emulator; exit 1 if any fails",
                       description=CLAIMS_HELP, formatter_class=fmt)
    c.add_argument("--json", action="store_true",
                   help="print the results as JSON (standard JSON: a non-finite number, e.g. the unbounded side of "
                        "a tolerance such as \"high\": inf, is null)")
    c.add_argument("--only", action="append", choices=ClaimGroupChoices(),
                   help="run one group (repeatable; default: every group)")
    c.add_argument("--fidelity", default="default", choices=list(PROFILES),
                   help="fidelity profile of the claims' runs (biotac-bench profiles)")
    c.add_argument("--seed", type=any_seed, default=2012, help="scene seed (with --seeds: the first of N)")
    c.add_argument("--seeds", type=whole(1, 1000), metavar="N",
                   help="run the claims for N seeds (seed, seed+1, ...) and report each claim's min/max and "
                        "how many seeds pass it")
    c.add_argument("--workers", type=local_workers, help=f"LocalCluster worker processes, 1 to {MAX_LOCAL_WORKERS} "
                   "(default: one per core); with "
                   "--seeds for every (seed, group) task, and for the exploration group's experiment")
    c.add_argument("--scheduler", type=scheduler_address,
                   help="address of an existing Dask scheduler, tcp://HOST:PORT (or DASK_SCHEDULER_ADDRESS); used as "
                   "--workers is")
    c.add_argument("--unit", type=unit_choice, default=None,
                   help="run the claims on this sensor unit: a unit seed, \"nominal\" (default) or a serial "
                        "number \"BT...\" (biotac-bench units)")
    c.add_argument("--quick", action="store_true", help="fewer drops and a shorter rest run (a look, not proof)")
    c.add_argument("--plots", metavar="DIR", help="write the frequency-sensitivity plot into DIR")
    c.set_defaults(func=sigterm_like_ctrl_c(_cmd_claims))

    b = sub.add_parser("benchmark", help="error vs the reference profile and cost per simulated second",
                       description=BENCHMARK_HELP, formatter_class=fmt)
    b.add_argument("--json", action="store_true", help="print the results as JSON")
    b.add_argument("--seconds", type=number(0.0, 36000.0, lo_open=True), default=60.0,
                   help="simulated seconds (s) of each throughput run, > 0 and ≤ 36000")
    b.add_argument("--hour", action="store_true",
                   help="stream a full simulated hour for the memory check (default: 600 simulated s)")
    b.add_argument("--no-rtl", action="store_true", help="skip the RTL measurements (no Verilator build)")
    only = b.add_mutually_exclusive_group()  # both had run --textures alone, --effects silently dropped
    only.add_argument("--textures", action="store_true",
                      help="only the sliding, texture-rig, Dask-scaling and exploration benchmarks")
    only.add_argument("--effects", action="store_true",
                      help="only the per-effect cost table: the default full frame with and without each of issue "
                           "10's effects (--seconds per run; about 10 s at 60)")
    b.set_defaults(func=_cmd_benchmark)
