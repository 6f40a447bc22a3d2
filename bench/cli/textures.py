"""Texture library commands: list the 117 textures and the test surfaces (one group, or as JSON), or show one
texture in full with where its numbers come from."""

from __future__ import annotations

import argparse

from bench.cli.args import strict_json

TEXTURES_HELP = """\
Lists the texture library (fixtures/textures/library.toml): the 117 textures of D Table 6-1 in the
dissertation's groups, and the test surfaces (901+) that scenes use.  Columns: number, name, group, RMS height
of the random component, periods of the periodic components along the sliding direction, static/kinetic
friction against the silicone skin, the texture's Young's modulus, thermal material.

The file is validated completely before anything is listed; every problem names the texture, the field, the
value and what is allowed.  --json prints the textures in the file's own fields and units; saved as a .json
file, that list is a library --library reads back (a library with groups of its own, [[group]] tables, prints
as {"group": [...], "texture": [...]}, which reads back too, as does --show N --json of a texture of
such a group, printed with its group).  Edit it (or a copy of the TOML) to try surfaces of your own,
named the same way everywhere: a scene slides over them with [scene] library = "FILE", the texture experiment
with [experiment] library = "FILE" (each relative to the file that names it), texture-sweep --library FILE
(relative to the current folder).  A scene's record.json and report.md, and the trials.json of texture-sweep and
explore, state the library used (path and the SHA-256 of the file, as sha256sum prints it); trials.csv names the
file on every row.

examples:
  biotac-bench textures                      # all of them
  biotac-bench textures --group "coarse weaves"
  biotac-bench textures --show 100           # or --show T100, --show burlap: every field and its source
  biotac-bench textures --json > textures.json
  biotac-bench textures --library textures.json --show 100
  biotac-bench texture-sweep --library textures.json --textures 100 --movements 7 --trials 2
"""


def _si(x: float, unit: str) -> str:
    for factor, prefix in ((1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "µ"), (1e-9, "n")):
        if abs(x) >= factor or factor == 1e-9:
            return f"{x / factor:.3g} {prefix}{unit}"
    return f"{x:.3g} {unit}"


def _periods(t) -> str:
    return ", ".join(f"{p.track_period_m * 1e3:.3g}" for p in t.periodic) or "-"


def _pick_group(text: str, group_names: tuple[str, ...]) -> str:
    """The group ``--group text`` names among ``group_names`` (the library's: D's, the test surfaces', its own): its
    name in any case, or the one group whose name holds ``text``; an empty or unknown one is refused listing every
    group, an ambiguous one listing those it is part of, the value spelled as the rest of the CLI spells values
    (``"glas"``, TOML's spelling; never Python's ``'glas'``)."""
    from bench.tomlfile import spelled

    key = text.strip().casefold()
    exact = [g for g in group_names if g.casefold() == key]
    found = exact or [g for g in group_names if key and key in g.casefold()]
    if len(found) != 1:
        if found:
            raise ValueError(f"--group {spelled(text)}: ambiguous, part of {len(found)} groups: {', '.join(found)}")
        raise ValueError(f"--group {spelled(text)}: {'unknown' if key else 'empty'}; groups: {', '.join(group_names)}")
    return found[0]


def _show(t) -> str:
    from emulator.thermal import MATERIALS

    m = MATERIALS[t.material]
    lines = [f"T{t.number} {t.name} ({t.group})"]
    if t.description:
        lines.append(f"  {t.description}")
    rows = [
        ("random relief", f"RMS {_si(t.rms_height_m, 'm')}, correlation length {_si(t.correlation_length_m, 'm')}, "
                          f"Hurst {t.hurst:g}"),
    ]
    for i, p in enumerate(t.periodic):
        harm = ", ".join(f"{h:g}" for h in p.harmonics) or "none"
        rows.append((f"periodic[{i}]", f"period {_si(p.period_m, 'm')} at {p.orientation_deg:g}° "
                                       f"(along the track {_si(p.track_period_m, 'm')}), amplitude "
                                       f"{_si(p.amplitude_m, 'm')}, harmonics {harm}"))
    rows += [
        ("friction", f"μs {t.mu_static:g}, μk {t.mu_kinetic:g}, Stribeck {_si(t.stribeck_velocity_m_per_s, 'm/s')}, "
                     f"+{t.mu_per_velocity_s_per_m:g} per m/s"),
        ("modulus", _si(t.modulus_Pa, "Pa")),
        ("material", f"{t.material} (k {m.k:g} W/m·K, ρ {m.rho:g} kg/m³, c {m.c:g} J/kg·K; effusivity "
                     f"{m.effusivity:.0f} W·s½/m²·K)"),
        ("seed", str(t.seed)),
        ("source", t.source),
    ]
    lines += [f"  {k:<14} {v}" for k, v in rows]
    return "\n".join(lines)


def _table(textures) -> str:
    head = ("No.", "name", "group", "RMS µm", "period mm", "μs/μk", "modulus", "material")
    rows = [(f"T{t.number}", t.name, t.group, f"{t.rms_height_m * 1e6:.3g}", _periods(t),
             f"{t.mu_static:.2f}/{t.mu_kinetic:.2f}", _si(t.modulus_Pa, "Pa"), t.material) for t in textures]
    widths = [max(len(r[i]) for r in rows + [head]) for i in range(len(head))]
    right = {0, 3, 5, 6}

    def fmt(r):
        return "  ".join(c.rjust(w) if i in right else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths))).rstrip()

    return "\n".join([fmt(head), fmt(tuple("-" * w for w in widths))] + [fmt(r) for r in rows])


def _cmd_textures(a) -> int:
    from bench.cli.args import library_option
    from bench.errors import shell_word
    from bench.textures.library import UnknownTextureError, library_record, texture_record

    if a.show is not None and a.group:
        raise ValueError(f"--show {a.show} prints one texture and --group {a.group} filters the list: give one or the "
                         f"other")
    library = library_option(a.library)  # as texture-sweep --library names it
    lib = library.textures
    if a.show is not None:
        try:
            t = library.texture(a.show)
        except UnknownTextureError as e:
            raise ValueError(e.for_option("--show")) from None
        if not a.json:
            print(_show(t))
            return 0
        own = tuple(g for g in library.groups if g[0] == t.group)  # its group, if the library's own: declared too
        print(strict_json(library_record([t], own) if own else texture_record(t), indent=2, ensure_ascii=False))
        return 0
    items = list(lib.values())
    if a.group is not None:  # (an empty --group "" is refused, not taken as no filter)
        group = _pick_group(a.group, library.group_names)
        items = [t for t in items if t.group == group]
    if a.json:
        print(strict_json(library_record(items, library.groups), indent=2, ensure_ascii=False))
        return 0
    print(_table(items))
    if not items:
        print("\n0 texture(s)")
        return 0
    library_flag = f" --library {shell_word(a.library)}" if a.library is not None else ""
    print(f"\n{len(items)} texture(s); `biotac-bench textures{library_flag} --show {items[0].number}` (or another "
          f"number or name) prints one with its source")
    return 0


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    p = sub.add_parser("textures", help="list the 117-texture library (and test surfaces), or show one texture",
                       description=TEXTURES_HELP, formatter_class=fmt)
    p.add_argument("--group", help="only this group (e.g. \"glass\", \"coarse weaves\")")
    p.add_argument("--show", metavar="N", help="one texture in full: number (10, T10) or name (\"velcro hooks\")")
    p.add_argument("--json", action="store_true", help="JSON in the library file's fields and units")
    p.add_argument("--library", metavar="FILE",
                   help="another library file, relative to the current folder: TOML as the shipped one, or .json "
                        "as --json prints (default: fixtures/textures/library.toml, which must hold all of T1..T117)")
    p.set_defaults(func=_cmd_textures)
