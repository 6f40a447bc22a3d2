"""Fault campaigns through firmware and host driver."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bench.cli.args import one_line_errors, output_file, whole


def _names(kind: str):
    """argparse type: ``all`` or a comma-separated list of known fault / scene names."""

    def parse(text: str) -> list[str]:
        from bench.campaigns import faults as campaign

        known = campaign.FAULTS if kind == "faults" else campaign.SCENES
        if text == "all":
            return list(known)
        names = [n.strip() for n in text.split(",")]
        if not all(names):
            raise argparse.ArgumentTypeError(f"{text!r}: comma-separated names (or all); known: {', '.join(known)}")
        bad = [n for n in names if n not in known]
        if bad:
            raise argparse.ArgumentTypeError(f"unknown {', '.join(bad)}; known: {', '.join(known)}")
        return names

    parse.__name__ = f"{kind} names"
    return parse


def _cmd_campaign(a) -> int:
    from bench.campaigns import faults as campaign

    results = campaign.run_campaign(a.faults, a.scenes, range(a.seeds),
                                    progress=lambda m: print(f"… {m}", file=sys.stderr))
    campaign.write_junit(results, Path(a.junit))
    print(campaign.summary(results))
    print(f"JUnit XML: {a.junit}")
    return 0 if all(r["passed"] for r in results) else 1


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    cp = one_line_errors(sub.add_parser(
        "campaign", help="fault campaign: fault × scene × seed through firmware and driver",
        description="Runs every chosen fault in every chosen scene for each seed through the bridge firmware, a "
                    "pty and the host driver; prints a summary and writes JUnit XML. Exit status 1 if any case "
                    "fails, 2 for bad arguments.", formatter_class=fmt))
    cp.add_argument("--faults", type=_names("faults"), default="all", help="comma-separated fault names, or all")
    cp.add_argument("--scenes", type=_names("scenes"), default="all", help="comma-separated scene names, or all")
    cp.add_argument("--seeds", type=whole(1, 10_000), default=1, help="how many seeds (0, 1, ...), at least 1")
    cp.add_argument("--junit", type=output_file, default="out/campaign.xml")
    cp.set_defaults(func=_cmd_campaign)
