"""The texture library: ``fixtures/textures/library.toml`` read, validated completely, converted to SI.

The file holds one ``[[texture]]`` table per texture (the 117 of D Table 6-1 by number, plus test surfaces
numbered 900-999), with units in the field names (``rms_height_um``, ``modulus_MPa``, ...); :func:`load_library`
returns ``{number: emulator.texture.Texture}`` in SI units, or raises :class:`~bench.errors.TextureError` listing
every problem found, each naming the texture (number and name), the field, the value and what is allowed — like
scene files (:mod:`bench.scenes.scene`).  :func:`texture` looks one texture up by number or name, and raises
:class:`UnknownTextureError` (a ``TextureError``) for one the library does not hold.  A library file may also be
JSON (``.json``): the list of textures ``biotac-bench textures --json`` prints, the same fields and units.

A library of one's own is named one way everywhere (:func:`named_library`): ``[scene] library`` and
``[experiment] library``, relative to the file that names them, and ``--library`` of ``texture-sweep`` and
``textures``, relative to the working folder; every problem names the key, the file, then the texture, field,
value and allowed range.  :func:`read_library` gives a :class:`LibraryFile`: the textures and the SHA-256 of the
file they were parsed from, its bytes as stored (what the outputs state, as ``sha256sum`` prints it); the parse is
cached on the file's text, so an edit is always seen.
In Python, ``read_library("mine.toml").texture(950)`` is the texture a :class:`emulator.sliding.Slide` takes.

Allowed values (physical ranges, wide enough for any real surface, narrow enough to catch a wrong unit):

==============================  ==================  ===========================================================
field                           range               why
==============================  ==================  ===========================================================
number                          1-117, 900-999      the 117 of D Table 6-1; test surfaces (group "test surfaces");
                                                    a library's own groups: 118-899, 1000-9999 (below)
rms_height_um                   0.0001 - 3000 µm    0.1 nm (atomically flat) to 3 mm (coarse pile, open foam)
correlation_length_um           0.1 - 50000 µm      sub-µm grains to 50 mm features (≪ the 1 m stored surface)
hurst                           0.1 - 1.0           roughness exponent of a self-affine surface (0 < H ≤ 1)
mu_static, mu_kinetic           0.02 - 3.0          lubricated contacts to clean soft elastomers; μk ≤ μs
stribeck_velocity_mm_per_s      0.01 - 1000 mm/s    optional, default 5 mm/s; at most 255 × μk mm/s (below)
mu_per_velocity_s_per_m         0 - 20 s/m          optional, default 0; viscous rise of μ with speed
modulus_MPa                     0.0005 - 1e6 MPa    0.5 kPa (fur pile) to 1000 GPa (diamond)
material                        emulator.thermal.MATERIALS
seed                            0 - 2⁶³−1, whole    each texture its own surface: seeds are unique
periodic[].period_mm            0.01 - 50 mm        normal to the ridges
periodic[].amplitude_um         0.001 - 5000 µm     fundamental, peak
periodic[].harmonics            ≤ 16 values, −1..1  relative amplitudes of the 2nd, 3rd, ... harmonics
periodic[].orientation_deg      −85 - 85°           ridge normal vs sliding direction (omit ridges along it)
==============================  ==================  ===========================================================

The Stribeck velocity's cap keeps the friction element passive (:func:`_check_passive_friction`): the bristle
damping fades over it, and with the largest damping a sensor may have (30 s/m) and μk at the deepest dip of its
fluctuation (0.82 μk) it allows 4·√(2e)·0.82·μk/30 s/m, 255 × μk mm/s (5.1 mm/s at μk = 0.02: the default always).

``name`` (unique, case-insensitive), ``group`` (the dissertation's group for the number), ``source`` (where the
numbers come from, non-empty) and ``description`` are text.  The shipped library must hold all of T1..T117, with
the textures the dissertation names at their numbers (:data:`NAMED`).

A library of one's own may declare groups of its own, one ``[[group]]`` table each (:func:`declared_groups`)::

    [[group]]
    name = "3D prints"        # text, unique (case-insensitive) among D's groups, "test surfaces" and the others
    first = 200               # its numbers, first to last: whole numbers within 118-899 or 1000-9999
    last = 249                #   (never D's 1-117 or the test surfaces' 900-999), overlapping no other group

and its textures then take numbers in that range, with ``group = "3D prints"``, validated as every other texture
(a number in no group names every group's range; a group that does not match the number names the right one; a
``[[group]]`` table with a problem is named once, and its textures get no problem of their own for their number or
group until it is fixed).
:attr:`LibraryFile.groups` holds the declared groups; the shipped library declares none.
"""

from __future__ import annotations

import difflib
import functools
import hashlib
import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from bench import tomlfile
from bench.tomlfile import spelled
from bench.errors import TextureError, escaped, shell_word, shortened
from bench.paths import FIXTURES
from emulator.friction import fluctuation_floor, stribeck_velocity_limit_m_per_s
from emulator.params import PARAMETER_FIELDS
from emulator.texture import FRICTION_FLUCTUATION_RMS, PeriodicComponent, Texture
from emulator.thermal import MATERIALS

MAX_LIBRARY_BYTES = 4_000_000  # a texture library file larger than 4 MB is refused before it is parsed

LIBRARY_PATH = FIXTURES / "textures" / "library.toml"

#: The dissertation's groups (D Table 6-1) by number range, in order.
GROUPS: tuple[tuple[str, int, int], ...] = (
    ("paper-like", 1, 9),
    ("art supplies and misc.", 10, 23),
    ("glass", 24, 28),
    ("foam", 29, 31),
    ("tiles and laminates", 32, 35),
    ("wood", 36, 38),
    ("engineering materials", 39, 46),
    ("rubber", 47, 54),
    ("vinyl", 55, 66),
    ("leathers and suedes", 67, 72),
    ("cottons and silks", 73, 83),
    ("other fabrics", 84, 99),
    ("coarse weaves", 100, 115),
    ("furs", 116, 117),
)
#: Surfaces outside the 117 that scenes use (e.g. 901 60-grit sandpaper, 902 3 mm grating).
TEST_GROUP: tuple[str, int, int] = ("test surfaces", 900, 999)
LIBRARY_SIZE = 117
GROUP_NAMES = tuple(g for g, _, _ in GROUPS) + (TEST_GROUP[0],)
#: Numbers a library's own groups (``[[group]]``) may span: past D's 117, below and above the test surfaces.
OWN_GROUP_RANGES: tuple[tuple[int, int], ...] = ((LIBRARY_SIZE + 1, TEST_GROUP[1] - 1), (TEST_GROUP[2] + 1, 9999))
GROUP_FIELDS = ("name", "first", "last")


def dissertation_textures(numbers) -> list[int]:
    """D Table 6-1's texture numbers (1..:data:`LIBRARY_SIZE`) among ``numbers`` (a library, or its numbers), sorted:
    what an experiment's or a sweep's "all" means, whatever else the library holds."""
    return sorted(n for n in numbers if 1 <= n <= LIBRARY_SIZE)


#: How textures are named without listing them (an experiment file's ``pilot.textures`` and ``training.textures``,
#: ``texture-sweep --textures``): ``"all"`` is D's T1..T117 (:func:`dissertation_textures`: the dissertation's
#: experiment, whatever else the library holds), ``"library"`` every texture the library holds (D's, the test
#: surfaces, groups of its own).  No texture may take either as its name.
ALL_TEXTURES, LIBRARY_TEXTURES = "all", "library"


def texture_word(value) -> str | None:
    """:data:`ALL_TEXTURES` or :data:`LIBRARY_TEXTURES` if ``value`` spells one (any case, spaces around ignored),
    else None: the one rule by which ``--textures`` and an experiment file's ``textures`` read them."""
    word = value.strip().casefold() if isinstance(value, str) else None
    return word if word in (ALL_TEXTURES, LIBRARY_TEXTURES) else None


def textures_named(word: str, numbers) -> list[int] | None:
    """The texture numbers ``word`` (:data:`ALL_TEXTURES` or :data:`LIBRARY_TEXTURES`, read by
    :func:`texture_word`) names among ``numbers`` (a library, or its numbers), sorted; None for any other word."""
    word = texture_word(word)
    if word == ALL_TEXTURES:
        return dissertation_textures(numbers)
    if word == LIBRARY_TEXTURES:
        return sorted(numbers)
    return None

#: The textures D ch. 6 names, at their numbers.
NAMED: dict[int, str] = {
    2: "linen paper", 3: "smooth cardstock", 10: "velcro hooks", 30: "foam", 38: "balsa wood", 43: "graphite",
    45: "milled aluminum", 46: "polished aluminum", 47: "rubber", 54: "silicone", 58: "textured vinyl #2",
    84: "satin", 87: "rayon", 100: "burlap",
}


@dataclass(frozen=True)
class _Number:
    """A numeric field: file unit, allowed range, SI = value × 10**exp, the Texture attribute, default (None:
    required)."""

    unit: str
    lo: float
    hi: float
    exp: int
    attr: str
    default: float | None = None

    def to_si(self, v: float) -> float:
        # dividing by an exact power of ten rounds correctly (60 µm -> 6e-05 m, not 5.9999999999999995e-05)
        return float(v) / 10 ** -self.exp if self.exp < 0 else float(v) * 10 ** self.exp

    def from_si(self, x: float) -> float:
        """Back in file units: the shortest decimal that :meth:`to_si` turns into ``x`` again."""
        v = x * 10 ** -self.exp if self.exp < 0 else x / 10 ** self.exp
        for digits in range(12, 18):
            if self.to_si(shorter := float(f"{v:.{digits}g}")) == x:
                return shorter
        return v


NUMBER_FIELDS: dict[str, _Number] = {
    "rms_height_um": _Number("µm", 1e-4, 3000.0, -6, "rms_height_m"),
    "correlation_length_um": _Number("µm", 0.1, 50000.0, -6, "correlation_length_m"),
    "hurst": _Number("", 0.1, 1.0, 0, "hurst"),
    "mu_static": _Number("", 0.02, 3.0, 0, "mu_static"),
    "mu_kinetic": _Number("", 0.02, 3.0, 0, "mu_kinetic"),
    "stribeck_velocity_mm_per_s": _Number("mm/s", 0.01, 1000.0, -3, "stribeck_velocity_m_per_s", 5.0),
    "mu_per_velocity_s_per_m": _Number("s/m", 0.0, 20.0, 0, "mu_per_velocity_s_per_m", 0.0),
    "modulus_MPa": _Number("MPa", 5e-4, 1e6, 6, "modulus_Pa"),
}
PERIODIC_FIELDS: dict[str, _Number] = {
    "period_mm": _Number("mm", 0.01, 50.0, -3, "period_m"),
    "amplitude_um": _Number("µm", 1e-3, 5000.0, -6, "amplitude_m"),
    "orientation_deg": _Number("°", -85.0, 85.0, 0, "orientation_deg", 0.0),
}
MAX_HARMONICS = 16
#: a texture's largest seed: a scene's (bench.scenes.limits.MAX_SEED; not imported: textures sit below scenes)
SEED_MAX = 2**63 - 1
TEXT_FIELDS = ("name", "group", "material", "source", "description")
KNOWN_FIELDS = frozenset({"number", "seed", "periodic", *TEXT_FIELDS, *NUMBER_FIELDS})
MAX_NAME = 60


def group_of(number: int, own: tuple[tuple[str, int, int], ...] = ()) -> str | None:
    """The group a texture number belongs to: D's (1-117), the test surfaces (900-999) or one of ``own`` (a
    library's declared groups, (name, first, last)); None outside them all."""
    for g, lo, hi in GROUPS + (TEST_GROUP,) + tuple(own):
        if lo <= number <= hi:
            return g
    return None


def _own_ranges() -> str:
    return " or ".join(f"{lo}-{hi}" for lo, hi in OWN_GROUP_RANGES)


def declared_groups(c: "_Checker", items) -> tuple[tuple[str, int, int], ...]:
    """A library's own groups (its ``[[group]]`` tables) as (name, first, last), every problem recorded in ``c``
    (naming the table, the field, the value and what is allowed); the groups with problems are left out."""
    if items is None:
        return ()
    if not isinstance(items, list) or not all(isinstance(g, dict) for g in items):
        c.add("library", f"group = {spelled(items)}: must be an array of tables ([[group]] with name, first, last)")
        return ()
    out: list[tuple[str, int, int]] = []
    taken = {g.casefold(): "one of D's groups" if g != TEST_GROUP[0] else "the test surfaces' group"
             for g in GROUP_NAMES}
    for i, g in enumerate(items):
        who = _table_label("group", i, g.get("name"))
        n_before = len(c.problems)
        c.broken_groups.append(g)  # (until it proves sound, below)
        c.unknown_fields(who, g, GROUP_FIELDS)
        name = c.text(who, g, "name")
        if name is not None and (len(name) > MAX_NAME or name != name.strip()):
            c.add(who, f"name = {spelled(name)}: at most {MAX_NAME} characters, no leading or trailing spaces")
        elif name is not None and name.casefold() in taken:
            c.add(who, f"name = {spelled(name)}: already the name of {taken[name.casefold()]}; group names are "
                       "unique")
        bounds = []
        for key in ("first", "last"):
            v = g.get(key)
            if key not in g:
                c.add(who, f"{key} is missing (a whole number, {_own_ranges()})")
            elif isinstance(v, bool) or not isinstance(v, int) or not any(lo <= v <= hi for lo, hi in OWN_GROUP_RANGES):
                c.add(who, f"{key} = {spelled(v)}: allowed {_own_ranges()}, a whole number (1-{LIBRARY_SIZE} are D's "
                           f"groups, {TEST_GROUP[1]}-{TEST_GROUP[2]} the test surfaces)")
            else:
                bounds.append(v)
        if len(c.problems) > n_before:
            continue
        first, last = bounds
        if first > last:
            c.add(who, f"first = {first}, last = {last}: first must not exceed last")
        elif first <= TEST_GROUP[2] and TEST_GROUP[1] <= last:
            c.add(who, f"first = {first}, last = {last}: spans the test surfaces' {TEST_GROUP[1]}-{TEST_GROUP[2]}")
        elif (other := next((o for o in out if o[1] <= last and first <= o[2]), None)) is not None:
            c.add(who, f"first = {first}, last = {last}: overlaps group {spelled(other[0])} ({other[1]}-{other[2]}); "
                       "a number belongs to one group")
        else:
            taken[name.casefold()] = f"group {spelled(name)} ({first}-{last})"
            out.append((name, first, last))
            c.broken_groups.pop()
    return tuple(out)


def _names_a_broken_group(t: dict, broken: list[dict]) -> bool:
    """Whether the ``[[texture]]`` table ``t`` belongs to one of the ``[[group]]`` tables ``broken`` (each with a
    problem of its own already recorded): its ``group`` is that table's name (case-insensitive), or its number lies
    within that table's first-last.  Its number and group are then not judged against the groups that are sound:
    the broken table's problem is the one to fix, said once, not again for every texture in it."""
    group, number = t.get("group"), t.get("number")
    for g in broken:
        name, first, last = g.get("name"), g.get("first"), g.get("last")
        if isinstance(group, str) and isinstance(name, str) and group.casefold() == name.casefold():
            return True
        if all(_whole(v) for v in (number, first, last)) and first <= number <= last:
            return True
    return False


def _whole(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _label(number: int, name) -> str:
    """How problems name a texture: ``T10 "velcro hooks"`` (the name as the file spells it; a lone surrogate in it
    as U+FFFD without :func:`spelled`'s note, which the name's own problem gives: the note once per message)."""
    return f"T{number} {spelled(name, note=False)}" if isinstance(name, str) and name else f"T{number}"


def _table_label(kind: str, i: int, name) -> str:
    """How problems name the ``i``-th ``[[kind]]`` table when no number names it: ``group[1] "3D prints"``."""
    return f"{kind}[{i}]" + (f" {spelled(name, note=False)}" if isinstance(name, str) and name else "")


class _Checker:
    def __init__(self):
        self.problems: list[str] = []
        #: the library's ``[[group]]`` tables with a problem (:func:`declared_groups`), as the file gives them
        self.broken_groups: list[dict] = []

    def add(self, who: str, msg: str):
        self.problems.append(f"{who}: {msg}")

    def number(self, who: str, table: dict, key: str, spec: _Number, prefix: str = ""):
        """The value in SI units, or None (problem recorded)."""
        name = prefix + key
        unit = f" {spec.unit}" if spec.unit else ""
        if key not in table:
            if spec.default is None:
                self.add(who, f"{name} is missing (a number, {spec.lo:g} to {spec.hi:g}{unit})")
                return None
            return spec.to_si(spec.default)
        v = table[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.add(who, f"{name} = {spelled(v)}: must be a number, {spec.lo:g} to {spec.hi:g}{unit}")
            return None
        if not math.isfinite(v) or not spec.lo <= v <= spec.hi:
            self.add(who, f"{name} = {spelled(v)}: allowed range is {spec.lo:g} to {spec.hi:g}{unit}")
            return None
        return spec.to_si(v)

    def unknown_fields(self, who: str, table: dict, known) -> None:
        """A problem for each key of ``table`` not in ``known`` (with a close match suggested, and the known ones)."""
        for k in table:
            if k not in known:
                self.add(who, f"unknown field {spelled(k)}{_did_you_mean(k, known)}; known fields: "
                              f"{', '.join(sorted(known))}")

    def text(self, who: str, table: dict, key: str, required=True):
        if key not in table:
            if required:
                self.add(who, f"{key} is missing (text)")
            return None
        v = table[key]
        if not isinstance(v, str) or (required and not v.strip()):
            self.add(who, f"{key} = {spelled(v)}: must be {'non-empty ' if required else ''}text")
            return None
        if tomlfile.unprintable(v):
            self.add(who, f"{key} = {spelled(v)}: must be printable text (no control characters, NUL or lone "
                          f"surrogates: it is written into reports and tables)")
            return None
        return v


def _did_you_mean(key: str, known) -> str:
    """`` (did you mean "rms_height_um"?)`` for a field name one typing slip from a known one, else ``""``."""
    near = difflib.get_close_matches(key, list(known), n=1, cutoff=0.8)
    return f" (did you mean {spelled(near[0])}?)" if near else ""


def _periodic(c: _Checker, who: str, items) -> tuple[PeriodicComponent, ...] | None:
    if not isinstance(items, list) or not all(isinstance(p, dict) for p in items):
        c.add(who, f"periodic = {spelled(items)}: must be an array of tables ([[texture.periodic]])")
        return None
    out, ok = [], True
    for j, p in enumerate(items):
        where = f"periodic[{j}]."
        for k in p:
            if k not in PERIODIC_FIELDS and k != "harmonics":
                known = [*PERIODIC_FIELDS, "harmonics"]
                c.add(who, f"{where}{escaped(k)}: unknown field{_did_you_mean(k, known)}; known fields: "
                           f"{', '.join(sorted(known))}")
                ok = False
        vals = {spec.attr: c.number(who, p, k, spec, where) for k, spec in PERIODIC_FIELDS.items()}
        harmonics = p.get("harmonics", [])
        if not isinstance(harmonics, list) or len(harmonics) > MAX_HARMONICS:
            c.add(who, f"{where}harmonics = {spelled(harmonics)}: must be a list of at most {MAX_HARMONICS} relative "
                       "amplitudes (2nd, 3rd, ...), each -1 to 1")
            harmonics = None
        else:
            for k, h in enumerate(harmonics):
                if isinstance(h, bool) or not isinstance(h, (int, float)) or not math.isfinite(h) or abs(h) > 1:
                    c.add(who, f"{where}harmonics[{k}] = {spelled(h)}: allowed range is -1 to 1 (relative to the "
                               "fundamental)")
                    harmonics = None
                    break
        if None in vals.values() or harmonics is None:
            ok = False
            continue
        out.append(PeriodicComponent(harmonics=tuple(float(h) for h in harmonics), **vals))
    return tuple(out) if ok else None


def parse_library(data: dict, source: str = "<library>", complete: bool = False) -> dict[int, Texture]:
    """Validate a parsed library (the TOML as a dict); ``complete`` also demands T1..T117 with the named ones.

    Returns ``{number: Texture}`` sorted by number; raises :class:`TextureError` listing every problem."""
    return _parse(data, source, complete)[0]


def _parse(data: dict, source: str, complete: bool) -> tuple[dict[int, Texture], tuple[tuple[str, int, int], ...]]:
    """:func:`parse_library`'s textures, and the library's own groups (name, first, last) besides."""
    c = _Checker()
    if not isinstance(data, dict):
        raise TextureError(source, ["the library must be a table holding [[texture]] tables"])
    for k in data:
        if k not in ("texture", "group"):
            c.add("library", f"unknown top-level key {spelled(k)}: the file holds [[texture]] tables only (and "
                             "[[group]] tables for groups of its own)")
    own = declared_groups(c, data.get("group"))
    items = data.get("texture")
    if items is None or items == []:
        c.add("library", "no [[texture]] tables")
        items = []
    elif not isinstance(items, list):
        c.add("library", f"texture = {spelled(items)}: must be an array of tables ([[texture]])")
        items = []

    seen = _Seen()
    out: dict[int, Texture] = {}
    for i, t in enumerate(items):
        tex = _texture(c, i, t, seen, own)
        if tex is not None:
            out[tex.number] = tex
    if complete:
        missing = [n for n in range(1, LIBRARY_SIZE + 1) if n not in seen.numbers]
        if missing:
            c.add("library", f"textures {_ranges(missing)} are missing: the library holds T1..T{LIBRARY_SIZE}")
        for n, expected in NAMED.items():
            if n in out and out[n].name != expected:
                c.add(_label(n, out[n].name),
                      f"name = {spelled(out[n].name)}: D ch. 6 names texture {n} {spelled(expected)}")
    if c.problems:
        raise TextureError(source, c.problems)
    return dict(sorted(out.items())), own


@dataclass
class _Seen:
    """Numbers, names (case-folded) and seeds met so far, each with the label of the texture that had it first."""

    numbers: dict = field(default_factory=dict)
    names: dict = field(default_factory=dict)
    seeds: dict = field(default_factory=dict)


def _texture(c: _Checker, i: int, t, seen: _Seen, own: tuple[tuple[str, int, int], ...] = ()) -> Texture | None:
    """One ``[[texture]]`` table (``own``: the library's own groups), or None after recording its problems."""
    if not isinstance(t, dict):
        c.add(f"texture[{i}]", f"{spelled(t)}: must be a table ([[texture]])")
        return None
    number, name = t.get("number"), t.get("name")
    if isinstance(number, int) and not isinstance(number, bool):
        who = _label(number, name)
    else:  # no usable number: say where the table is
        who = _table_label("texture", i, name)
    n_before = len(c.problems)
    c.unknown_fields(who, t, KNOWN_FIELDS)
    in_broken_group = _names_a_broken_group(t, c.broken_groups)

    # identity: number, name, group, seed
    if "number" not in t:
        c.add(who, f"number is missing ({_allowed_numbers(own)})")
        number = None
    elif in_broken_group and _whole(number) and group_of(number, own) is None:
        number = None  # (not valid yet, and no problem of its own: the broken group's says what to fix)
    elif isinstance(number, bool) or not isinstance(number, int) or group_of(number, own) is None:
        c.add(who, f"number = {spelled(number)}: allowed {_allowed_numbers(own)}, a whole number")
        number = None
    elif number in seen.numbers:
        c.add(who, f"number = {number}: already used by {seen.numbers[number]}; numbers are unique")
    else:
        seen.numbers[number] = who
    name = c.text(who, t, "name")
    if name is not None:
        if len(name) > MAX_NAME or name != name.strip():
            c.add(who, f"name = {spelled(name)}: at most {MAX_NAME} characters, no leading or trailing spaces")
        elif re.fullmatch(r"[Tt]?\d+", name):
            c.add(who, f"name = {spelled(name)}: looks like a texture number (\"T5\" and \"5\" look textures up by "
                       f"number), so it would hide another texture; give it a name")
        elif textures_named(name, ()) is not None:
            c.add(who, f"name = {spelled(name)}: names textures without listing them ({spelled(ALL_TEXTURES)}: D's "
                       f"T1..T{LIBRARY_SIZE}, {spelled(LIBRARY_TEXTURES)}: every texture of the library), so it would "
                       f"not look this one up; give it another name")
        elif name.casefold() in seen.names:
            c.add(who, f"name = {spelled(name)}: already used by {seen.names[name.casefold()]}; names are unique")
        else:
            seen.names[name.casefold()] = who
    group = c.text(who, t, "group")
    names = GROUP_NAMES + tuple(g for g, _, _ in own)
    if group is not None and number is not None and group != group_of(number, own):
        expected = group_of(number, own)
        lo, hi = next((lo, hi) for g, lo, hi in GROUPS + (TEST_GROUP,) + own if g == expected)
        c.add(who, f"group = {spelled(group)}: texture {number} is in group {spelled(expected)} (numbers {lo}-{hi}); "
                   f"groups: {', '.join(names)}")
    elif group is not None and group not in names and not in_broken_group:
        c.add(who, f"group = {spelled(group)}: must be one of: {', '.join(names)}")
    seed = t.get("seed")
    if "seed" not in t:
        c.add(who, "seed is missing (a whole number, 0 to 2**63-1, unique)")
    elif isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= SEED_MAX:
        c.add(who, f"seed = {spelled(seed)}: must be a whole number, 0 to 2**63-1")
    elif seed in seen.seeds:
        c.add(who, f"seed = {seed}: already the seed of {seen.seeds[seed]}; each texture is its own surface")
    else:
        seen.seeds[seed] = who

    # physics: numbers in SI, friction consistent, a known thermal material, periodic components
    vals = {spec.attr: c.number(who, t, k, spec) for k, spec in NUMBER_FIELDS.items()}
    if None not in vals.values() and vals["mu_kinetic"] > vals["mu_static"]:
        c.add(who, f"mu_kinetic = {spelled(t['mu_kinetic'])}: must not exceed mu_static = {spelled(t['mu_static'])} "
                   "(kinetic friction ≤ static)")
    elif None not in vals.values():
        _check_passive_friction(c, who, t, vals["mu_kinetic"], vals["stribeck_velocity_m_per_s"])
    material = c.text(who, t, "material")
    if material is not None and material not in MATERIALS:
        near = difflib.get_close_matches(material, list(MATERIALS), n=3, cutoff=0.5)
        hint = f" (did you mean {', '.join(map(spelled, near))}?)" if near else ""
        c.add(who, f"material = {spelled(material)}: unknown{hint}; known materials (emulator.thermal.MATERIALS): "
                   f"{', '.join(MATERIALS)}")
    source = c.text(who, t, "source")
    description = c.text(who, t, "description", required=False)
    periodic = _periodic(c, who, t.get("periodic", []))
    if len(c.problems) > n_before or number is None:
        return None
    return Texture(number=number, name=name, group=group, material=material, seed=seed, source=source,
                   description=description or "", periodic=periodic, **vals)


#: the largest bristle damping at rest σ1 (s/m) a sensor may have (SensorParams' range): a library texture must
#: keep the friction element passive under it, whatever sensor slides on it
SIGMA1_MAX_S_PER_M = PARAMETER_FIELDS["bristle_damping_per_N"].metadata["range"][1]


def _allowed_numbers(own: tuple[tuple[str, int, int], ...]) -> str:
    """The texture numbers a library with the own groups ``own`` allows, in words."""
    groups = "".join(f", {lo} to {hi} (group {spelled(g)})" for g, lo, hi in own)
    return (f"1 to {LIBRARY_SIZE} (D's library), {TEST_GROUP[1]} to {TEST_GROUP[2]} (test surfaces){groups}; "
            f"numbers {_own_ranges()} need a [[group]] of the library's own")


def _check_passive_friction(c: _Checker, who: str, t: dict, mu_kinetic: float, stribeck_m_per_s: float) -> None:
    """Refuse a Stribeck velocity (m/s) over which the bristle damping fades too slowly for the texture's kinetic
    friction: the friction element could then give energy back (emulator.friction.stribeck_velocity_limit_m_per_s)."""
    limit = stribeck_velocity_limit_m_per_s(mu_kinetic, SIGMA1_MAX_S_PER_M, FRICTION_FLUCTUATION_RMS)
    if stribeck_m_per_s <= limit * (1.0 + 1e-12):
        return
    spec = NUMBER_FIELDS["stribeck_velocity_mm_per_s"]
    shown = spelled(t["stribeck_velocity_mm_per_s"]) if "stribeck_velocity_mm_per_s" in t else f"{spec.default:g} (default)"
    c.add(who, f"stribeck_velocity_mm_per_s = {shown}: allowed range is {spec.lo:g} to {spec.from_si(limit):.4g} "
               f"mm/s with mu_kinetic = {spelled(t['mu_kinetic'])}: the bristle damping σ1 (up to "
               f"{SIGMA1_MAX_S_PER_M:g} s/m) fades over it, and the friction stays passive only while "
               f"σ1·v_s/√(2e) ≤ 4·µk·{fluctuation_floor(FRICTION_FLUCTUATION_RMS):g} (µk at the deepest dip of "
               f"its {FRICTION_FLUCTUATION_RMS:.0%} fluctuation)")


def _ranges(numbers: list[int]) -> str:
    runs, start = [], numbers[0]
    for a, b in zip(numbers, numbers[1:] + [None]):
        if b != a + 1:
            runs.append(f"T{start}" if start == a else f"T{start}-T{a}")
            start = b
    return ", ".join(runs)


MAX_NESTING = 8  # arrays or tables deep; a library needs 4 (texture, periodic, harmonics)


def _no_duplicate_keys(pairs: list) -> dict:
    """A JSON object, refusing a key given twice (json would keep the last silently; TOML refuses it too)."""
    keys = [k for k, _ in pairs]
    twice = sorted({k for k in keys if keys.count(k) > 1})
    if twice:
        raise ValueError(f"key {twice[0]!r} given twice in one object")
    return dict(pairs)


def read_library_file(path: str | Path) -> dict:
    """The parsed library file, TOML (``{"texture": [...]}``) or JSON (``.json``: a list of textures as
    ``biotac-bench textures --json`` prints, one texture as ``--show N --json`` prints, or the TOML's object); an
    unreadable or oversized file, a device or pipe, non-UTF-8 bytes, syntax errors and absurd nesting raise
    :class:`TextureError` naming the file (:mod:`bench.tomlfile`)."""
    return _parse_text(_library_file(path)[0], str(path))


def _parse_text(text: str, path: str) -> dict:
    """The parsed library of ``text`` (the file ``path``'s: its suffix says TOML or JSON); see
    :func:`read_library_file`."""
    if Path(path).suffix.lower() != ".json":
        return tomlfile.parse(text, str(path), TextureError, MAX_NESTING, "a library needs 4 levels")
    try:
        data = json.loads(text, object_pairs_hook=_no_duplicate_keys)
    except json.JSONDecodeError as e:
        raise TextureError(str(path), [f"JSON syntax error: {e.msg} (line {e.lineno}, column {e.colno})"]) from None
    except RecursionError:
        raise TextureError(str(path), [f"arrays or objects nested too deeply to read (a library needs 4 levels; "
                                       f"at most {MAX_NESTING} are allowed)"]) from None
    except ValueError as e:  # a key given twice, or an integer of more than 4300 digits
        why = "a whole number of more than 4300 digits" if "digits" in str(e) else str(e)
        raise TextureError(str(path), [f"JSON value error: {why}"]) from None
    deep = tomlfile.too_deep(data, MAX_NESTING)
    if deep is not None:
        raise TextureError(str(path), [f"{deep}: nested more than {MAX_NESTING} arrays or objects deep (a library "
                                       "needs 4 levels)"])
    if isinstance(data, dict) and "texture" not in data:
        data = [data]  # one texture, as `biotac-bench textures --show N --json` prints it
    return {"texture": data} if isinstance(data, list) else data


def _library_file(path: str | Path) -> tuple[str, str]:
    """The library file's text and the SHA-256 (hex) of its bytes as stored — what ``sha256sum`` prints for it, a
    byte-order mark included — from one reading."""
    stored, text = tomlfile.read_stored(path, TextureError, MAX_LIBRARY_BYTES,
                                        "no [[texture]] tables: the library is empty")
    return text, hashlib.sha256(stored).hexdigest()


@functools.lru_cache(maxsize=8)
def _load_cached(path: str, text: str, complete: bool) -> tuple[dict[int, Texture], tuple[tuple[str, int, int], ...]]:
    """The textures and own groups of ``text`` (the file ``path``'s): keyed on the content itself, so an edit is
    always seen."""
    return _parse(_parse_text(text, path), path, complete)


@dataclass(frozen=True, eq=False)
class LibraryFile:
    """A texture library file as read: ``path`` (as given; absolute when a scene, an experiment or a command names
    it), ``sha256`` (hex digest of the file's bytes as stored, as ``sha256sum`` prints it), ``textures`` by
    number in SI units, whether it is the shipped ``fixtures/textures/library.toml``, and the groups it declares
    of its own (``[[group]]``: (name, first, last) each; none for the shipped one)."""

    path: str
    sha256: str
    textures: dict
    shipped: bool
    groups: tuple = ()

    @property
    def group_names(self) -> tuple[str, ...]:
        """Every group a texture of this library may be in: D's, the test surfaces', then its own."""
        return GROUP_NAMES + tuple(g for g, _, _ in self.groups)

    def texture(self, number_or_name: int | str) -> Texture:
        """One texture by number or name, as :func:`texture` looks it up (:class:`UnknownTextureError` if absent)."""
        return _lookup(self.textures, self.path, number_or_name)

    def record(self) -> dict:
        """What outputs state about the library: its path, content hash and whether it is the shipped one."""
        return {"path": self.path, "sha256": self.sha256, "shipped": self.shipped}


def read_library(path: str | Path | None = None, complete: bool | None = None) -> LibraryFile:
    """The library file ``path`` (default: the shipped one) read and validated completely: its textures and the
    hash of the file's bytes they came from (one reading: the hash is of what was parsed).  ``complete`` as for
    :func:`load_library`; a file that cannot be read or is invalid raises :class:`TextureError` naming it."""
    p = Path(path) if path is not None else LIBRARY_PATH
    if complete is None:
        complete = path is None
    text, sha256 = _library_file(p)
    textures, groups = _load_cached(str(p), text, bool(complete))
    shipped = path is None or os.path.realpath(p) == os.path.realpath(LIBRARY_PATH)
    return LibraryFile(str(p), sha256, MappingProxyType(textures), shipped, groups)


def check_unchanged(library: LibraryFile, what: str) -> None:
    """:class:`TextureError` if the file ``library`` was read from no longer holds the text read (``what``: what
    ran meanwhile, e.g. "the sweep"): its trials read the file again, each on its worker, so an edit while they ran
    mixes two libraries under the one path and SHA-256 the outputs state, and a stage cache keyed on the first."""
    try:
        now = _library_file(library.path)[1]
    except TextureError as e:
        now = None
        why = "; ".join(e.problems)
    if now != library.sha256:
        why = f"SHA-256 {library.sha256[:16]}… at the start, {now[:16]}… now" if now else why
        raise TextureError(library.path, [f"the library file changed while {what} ran ({why}): its trials may mix "
                                          f"both versions, so nothing is written; run again"])


def load_library(path: str | Path | None = None, complete: bool | None = None) -> dict[int, Texture]:
    """The textures of a library file (default: the shipped ``fixtures/textures/library.toml``), by number, in SI.

    Everything is validated before anything is returned; ``complete`` (default: True for the shipped file)
    also demands T1..T117 with the textures the dissertation names at their numbers."""
    return dict(read_library(path, complete).textures)


#: How every place that names a texture library of one's own says what it wants: a scene's ``[scene] library``,
#: an experiment's ``[experiment] library``, ``texture-sweep --library``.
LIBRARY_VALUE = "the path of a texture library file (TOML, or .json as `biotac-bench textures --json` prints)"


def _shown(value) -> str:
    """``value`` for messages as the file spells it, shortened when long."""
    return spelled(value, 120)


def library_path(value, where: str, naming_file: str | Path | None = None) -> str:
    """The absolute path of the library file that ``value`` names at ``where`` (``"scene.library"``,
    ``"experiment.library"``, ``"--library"``): relative to the folder of ``naming_file`` (the scene or experiment
    file that names it; None or a ``"<scene>"``-like source: the working folder).  :class:`TextureError` (its one
    problem naming ``where`` and the value) if ``value`` is no path."""
    if not isinstance(value, str) or not value.strip() or "\0" in value:
        raise TextureError(str(naming_file or where), [f"{where} = {_shown(value)}: {LIBRARY_VALUE}"])
    base = Path(naming_file).parent if naming_file is not None else Path(".")
    return str((base / value).resolve())


def named_problems(where: str, value, path: str, error: TextureError) -> list[str]:
    """The problems of the library file ``path`` (named by ``value`` at ``where``), each saying where it was named
    and which file it is: ``scene.library = "mine.toml" (/abs/mine.toml): T5 "kraft paper": hurst = 7: allowed
    range is 0.1 to 1``."""
    return [f"{where} = {_shown(value)} ({shortened(escaped(str(path)))}): {p}" for p in error.problems]


def named_library(value, where: str, naming_file: str | Path | None = None) -> LibraryFile:
    """The library file ``value`` names at ``where`` (:func:`library_path`), read and validated: a
    :class:`TextureError` whose problems each name ``where``, the value, the file, then the texture, field, value
    and allowed range (:func:`named_problems`)."""
    path = library_path(value, where, naming_file)
    try:
        return read_library(path)
    except TextureError as e:
        raise TextureError(str(naming_file or where), named_problems(where, value, path, e)) from None


_NUMBER_RE = re.compile(r"^\s*[Tt]?\s*(\d+)\s*$")


class UnknownTextureError(TextureError):
    """A texture asked for by number or name is not in the library (the library itself is fine); ``problem``
    says what was asked, what the library holds and the close matches.  A command line words it with its flag:
    :meth:`for_option`."""

    def __init__(self, source: str, query, problem: str):
        super().__init__(source, [problem])
        self.query, self.problem = query, problem

    def __str__(self) -> str:
        return f"{self.problem} (library: {escaped(str(self.source))})"

    def for_option(self, option: str) -> str:
        """The message for a command-line flag: ``--show: no texture number 999; the library holds ...``."""
        return f"{option}: {self.problem}"


def texture(number_or_name: int | str, path: str | Path | None = None) -> Texture:
    """One texture by number (``10``, ``"T10"``, ``"10"``) or name (``"velcro hooks"``, case-insensitive)."""
    lib = read_library(path)
    return _lookup(lib.textures, lib.path, number_or_name)


def listing_command(path: str | Path | None) -> str:
    """The command that lists the library file ``path`` (None: the shipped one), to suggest in a message: one that
    works as typed (the path one shell word, :func:`bench.errors.shell_word`; absolute paths stay absolute)."""
    if path is None or os.path.realpath(path) == os.path.realpath(LIBRARY_PATH):
        return "biotac-bench textures"
    return f"biotac-bench textures --library {shell_word(os.fspath(path))}"


def _lookup(lib, source: str, q) -> Texture:
    """Texture ``q`` (number or name) of ``lib`` (the textures of the file ``source``), or
    :class:`UnknownTextureError` saying what the library holds and what comes close."""
    if isinstance(q, bool) or not isinstance(q, (int, str)):
        raise TextureError(source, [f'texture {spelled(q)}: give a number (10, "T10") or a name ("velcro hooks")'])
    m = _NUMBER_RE.match(q) if isinstance(q, str) else None
    if isinstance(q, int) or m:
        n = q if isinstance(q, int) else int(m.group(1))
        if n in lib:
            return lib[n]
        nums = sorted(lib)
        near = sorted(nums, key=lambda k: abs(k - n))[:3]
        raise UnknownTextureError(source, q, f"no texture number {n}; the library holds {_ranges(nums)}; closest: "
                                  + ", ".join(_label(k, lib[k].name) for k in sorted(near)))
    by_name = {t.name.casefold(): t for t in lib.values()}
    key = q.strip().casefold()
    if key in by_name:
        return by_name[key]
    names = list(by_name)
    near = difflib.get_close_matches(key, names, n=5, cutoff=0.5)
    near += [nm for nm in names if key and key in nm and nm not in near][:5 - len(near)]
    hint = ("close matches: " + ", ".join(_label(by_name[nm].number, by_name[nm].name) for nm in near)
            if near else f"no close matches (`{listing_command(source)}` lists them all)")
    raise UnknownTextureError(source, q, f"no texture named {spelled(q)}; {hint}")


def library_record(textures, groups: tuple[tuple[str, int, int], ...] = ()) -> list[dict] | dict:
    """``textures`` as ``biotac-bench textures --json`` prints them, a list of :func:`texture_record`; with groups
    of the library's own (``groups``: (name, first, last) each), ``{"group": [...], "texture": [...]}``, so that
    the file reads back (:func:`read_library_file`)."""
    records = [texture_record(t) for t in textures]
    if not groups:
        return records
    return {"group": [dict(zip(GROUP_FIELDS, g)) for g in groups], "texture": records}


def texture_record(t: Texture) -> dict:
    """A texture in the library file's fields and units (what ``biotac-bench textures --json`` prints):
    ``parse_library({"texture": [texture_record(t)]})`` gives ``t`` back."""
    rec: dict = {"number": t.number, "name": t.name, "group": t.group, "description": t.description}
    for key, spec in NUMBER_FIELDS.items():
        rec[key] = spec.from_si(getattr(t, spec.attr))
    rec.update(material=t.material, seed=t.seed, source=t.source)
    rec["periodic"] = [{key: spec.from_si(getattr(p, spec.attr)) for key, spec in PERIODIC_FIELDS.items()}
                       | {"harmonics": list(p.harmonics)} for p in t.periodic]
    return rec
