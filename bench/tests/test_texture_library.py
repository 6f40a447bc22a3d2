"""The texture library: 117 textures in the dissertation's groups, the named ones at their numbers, every field
physical, groups varied, complete validation with clear messages, lookup, the CLI listing and its JSON."""

import itertools
import json
import math
import tomllib

import numpy as np
import pytest

from bench.cli import main as cli
from bench.errors import BenchError, TextureError
from bench.textures import library as L
from bench.textures.library import (LIBRARY_PATH, NUMBER_FIELDS, PERIODIC_FIELDS, load_library, parse_library,
                                    read_library_file, texture, texture_record)
from emulator.texture import SURFACE_LENGTH_M, Texture, surface_track
from emulator.thermal import MATERIALS

pytestmark = pytest.mark.unit

# D Table 6-1's groups, written out here rather than taken from the module under test
DISSERTATION_GROUPS = [
    ("paper-like", 1, 9), ("art supplies and misc.", 10, 23), ("glass", 24, 28), ("foam", 29, 31),
    ("tiles and laminates", 32, 35), ("wood", 36, 38), ("engineering materials", 39, 46), ("rubber", 47, 54),
    ("vinyl", 55, 66), ("leathers and suedes", 67, 72), ("cottons and silks", 73, 83), ("other fabrics", 84, 99),
    ("coarse weaves", 100, 115), ("furs", 116, 117),
]
NAMED_IN_D = {2: "linen paper", 3: "smooth cardstock", 10: "velcro hooks", 30: "foam", 38: "balsa wood",
              43: "graphite", 45: "milled aluminum", 46: "polished aluminum", 47: "rubber", 54: "silicone",
              58: "textured vinyl #2", 84: "satin", 87: "rayon", 100: "burlap"}


@pytest.fixture(scope="module")
def lib():
    return load_library()


# ------------------------------------------------------------------------------------------ contents
def test_117_textures_in_the_dissertations_groups(lib):
    assert [n for n in lib if n <= 117] == list(range(1, 118))
    for group, lo, hi in DISSERTATION_GROUPS:
        assert [n for n, t in lib.items() if t.group == group] == list(range(lo, hi + 1)), group
    extras = {n: t for n, t in lib.items() if n > 117}
    assert all(900 <= n <= 999 and t.group == "test surfaces" for n, t in extras.items())
    assert all(isinstance(t, Texture) for t in lib.values())


def test_named_textures_at_their_numbers(lib):
    for n, name in NAMED_IN_D.items():
        assert lib[n].name == name
    assert L.NAMED == NAMED_IN_D


def test_test_surfaces_for_scenes(lib):
    sandpaper = texture("60-grit sandpaper")
    assert sandpaper.number == 901 and 250e-6 <= sandpaper.correlation_length_m <= 270e-6  # FEPA/CAMI 60 grit
    assert sandpaper.rms_height_m == pytest.approx(0.2 * sandpaper.correlation_length_m, rel=0.01)
    grating = texture("3 mm grating")
    (c,) = grating.periodic
    assert grating.number == 902 and c.track_period_m == pytest.approx(3e-3)
    assert c.harmonics[0::2] == (0.0, 0.0, 0.0)  # square-ish: odd harmonics only
    assert [abs(h) for h in c.harmonics[1::2]] == pytest.approx([1 / 3, 1 / 5, 1 / 7], abs=1e-3)


def test_every_field_within_range_and_every_material_known(lib):
    for t in lib.values():
        rec = texture_record(t)
        for key, spec in NUMBER_FIELDS.items():
            assert math.isfinite(rec[key]) and spec.lo <= rec[key] <= spec.hi, (t.number, key, rec[key])
        assert t.mu_kinetic <= t.mu_static
        assert t.material in MATERIALS, (t.number, t.material)
        assert t.source.strip() and t.description.strip() and t.name == t.name.strip()
        for p in rec["periodic"]:
            for key, spec in PERIODIC_FIELDS.items():
                assert spec.lo <= p[key] <= spec.hi, (t.number, key, p[key])
            assert all(abs(h) <= 1 for h in p["harmonics"])
        assert all(c.track_period_m < SURFACE_LENGTH_M for c in t.periodic)
    assert len({t.seed for t in lib.values()}) == len(lib)
    assert len({t.name.casefold() for t in lib.values()}) == len(lib)


def _parameters(t: Texture) -> tuple:
    return (t.rms_height_m, t.correlation_length_m, t.hurst, t.mu_static, t.mu_kinetic, t.stribeck_velocity_m_per_s,
            t.mu_per_velocity_s_per_m, t.modulus_Pa, t.material, t.periodic)


def test_members_of_a_group_are_similar_but_not_identical(lib):
    for group, lo, hi in DISSERTATION_GROUPS + [("test surfaces", 900, 999)]:
        members = [t for t in lib.values() if t.group == group]
        for a, b in itertools.combinations(members, 2):
            differ = sum(x != y for x, y in zip(_parameters(a), _parameters(b)))
            assert differ >= 2, f"T{a.number} and T{b.number} differ in only {differ} parameter(s)"


def test_weaves_follow_their_thread_counts(lib):
    """Spot checks of the documented derivations: a weave's period is its thread spacing."""
    assert lib[100].periodic[0].track_period_m == pytest.approx(25.4e-3 / 12, rel=0.01)  # burlap 12/inch
    for n, count in ((105, 11), (106, 14), (107, 18)):  # aida cloths
        assert lib[n].periodic[0].track_period_m == pytest.approx(25.4e-3 / count, rel=0.01)
    c = lib[45].periodic[0]  # milled aluminum: cusps f²/8r for f = 0.25 mm, r = 0.8 mm
    assert c.period_m == pytest.approx(0.25e-3) and c.amplitude_m == pytest.approx(4 / math.pi**2 * 9.77e-6, rel=0.01)


def test_named_textures_make_finite_tracks(lib):
    for n in list(NAMED_IN_D) + [901, 902]:
        track = surface_track(lib[n], 50e-6, length_m=0.1)
        assert np.all(np.isfinite(track.heights_m)) and np.std(track.heights_m) > 0


def test_load_is_deterministic():
    a = load_library()
    L._load_cached.cache_clear()
    b = load_library()
    c = parse_library(read_library_file(LIBRARY_PATH), complete=True)
    assert a == b == c and list(a) == sorted(a)
    assert a is not b  # callers get their own dict


# ------------------------------------------------------------------------------------------ validation
GOOD = """\
[[texture]]
number = 5
name = "kraft paper"
group = "paper-like"
rms_height_um = 6.0
correlation_length_um = 200.0
hurst = 0.7
mu_static = 0.6
mu_kinetic = 0.48
modulus_MPa = 40.0
material = "paper"
seed = 5
source = "test"
"""
SECOND = (GOOD.replace("number = 5", "number = 4").replace('"kraft paper"', '"newsprint"')
          .replace("seed = 5", "seed = 4"))
PERIODIC = "[[texture.periodic]]\nperiod_mm = 1.0\namplitude_um = 20.0\n"


def _edit(old: str, new: str, text: str = GOOD) -> str:
    assert old in text
    return text.replace(old, new)


BROKEN = {
    "unknown field": (GOOD + 'colour = "brown"\n', ['T5 "kraft paper"', 'unknown field "colour"', "hurst"]),
    "missing field": (_edit("rms_height_um = 6.0\n", ""), ['T5 "kraft paper"', "rms_height_um is missing",
                                                           "0.0001 to 3000 µm"]),
    "wrong type": (_edit("hurst = 0.7", 'hurst = "high"'), ['T5 "kraft paper"', 'hurst = "high"',
                                                            "must be a number", "0.1 to 1"]),
    "boolean": (_edit("hurst = 0.7", "hurst = true"), ['T5 "kraft paper"', 'hurst = true', "must be a number"]),
    "nan": (_edit("rms_height_um = 6.0", "rms_height_um = nan"), ['T5 "kraft paper"', "rms_height_um = nan",
                                                                   "allowed range is 0.0001 to 3000 µm"]),
    "infinite": (_edit("modulus_MPa = 40.0", "modulus_MPa = inf"), ['T5 "kraft paper"', "modulus_MPa = inf",
                                                                     "allowed range", "MPa"]),
    "metres in a µm field": (_edit("rms_height_um = 6.0", "rms_height_um = 6e-6"),
                             ['T5 "kraft paper"', "rms_height_um = 6e-06", "0.0001 to 3000 µm"]),
    "pascals in a MPa field": (_edit("modulus_MPa = 40.0", "modulus_MPa = 4e7"),
                               ['T5 "kraft paper"', "modulus_MPa = 40000000.0", "0.0005 to 1e+06 MPa"]),
    "kinetic above static": (_edit("mu_kinetic = 0.48", "mu_kinetic = 0.9"),
                             ['T5 "kraft paper"', "mu_kinetic = 0.9", "mu_static = 0.6"]),
    "friction out of range": (_edit("mu_static = 0.6", "mu_static = 12.0"),
                              ['T5 "kraft paper"', "mu_static = 12.0", "0.02 to 3"]),
    "optional field bad": (GOOD + "stribeck_velocity_mm_per_s = -1.0\n",
                           ['T5 "kraft paper"', "stribeck_velocity_mm_per_s = -1.0", "0.01 to 1000 mm/s"]),
    "stribeck velocity past passivity": (GOOD + "stribeck_velocity_mm_per_s = 500.0\n",
                                         ['T5 "kraft paper"', "stribeck_velocity_mm_per_s = 500.0",
                                          "0.01 to 122.4 mm/s", "mu_kinetic = 0.48", "30 s/m"]),
    "unknown material": (_edit('material = "paper"', 'material = "papyrus"'),
                         ['T5 "kraft paper"', 'material = "papyrus"', "unknown", '"paper"', "aluminum"]),
    "wrong group": (_edit('group = "paper-like"', 'group = "glass"'),
                    ['T5 "kraft paper"', 'group = "glass"', '"paper-like"', "1-9"]),
    "number out of range": (_edit("number = 5", "number = 500"),
                            ['T500 "kraft paper"', "number = 500", "1 to 117", "900 to 999"]),
    "number not a number": (_edit("number = 5", 'number = "five"'),
                            ['texture[0] "kraft paper"', 'number = "five"', "whole number"]),
    "number missing": (_edit("number = 5\n", ""), ['texture[0] "kraft paper"', "number is missing"]),
    "name missing": (_edit('name = "kraft paper"\n', ""), ["T5", "name is missing"]),
    "negative seed": (_edit("seed = 5", "seed = -1"), ['T5 "kraft paper"', "seed = -1", "0 to 2**63-1"]),
    "fractional seed": (_edit("seed = 5", "seed = 1.5"), ['T5 "kraft paper"', "seed = 1.5", "whole number"]),
    "empty source": (_edit('source = "test"', 'source = " "'), ['T5 "kraft paper"', 'source = " "', "non-empty"]),
    "control character in a name": (_edit('name = "kraft paper"', 'name = "kraft\\u0007paper"'),
                                     ['name = "kraft\\u0007paper"', "printable text"]),
    "a name like a number": (_edit('name = "kraft paper"', 'name = "T4"'), ['name = "T4"', "looks like a texture number"]),
    "newline in a description": (GOOD + 'description = "two\\nlines"\n', ['description = "two\\nlines"', "printable"]),
    "zero period": (GOOD + _edit("period_mm = 1.0", "period_mm = 0.0", PERIODIC),
                    ['T5 "kraft paper"', "periodic[0].period_mm = 0.0", "0.01 to 50 mm"]),
    "missing amplitude": (GOOD + _edit("amplitude_um = 20.0\n", "", PERIODIC),
                          ['T5 "kraft paper"', "periodic[0].amplitude_um is missing"]),
    "harmonic too big": (GOOD + PERIODIC + "harmonics = [0.5, 2.0]\n",
                         ['T5 "kraft paper"', "periodic[0].harmonics[1] = 2.0", "-1 to 1"]),
    "harmonics not a list": (GOOD + PERIODIC + "harmonics = 0.3\n",
                             ['T5 "kraft paper"', "periodic[0].harmonics = 0.3", "list"]),
    "periodic unknown field": (GOOD + PERIODIC + "phase_deg = 10.0\n",
                               ['T5 "kraft paper"', "periodic[0].phase_deg", "unknown field"]),
    # a typing slip names the field meant (found by a research group's own library: the slip gave only "missing")
    "misspelt field": (_edit("rms_height_um = 6.0", "rms_heigth_um = 6.0"),
                       ['T5 "kraft paper"', 'unknown field "rms_heigth_um" (did you mean "rms_height_um"?)']),
    "misspelt periodic field": (GOOD + _edit("period_mm = 1.0", "period_um = 1.0", PERIODIC),
                                ['periodic[0].period_um: unknown field (did you mean "period_mm"?)']),
    "escape sequence in a periodic field's name": (GOOD + PERIODIC + '"a\\u001b[2J" = 1.0\n',
                                                    ["periodic[0].a\\x1b[2J: unknown field;"]),
    "ridges along the track": (GOOD + PERIODIC + "orientation_deg = 90.0\n",
                               ['T5 "kraft paper"', "periodic[0].orientation_deg = 90.0", "-85 to 85"]),
    "periodic not tables": (GOOD + "periodic = 3\n", ['T5 "kraft paper"', "periodic = 3", "array of tables"]),
    "duplicate number": (GOOD + _edit("number = 4", "number = 5", SECOND),
                         ['T5 "newsprint"', "number = 5", 'already used by T5 "kraft paper"']),
    "duplicate name": (GOOD + _edit('"newsprint"', '"Kraft Paper"', SECOND),
                       ['T4 "Kraft Paper"', 'name = "Kraft Paper"', 'already used by T5 "kraft paper"']),
    "duplicate seed": (GOOD + _edit("seed = 4", "seed = 5", SECOND),
                       ['T4 "newsprint"', "seed = 5", 'already the seed of T5 "kraft paper"']),
    "friction falling with speed": (GOOD + "mu_per_velocity_s_per_m = -1.0\n",
                                    ['T5 "kraft paper"', "mu_per_velocity_s_per_m = -1.0", "0 to 20 s/m"]),
    "unknown top-level key": ("version = 2\n" + GOOD, ["library", 'unknown top-level key "version"']),
    "no textures": ("", ["library", "no [[texture]] tables"]),
}


def test_a_good_snippet_parses():
    lib = parse_library(tomllib.loads(GOOD + PERIODIC + "harmonics = [0.0, -0.333]\n" + SECOND))
    assert list(lib) == [4, 5]
    t = lib[5]
    assert t.rms_height_m == 6e-6 and t.modulus_Pa == 40e6 and t.stribeck_velocity_m_per_s == 0.005
    assert t.periodic[0].period_m == 1e-3 and t.periodic[0].amplitude_m == 20e-6


@pytest.mark.parametrize("case", sorted(BROKEN))
def test_broken_libraries_are_rejected_with_texture_field_and_value(case, tmp_path):
    text, fragments = BROKEN[case]
    f = tmp_path / "broken.toml"
    f.write_text(text, encoding="utf-8")
    with pytest.raises(TextureError) as e:
        load_library(f)
    message = str(e.value)
    assert str(f) in message
    problem = next((p for p in e.value.problems if all(x in p for x in fragments)), None)
    assert problem is not None, f"no problem mentions all of {fragments}: {e.value.problems}"


def test_every_problem_is_listed_at_once(tmp_path):
    text = _edit("hurst = 0.7", "hurst = 7.0", _edit('material = "paper"', 'material = "papyrus"')) + "colour = 1\n"
    with pytest.raises(TextureError) as e:
        parse_library(tomllib.loads(text + SECOND.replace("mu_kinetic = 0.48", "mu_kinetic = 0.7")))
    assert len(e.value.problems) == 4
    assert isinstance(e.value, BenchError) and isinstance(e.value, ValueError)


def test_file_level_errors_name_the_file(tmp_path):
    bad = tmp_path / "latin1.toml"
    bad.write_bytes(GOOD.replace("kraft paper", "papier kraft \xe9").encode("latin-1"))
    with pytest.raises(TextureError, match=r"(?s)latin1\.toml.*not UTF-8 text: byte 0xe9"):
        load_library(bad)
    syntax = tmp_path / "syntax.toml"
    syntax.write_text("[[texture]\nnumber = 5\n", encoding="utf-8")
    with pytest.raises(TextureError, match=r"(?s)syntax\.toml.*TOML syntax error"):
        load_library(syntax)
    with pytest.raises(TextureError, match=r"(?s)missing\.toml.*cannot read the file"):
        load_library(tmp_path / "missing.toml")


def test_the_shipped_library_must_be_complete(tmp_path):
    data = read_library_file(LIBRARY_PATH)
    data["texture"] = [t for t in data["texture"] if t["number"] not in (7, 8, 9, 50)]
    with pytest.raises(TextureError, match=r"T7-T9, T50 are missing"):
        parse_library(data, complete=True)
    assert 7 not in parse_library(data)  # a partial library is fine when completeness is not asked for
    data = read_library_file(LIBRARY_PATH)
    next(t for t in data["texture"] if t["number"] == 10)["name"] = "hook tape"
    with pytest.raises(TextureError, match=r'T10 "hook tape": name = "hook tape": D ch. 6 names texture 10 '
                                           r'"velcro hooks"'):
        parse_library(data, complete=True)


# ------------------------------------------------------------------------------------------ lookup
def test_lookup_by_number_or_name():
    t = texture(10)
    assert t.name == "velcro hooks"
    assert texture("T10") == texture("10") == texture("  Velcro Hooks ") == t


@pytest.mark.parametrize("query, fragments", [
    ("velcro hook", ['no texture named "velcro hook"', 'T10 "velcro hooks"', 'T11 "velcro loops"']),
    ("aluminium", ['no texture named "aluminium"', 'T45 "milled aluminum"', 'T46 "polished aluminum"']),
    ("zzzz", ['no texture named "zzzz"', "biotac-bench textures"]),
    (999, ["no texture number 999", "T1-T117", 'closest: T117 "faux fur", T901 "60-grit sandpaper"']),
    (True, ['texture true: give a number (10, "T10") or a name ("velcro hooks")']),
])
def test_lookup_errors_list_close_matches(query, fragments):
    """Names asked for and names offered are spelled as the library file and every other message spells them
    (``"velcro hooks"``, not Python's ``'velcro hooks'``)."""
    with pytest.raises(TextureError) as e:
        texture(query)
    assert all(x in str(e.value) for x in fragments), str(e.value)


# ------------------------------------------------------------------------------------------ CLI
def test_cli_lists_the_library(capsys):
    assert cli.main(["textures"]) == 0
    out = capsys.readouterr().out
    for n, name in NAMED_IN_D.items():
        assert f"T{n}" in out and name in out
    assert "119 texture(s)" in out and "T902" in out


def test_cli_json_round_trips(capsys):
    assert cli.main(["textures", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["number"] for r in rows] == list(load_library())
    assert parse_library({"texture": rows}, complete=True) == load_library()


def test_cli_group_and_show(capsys):
    assert cli.main(["textures", "--group", "glass", "--json"]) == 0
    assert [r["number"] for r in json.loads(capsys.readouterr().out)] == [24, 25, 26, 27, 28]
    assert cli.main(["textures", "--show", "T100"]) == 0
    out = capsys.readouterr().out
    assert "T100 burlap (coarse weaves)" in out and load_library()[100].source in out
    assert cli.main(["textures", "--show", "burlap", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["source"] == load_library()[100].source


def test_cli_errors_print_cleanly(tmp_path, capsys):
    assert cli.main(["textures", "--group", "plastics"]) == 2
    err = capsys.readouterr().err
    assert err.startswith('error: --group "plastics"') and "coarse weaves" in err and "Traceback" not in err
    assert cli.main(["textures", "--show", "velcro hook"]) == 2
    assert 'T10 "velcro hooks"' in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text(_edit("mu_kinetic = 0.48", "mu_kinetic = 0.9"), encoding="utf-8")
    assert cli.main(["textures", "--library", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.toml" in err and "mu_kinetic = 0.9" in err and "Traceback" not in err


def test_every_texture_has_the_literature_friction_fluctuation(lib):
    """No texture overrides the friction fluctuation's amplitude (an override needs a sourced reason)."""
    from emulator.texture import FRICTION_FLUCTUATION_RMS

    assert {t.friction_fluctuation_rms for t in lib.values()} == {FRICTION_FLUCTUATION_RMS}


def test_a_json_library_with_a_lone_surrogate_in_a_name_is_refused_by_field(tmp_path):
    """Found by a hostile pass: JSON allows "\\ud800", which passed validation and then failed as a 'utf-8' codec
    error naming neither the file nor the texture."""
    record = tomllib.loads(GOOD)["texture"][0] | {"name": "copy\ud800paper"}
    f = tmp_path / "lib.json"
    f.write_text(json.dumps([record]), encoding="utf-8")
    with pytest.raises(TextureError) as e:
        load_library(f)
    assert str(f) in str(e.value) and any('name = "copy\ufffdpaper" (\ufffd stands for the lone surrogate \\ud800' in p
                                          and "printable" in p for p in e.value.problems), e.value.problems


def test_a_lone_surrogates_note_shows_once_per_problem_though_the_name_labels_each(tmp_path):
    """A JSON texture named with a lone surrogate: each of its problems is labelled by the name (U+FFFD in the
    surrogate's place), and the note saying which surrogate it stands for comes once, with the name's own problem
    (it came twice in one line: after the label and after the value)."""
    record = tomllib.loads(GOOD)["texture"][0] | {"name": "copy\ud800paper", "mu_kinetic": 9.0}
    f = tmp_path / "lib.json"
    f.write_text(json.dumps([record]), encoding="utf-8")
    with pytest.raises(TextureError) as e:
        load_library(f)
    notes = [p.count("stands for the lone surrogate \\ud800") for p in e.value.problems]
    assert len(notes) == 2 and sorted(notes) == [0, 1], e.value.problems
    assert all(p.startswith(f'T{record["number"]} "copy\ufffdpaper": ') for p in e.value.problems), e.value.problems


def test_a_json_library_with_a_key_given_twice_is_refused(tmp_path):
    """JSON keeps the last of two equal keys silently (TOML refuses them): the library refuses them too."""
    record = json.dumps(tomllib.loads(GOOD)["texture"][0])
    f = tmp_path / "lib.json"
    f.write_text("[" + record[:-1] + ', "hurst": 0.9}]', encoding="utf-8")
    with pytest.raises(TextureError, match="key 'hurst' given twice"):
        load_library(f)


def test_a_complete_library_needs_every_one_of_the_117(tmp_path):
    """parse_library(complete=True), as the shipped library is read: T117 (the last) missing is named."""
    data = tomllib.loads(LIBRARY_PATH.read_text(encoding="utf-8"))
    data["texture"] = [t for t in data["texture"] if t.get("number") != 117]
    with pytest.raises(TextureError) as e:
        parse_library(data, complete=True)
    assert any("textures T117 are missing" in p for p in e.value.problems), e.value.problems


def test_an_edited_library_file_is_read_again_even_at_the_same_size(tmp_path):
    """The library is cached by path, modification time and size: an edit that keeps the size (one digit changed)
    is still seen — a cache keyed on the size alone returned the old textures."""
    import os

    f = tmp_path / "lib.toml"
    f.write_text(GOOD, encoding="utf-8")
    assert load_library(f)[5].hurst == 0.7
    f.write_text(GOOD.replace("hurst = 0.7", "hurst = 0.8"), encoding="utf-8")
    st = f.stat()
    os.utime(f, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))  # a later modification time, as any edit gets
    assert load_library(f)[5].hurst == 0.8


def test_the_stribeck_velocity_is_held_to_passivity_and_the_default_and_shipped_library_pass(tmp_path):
    """A texture's Stribeck velocity is allowed up to emulator.friction.stribeck_velocity_limit_m_per_s at its own
    µk and the largest σ1 a sensor may have (30 s/m): the default 5 mm/s at the lowest µk (0.02, limit 5.1 mm/s),
    and every shipped texture, within it (the shipped library's largest σ1·v_s/√(2e) / (4·µk·0.82) is 0.094,
    graphite's); the limit itself is allowed, a hair above it is not."""
    from bench.textures.library import SIGMA1_MAX_S_PER_M
    from emulator.friction import stribeck_velocity_limit_m_per_s
    from emulator.texture import FRICTION_FLUCTUATION_RMS

    def limit(mu_k):
        return stribeck_velocity_limit_m_per_s(mu_k, SIGMA1_MAX_S_PER_M, FRICTION_FLUCTUATION_RMS)

    assert limit(1.0) * 1e3 == pytest.approx(255, abs=0.5)  # the module's docstring: 255 × µk mm/s
    worst = max(t.stribeck_velocity_m_per_s / limit(t.mu_kinetic) for t in load_library().values())
    assert worst == pytest.approx(0.094, abs=0.001)
    lowest = _edit("mu_static = 0.6", "mu_static = 0.02", _edit("mu_kinetic = 0.48", "mu_kinetic = 0.02"))
    f = tmp_path / "lib.toml"
    f.write_text(lowest, encoding="utf-8")
    assert load_library(f)[5].stribeck_velocity_m_per_s == 0.005
    at = limit(0.48) * 1e3
    f.write_text(GOOD + f"stribeck_velocity_mm_per_s = {at!r}\n", encoding="utf-8")
    assert load_library(f)[5].stribeck_velocity_m_per_s == pytest.approx(at * 1e-3, rel=1e-12)
    f.write_text(GOOD + f"stribeck_velocity_mm_per_s = {at * (1 + 1e-9)!r}\n", encoding="utf-8")
    with pytest.raises(TextureError, match="stribeck_velocity_mm_per_s"):
        load_library(f)


def test_a_textures_seed_is_bounded_as_a_scenes():
    """The library keeps its own copy of the seed bound (textures sit below scenes in the package layering): it is
    the scene's, so a seed a scene takes a texture takes too."""
    from bench.scenes.limits import MAX_SEED
    from bench.textures import library

    assert library.SEED_MAX == MAX_SEED
