"""Sensor-unit commands: ``biotac-bench units`` prints a unit's parameters (drawn by emulator/units.py)."""

from __future__ import annotations

import argparse

from bench.cli.args import strict_json, unit_serial, whole

UNITS_HELP = """\
A sensor unit is one real device: its parameters drawn deterministically from documented manufacturing spreads
(inflation, bridge offset and span, amplifier offsets, electrode gaps, thermistor tolerance, resonance; the basis
of each spread is in emulator/units.py) by a unit seed, or from its serial number.  The nominal unit is the
model's nominal sensor exactly.

  biotac-bench units --seed 17              # unit 17's parameters and the figures they imply
  biotac-bench units --seed 17 --compare    # beside the nominal unit, with the difference
  biotac-bench units --serial BTU0000000000017 --json
  biotac-bench claims --unit 17             # the published-figure claims for unit 17

In a scene: [sensor] unit = 17 (or "nominal", or a serial "BT..."); other fingers in [[sensors]] tables with
index = 2..5, unit, variant.
"""


def _rows(u) -> dict:
    from emulator.units import DRAWN_FIELDS, derived

    out = {name: getattr(u.params, name) for name in DRAWN_FIELDS}
    out.update(derived(u.params))
    return out


def _units_cmd(a) -> int:
    from emulator.params import PARAMETER_FIELDS
    from emulator.units import unit

    u = unit(a.serial if a.serial is not None else a.seed)
    nominal = unit(None)
    rows, ref = _rows(u), _rows(nominal)
    if a.json:
        doc = {"serial": u.serial, "unit": u.name, "parameters": rows}
        if a.compare:
            doc["nominal"] = ref
        print(strict_json(doc, indent=2))
        return 0
    print(f"unit {u.name}  serial {u.serial}")
    head = f"{'parameter':34s} {'value':>14s}"
    if a.compare:
        head += f" {'nominal':>14s} {'difference':>12s}"
    print(head + "  unit")
    for name, v in rows.items():
        what = PARAMETER_FIELDS[name].metadata["unit"] if name in PARAMETER_FIELDS else _DERIVED_UNITS[name]
        line = f"{name:34s} {_fmt(v)}"
        if a.compare:
            line += f" {_fmt(ref[name])} {_difference(name, v, ref[name]):>12s}"
        print(f"{line}  {what}")
    return 0


#: drawn values that name a draw rather than measure anything: a difference of two of them means nothing
_LABELS = ("electrode_gap_seed",)


def _difference(name: str, v, nominal) -> str:
    """The difference column of ``units --compare``: relative (%) to a non-zero nominal value, else absolute in the
    parameter's unit; for a label (a seed), only whether it differs."""
    if name in _LABELS:
        return "differs" if v != nominal else "same"
    d = v - nominal
    return f"{100 * d / nominal:+.2f} %" if nominal else f"{d:+.4g}"


def _fmt(v) -> str:
    return f"{v:14d}" if isinstance(v, int) else f"{v:14.6g}"


_DERIVED_UNITS = {"resting_pressure_Pa": "Pa", "resting_PDC_V": "V", "resting_PDC_code": "code",
                  "resonance_at_inflation_Hz": "Hz", "PDC_Pa_per_bit": "Pa/bit"}


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    from emulator.units import MAX_UNIT_SEED

    u = sub.add_parser("units", help="a sensor unit's parameters (manufacturing spreads)",
                       description=UNITS_HELP, formatter_class=fmt)
    which = u.add_mutually_exclusive_group()
    which.add_argument("--seed", type=whole(0, MAX_UNIT_SEED), help=f"unit seed (0 to {MAX_UNIT_SEED}); default: "
                                                                    "the nominal unit")
    which.add_argument("--serial", type=unit_serial, help="serial number (\"BT...\"): BTU + 13 digits is that seed, and so "
                                                      "is BTSP + 12 digits (what a BioTac SP of that unit answers); "
                                                      "any other serial seeds the draw from its text")
    u.add_argument("--compare", action="store_true", help="show the nominal unit and the difference beside it")
    u.add_argument("--json", action="store_true", help="print JSON")
    u.set_defaults(func=_units_cmd)
