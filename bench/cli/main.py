"""biotac-bench: run scenes against the emulated BioTac, check the published figures, measure costs.

Each command group lives in its own module with an ``add_commands(sub)`` function; :data:`COMMAND_GROUPS` joins
them into one parser, in the order ``--help`` lists them.
"""

from __future__ import annotations

import argparse
import sys

from bench.cli import campaigns, cheetah, experiments, hosts, rtl, scenes, textures, units, verification

MAIN_HELP = """\
An emulated BioTac fingertip — pressure (PDC, PAC), temperature (TDC, TAC) and 19 impedance electrodes at
sample level — behind its SPI protocol (software model or Verilog RTL), driven by scene files.

typical session:
  biotac-bench scenes                                  # what ships
  biotac-bench run fixtures/scenes/sphere_drops.toml   # run one: codes.npz, record.json, report.md, plots
  biotac-bench claims                                  # check every published figure (PASS/FAIL table)
  biotac-bench noise-budget                            # where the 1.4 bits of PAC noise come from
  biotac-bench benchmark                               # what each fidelity profile costs and how wrong it is

Every subcommand has its own --help.
"""

#: The command groups, in the order ``--help`` lists them.
COMMAND_GROUPS = (scenes, units, textures, experiments, verification, rtl, hosts, cheetah, campaigns)


def build_parser() -> argparse.ArgumentParser:
    fmt = argparse.RawDescriptionHelpFormatter
    p = argparse.ArgumentParser(prog="biotac-bench", description=MAIN_HELP, formatter_class=fmt)
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for group in COMMAND_GROUPS:
        group.add_commands(sub, fmt)
    return p


def main(argv=None) -> int:
    from bench.errors import BenchError
    from emulator.adc import NumericalError

    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (BenchError, ValueError, NumericalError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
