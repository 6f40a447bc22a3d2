"""Fault campaigns through firmware and host driver."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def _cmd_campaign(a) -> int:
    from bench.campaigns import faults as campaign

    faults = list(campaign.FAULTS) if a.faults == "all" else a.faults.split(",")
    scenes = list(campaign.SCENES) if a.scenes == "all" else a.scenes.split(",")
    for name, known in ((faults, campaign.FAULTS), (scenes, campaign.SCENES)):
        bad = [x for x in name if x not in known]
        if bad:
            raise ValueError(f"unknown: {', '.join(bad)}; known: {', '.join(known)}")
    results = campaign.run_campaign(faults, scenes, range(a.seeds),
                                    progress=lambda m: print(f"… {m}", file=sys.stderr))
    campaign.write_junit(results, Path(a.junit))
    print(campaign.summary(results))
    print(f"JUnit XML: {a.junit}")
    return 0 if all(r["passed"] for r in results) else 1


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    cp = sub.add_parser("campaign", help="fault campaign: fault × scene × seed through firmware and driver",
                        description="Runs every chosen fault in every chosen scene for each seed through the "
                                    "bridge firmware, a pty and the host driver; prints a summary and writes "
                                    "JUnit XML. Exit status 1 if any case fails.", formatter_class=fmt)
    cp.add_argument("--faults", default="all", help="comma-separated fault names, or all")
    cp.add_argument("--scenes", default="all", help="comma-separated scene names, or all")
    cp.add_argument("--seeds", type=int, default=1)
    cp.add_argument("--junit", default="out/campaign.xml")
    cp.set_defaults(func=_cmd_campaign)
