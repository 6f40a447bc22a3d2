"""Fault campaigns through firmware and host driver."""

from __future__ import annotations

import argparse
import os
import sys
from datetime import datetime, timezone
from pathlib import Path

from bench.campaigns.case_names import (CASE_FRAMES, CASE_MAX_S, FAULT_EXPECTED, NEEDS_SOFTWARE_SPI,
                                        SCENE_DESCRIPTIONS, SPI_BUSES, check_bus, is_scene_file)
from bench.campaigns.drivers import BENCH_DRIVER, HOST_LIMIT_PER_FRAME_S, HOST_LIMIT_S
from bench.cli.args import (NotedWhenTyped, add_cluster_arguments, firmware_choice, firmware_file,
                            replaceable_report, say_leftovers, sigterm_like_ctrl_c, typed, whole)
from bench.errors import escaped
from bench.tomlfile import spelled


def _names(kind: str):
    """argparse type: ``all`` or a comma-separated list of known fault / scene names (scenes: also scene files, a
    path or a name ending in .toml, :func:`~bench.campaigns.case_names.is_scene_file`; read when the campaign
    starts)."""

    def parse(text: str) -> list[str]:
        known = FAULT_EXPECTED if kind == "faults" else SCENE_DESCRIPTIONS
        if text == "all":
            return list(known)
        names = [n.strip() for n in text.split(",")]
        if not all(names):
            raise argparse.ArgumentTypeError(f"{spelled(text)}: comma-separated names (or all); known: "
                                             f"{', '.join(known)}")
        bad = [n for n in names if n not in known and not (kind == "scenes" and is_scene_file(n))]
        if bad:
            files = " (or a scene file: a path, or a shipped scene's name with .toml, e.g. press_hold.toml)"
            raise argparse.ArgumentTypeError(f"unknown {', '.join(bad)}; known: {', '.join(known)}"
                                             + (files if kind == "scenes" else ""))
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise argparse.ArgumentTypeError(f"{', '.join(twice)} listed twice (each case would run twice)")
        return names

    parse.__name__ = f"{kind} names"
    return parse


def _driver_spec(text: str) -> str:
    """argparse type: ``--driver``'s MODULE:CALLABLE or PATH.py:CALLABLE, spelled right (imported when the campaign
    starts: :func:`bench.campaigns.drivers.load_driver`)."""
    from bench.campaigns.drivers import parse_driver

    try:
        parse_driver(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    return text


_driver_spec.__name__ = "driver"


def _cmd_campaign(a) -> int:
    """The campaign, holding --junit's lock from start to end (:class:`~bench.reporting.outdir.OutFile`): two
    campaigns never write one report, and the temporary files of a campaign killed as it wrote its report are
    removed and named."""
    from bench.reporting.outdir import OutFile

    check_bus(a.faults, a.spi)  # a fault the bus cannot carry: refused by name before anything (the report) is touched
    firmware_choice(a.firmware, "campaign")  # a library beside other files: refused before the report is touched
    with say_leftovers(OutFile.open(a.junit, "--junit", "campaign", "this report",
                                    default=not typed(a, "junit"))) as report:
        return _run_campaign(a, report.path, report.where)


def _run_campaign(a, report: Path, where: str) -> int:
    """The campaign, its JUnit report written to ``report`` (named ``where`` in messages: the flag and the path, or
    the default file)."""
    from bench.campaigns import faults as campaign
    from bench.campaigns.engine import ClusterSpec, signals_held
    from bench.errors import BenchError

    spec = ClusterSpec.from_env(a.scheduler, a.workers)
    firmware = firmware_choice(a.firmware, "campaign")
    seeds = range(a.seeds) if a.seed is None else [a.seed]  # --seed: one case's seed again
    n_cases = len(a.faults) * len(a.scenes) * len(seeds)
    print(f"{n_cases} cases ({len(a.faults)} fault(s) × {len(a.scenes)} scene(s) × "
          f"{len(seeds) if a.seed is None else f'seed {a.seed}'}) over the {a.spi} SPI bus on {spec.describe()}, "
          f"firmware: {campaign.firmware_name(firmware)}, driver: {a.driver}", file=sys.stderr)
    started = datetime.now(timezone.utc)  # the report's timestamp: when the campaign began
    finished: dict = {}  # each case's result by its index, as it finishes: kept when the campaign is stopped
    try:
        from bench.campaigns.scene_files import campaign_scenes

        scenes = campaign_scenes(a.scenes, a.faults, a.spi)  # scene files read and checked before anything runs
        results = campaign.run_campaign(a.faults, scenes, seeds, spec=spec, progress=not a.quiet,
                                        spi=a.spi, firmware=firmware, driver=a.driver, finished=finished)
    except (KeyboardInterrupt, BenchError) as e:  # (SIGTERM too; no cluster, a firmware that does not build) the
        # report says so: an earlier campaign's passing report left at --junit would be published as this one's
        done = [finished[k] for k in sorted(finished)]
        why = (f"the campaign was stopped before its {n_cases} case(s) finished" if isinstance(e, KeyboardInterrupt)
               else f"the campaign could not run: {e}" if not done
               else f"the campaign could not finish its {n_cases} case(s): {e}")
        why += (f"; the {len(done)} that had finished are reported" if done else "; no case's result is reported")
        with signals_held():
            if done:  # what had finished is shown, as a finished campaign's are
                print(campaign.summary(done), flush=True)
            try:
                campaign.write_unfinished_junit(report, why, a.spi, started, done)
            except OSError as oe:
                print(f"error: {where}: the report saying so could not be written ({oe.strerror or oe})"
                      f"{_left_at(report)}", file=sys.stderr)
        raise
    print(campaign.summary(results), flush=True)  # first: the results are shown even if the report cannot be written
    try:
        with signals_held():  # a signal meanwhile: the report is finished first, then the stop
            campaign.write_junit(results, report, started)
    except OSError as e:
        print(f"error: {where}: the JUnit XML could not be written ({e.strerror or e}){_left_at(report)}; the "
              f"summary above holds the results", file=sys.stderr)
        return 1  # the work was done, its report not written (as a run whose record.json could not be)
    print(f"JUnit XML: {escaped(str(report))}")
    return 0 if all(r["passed"] for r in results) else 1


def _left_at(report: Path) -> str:
    """What a campaign whose report could not be written says is at ``report``: an earlier campaign's report, left as
    it was (a report is written whole or not at all, and --junit takes no other file) — not this campaign's, which a
    CI step publishing it must not take it for — or nothing."""
    return "; the file there is an earlier campaign's report, left as it was" if os.path.lexists(report) else ""


def _listed(table: dict) -> str:
    """A table's entries as the help lists faults and scenes: one "  name  text" line each."""
    return "\n".join(f"  {name:<18} {text}" for name, text in table.items())


def _over_the_rtl() -> str:
    """What --help says of the faults over the RTL: every one, or those refused (:data:`NEEDS_SOFTWARE_SPI`)."""
    if not NEEDS_SOFTWARE_SPI:
        return "Every fault runs over either bus."
    return ("Faults the RTL cannot carry yet are refused by name before anything runs (run them with --spi "
            f"software):\n{_listed(NEEDS_SOFTWARE_SPI)}")


#: campaign's --help: its faults and scenes listed from :mod:`bench.campaigns.case_names` (light: the names the
#: campaign's registries are built from)
CAMPAIGN_HELP = f"""\
Runs every chosen fault in every chosen scene for each seed through the bridge firmware, a pty and the host driver
(one case: about 150 frames), and checks that the firmware and driver react as stated; prints a summary and writes
JUnit XML (each case's wall time as its time and what it ran and expected as its system-out; the suite's start, UTC,
and host as its timestamp and hostname).  Each case is an independent task on Dask (a LocalCluster on this machine's
cores, or an existing scheduler with --scheduler / DASK_SCHEDULER_ADDRESS); the verdicts are the same for any number
of workers.  An --junit path where no file can be created is refused before anything runs; the summary is printed
before the report is written; a second campaign naming a report a first one is still running for is refused (a lock
file beside the report, removed at the end).  Exit status 1 if any case fails or the report could not be written
after all (an earlier campaign's report there is then left as it was, and the error says so), 2 for bad arguments
or no scheduler at the address; Ctrl-C stops the campaign (exit 130; SIGTERM: 143) and its --junit report holds one
error saying it was stopped, after the results of the cases that had finished (the summary shows them too); a
campaign that could not run (no scheduler at the address) leaves one error saying why.

faults (--faults), each with what a correct firmware and driver do:
{_listed(FAULT_EXPECTED)}

scenes (--scenes): the campaign's own stimulus sets for sensor 1, by name:
{_listed(SCENE_DESCRIPTIONS)}
or your own scene: an entry with a "/" or ending in .toml is a scene file as `biotac-bench run` takes it
(my_scene.toml, ci/grip.toml), or a shipped scene of `biotac-bench scenes` (taps.toml when no file taps.toml is
here; the bare names above are always the campaign's own sets).  Sensor 1 is the scene's (its stimuli, unit,
variant, parameters, skin, noise and fidelity) in every fault case; the campaign's seed replaces the scene's, a
fault's sensor 2 is sensor 1's twin at rest, and the case streams the whole scene and the frames the fluid-leak
check reads after it (at least {CASE_FRAMES} frames).  Its cases are named by the file: grip.toml[seed=K].  Refused
before anything runs, naming the file and field: several sensors, [faults] of its own, more than {CASE_MAX_S:g} s, a
[host] the bridge firmware is not (a sequence, slot rate or SPI clock of its own), a host.spi other than --spi, a
first stimulus too early for none or fluid_leak (each checks the resting sensor in the case's first frames; the
refusal says how early), and for fluid_leak (its prediction is the nominal sensor's) a unit or parameters of the
scene's own or a stimulus that never ends (power_on, ambient_step, heater_failure).

--driver MODULE:CALLABLE (or PATH.py:CALLABLE) runs every case through your host driver instead of the bench's
({BENCH_DRIVER}): the callable is called with the serial port's path and returns the driver object, which the
case uses as the bench's: start(), request_status(), wait_for(reply_type, timeout_s), frames(max_frames=,
timeout_s=) yielding the bench's DataFrame, parser.stats (crc_errors, dropped_frames), close() — a subclass or a
wrapper of the bench's BridgeDriver is simplest.  A PATH.py is read here (a relative path: from this directory) and
its text sent with every case, so workers elsewhere (--scheduler) run the same file; a MODULE must be importable
where the workers run.  A driver that does not import, is not callable or cannot take the
port is refused before anything runs; one that raises, returns an object lacking part of that, or hangs (its calls
not returned within {HOST_LIMIT_S:g} s + {HOST_LIMIT_PER_FRAME_S:g} s per frame) makes its case an error naming the
driver; frames missing from the sequence numbers it hands over that it did not count as dropped fail the case.

--spi rtl runs the cases over the Verilog RTL in the C++ harness instead of the software model (the same verdicts
are expected; the summary and the report's property "spi" say which bus ran).  {_over_the_rtl()}

  biotac-bench campaign                                   # every fault in every scene, seed 0
  biotac-bench campaign --faults unplug_replug,serial_loss --scenes rest --seeds 3 --junit out/c.xml
  biotac-bench campaign --seeds 10 --scheduler tcp://10.0.0.5:8786        # on an existing Dask cluster
  biotac-bench campaign --faults serial_loss --scenes taps --seed 7         # the case taps[seed=7] again
  biotac-bench campaign --spi rtl --scenes rest --junit out/c-rtl.xml       # every fault over the RTL
  biotac-bench campaign --scenes ci/grip.toml,taps.toml --seeds 3          # your scene file and a shipped one
  biotac-bench campaign --faults cs_glitch --scenes ci/grip.toml --seed 2   # the case grip.toml[seed=2] again
  biotac-bench campaign --driver ci/our_driver.py:open_driver --junit out/c.xml   # your host driver in every case
"""


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    cp = sub.add_parser(
        "campaign", help="fault campaign: fault × scene × seed through firmware and driver", description=CAMPAIGN_HELP,
        formatter_class=fmt)
    cp.add_argument("--faults", type=_names("faults"), default="all",
                    help="comma-separated fault names (listed above), or all")
    cp.add_argument("--scenes", type=_names("scenes"), default="all",
                    help="comma-separated campaign scene names (listed above), or all; or scene files: an entry with "
                         "a / or ending in .toml (my_scene.toml; taps.toml: the shipped scene)")
    seeds = cp.add_mutually_exclusive_group()
    seeds.add_argument("--seeds", type=whole(1, 10_000), default=1,
                       help="how many seeds, 1 to 10000: each case runs with seeds 0, 1, ..., N - 1")
    seeds.add_argument("--seed", type=whole(0, 9_999),
                       help="run the cases with this one seed only, 0 to 9999: a failing case again (its seed is in "
                            "the summary and in the report's case name, rest[seed=7])")
    cp.add_argument("--junit", type=replaceable_report(b"<testsuite", "a JUnit XML report"),
                    default="out/campaign.xml", action=NotedWhenTyped,
                    help="where to write the JUnit XML report (one test case per fault × scene × seed; an earlier "
                         "report there is replaced, as CI tools expect; any other file is refused)")
    cp.add_argument("--spi", choices=list(SPI_BUSES), default="software",
                    help="the sensors' SPI side: the software model (default) or the Verilog RTL in the C++ harness")
    add_cluster_arguments(cp)
    cp.add_argument("--firmware", nargs="+", type=firmware_file, metavar="FILE",
                    help="your firmware instead of the reference one, checked against every case: its C sources or "
                         "one built .so (as bridge --firmware); the report's property \"firmware\" names it")
    cp.add_argument("--driver", type=_driver_spec, default=BENCH_DRIVER, metavar="MODULE:CALLABLE",
                    help="your host driver instead of the bench's (%(default)s): a module Python imports or a .py "
                         "file, and the callable in it that takes the serial port's path and returns the driver "
                         "(see above); the report's property \"driver\" names it")
    cp.add_argument("--quiet", action="store_true", help="no progress bar")
    cp.set_defaults(func=sigterm_like_ctrl_c(_cmd_campaign))
