"""A lab's texture groups of its own: a library's ``[[group]]`` tables (name, first, last) let its textures take
numbers past D's 117, validated as every other field (the file, the table, the field, the value, the allowed range),
and usable wherever a library is: ``textures``, scenes, ``texture-sweep``, ``explore``.  The shipped library
declares none and reads as before."""

import csv
import json
import tomllib

import pytest

from bench.cli import main as cli
from bench.errors import TextureError
from bench.experiments import experiment as E
from bench.paths import FIXTURES
from bench.reporting.trials_file import read_trials
from bench.scenes.scene import parse_scene_text
from bench.textures import library as L

pytestmark = pytest.mark.unit

EXAMPLE = FIXTURES / "textures" / "own_groups_example.toml"


def test_the_example_library_declares_two_groups_and_its_textures_are_in_them():
    lib = L.read_library(EXAMPLE)
    assert lib.groups == (("3D prints", 200, 249), ("gripper pads", 1000, 1009))
    assert {n: t.group for n, t in lib.textures.items()} == {200: "3D prints", 201: "3D prints",
                                                             1000: "gripper pads"}
    assert lib.group_names[-2:] == ("3D prints", "gripper pads") and lib.group_names[:-2] == L.GROUP_NAMES
    assert lib.texture("urethane gripper pad").number == 1000 and lib.texture("T201").group == "3D prints"


def test_the_shipped_library_declares_no_group():
    lib = L.read_library()
    assert lib.groups == () and lib.group_names == L.GROUP_NAMES and max(lib.textures) == 902


def test_textures_lists_a_group_of_its_own_and_its_json_reads_back(tmp_path, capsys):
    """``textures --group`` finds the library's own groups; ``--json`` of a library with groups of its own is the
    object {"group": [...], "texture": [...]}, which ``--library`` reads back to the same textures."""
    assert cli.main(["textures", "--library", str(EXAMPLE), "--group", "gripper"]) == 0
    listed = capsys.readouterr().out
    assert "T1000" in listed and "T200" not in listed
    assert cli.main(["textures", "--library", str(EXAMPLE), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["group"] == [{"name": "3D prints", "first": 200, "last": 249},
                                {"name": "gripper pads", "first": 1000, "last": 1009}]
    back = tmp_path / "mine.json"
    back.write_text(json.dumps(printed))
    assert L.load_library(back) == L.load_library(EXAMPLE)


def test_one_texture_of_a_group_of_its_own_printed_as_json_reads_back(tmp_path, capsys):
    """``--show N --json`` of a texture in one of the library's own groups declares that group beside it
    ({"group": [its group], "texture": [it]}), so the file reads back as a library (a bare texture numbered 200 was
    refused: a number in no group, a group not D's); one of D's textures is still printed alone."""
    assert cli.main(["textures", "--library", str(EXAMPLE), "--show", "T200", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["group"] == [{"name": "3D prints", "first": 200, "last": 249}]
    back = tmp_path / "one.json"
    back.write_text(json.dumps(printed))
    assert L.load_library(back) == {200: L.load_library(EXAMPLE)[200]}
    assert cli.main(["textures", "--show", "2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["number"] == 2


GROUPS_AND_ONE = """\
[[group]]
name = "3D prints"
first = 200
last = 249
{more}
[[texture]]
number = {number}
name = "a print"
group = {group}
rms_height_um = 1.0
correlation_length_um = 20.0
hurst = 0.8
mu_static = 0.8
mu_kinetic = 0.6
modulus_MPa = 3500.0
material = "acrylic"
seed = 7
source = "made up for a test"
"""


def _problems(tmp_path, more="", number=200, group='"3D prints"') -> list[str]:
    path = tmp_path / "mine.toml"
    path.write_text(GROUPS_AND_ONE.format(more=more, number=number, group=group))
    with pytest.raises(TextureError) as e:
        L.read_library(path)
    assert e.value.source == str(path) and str(e.value).startswith(f"{path}: ")
    return e.value.problems


@pytest.mark.parametrize("more, expected", [
    ('[[group]]\nname = "Glass"\nfirst = 300\nlast = 310\n',
     'group[1] "Glass": name = "Glass": already the name of one of D\'s groups; group names are unique'),
    ('[[group]]\nname = "3d PRINTS"\nfirst = 300\nlast = 310\n',
     'group[1] "3d PRINTS": name = "3d PRINTS": already the name of group "3D prints" (200-249)'),
    ('[[group]]\nname = "early"\nfirst = 100\nlast = 130\n',
     'group[1] "early": first = 100: allowed 118-899 or 1000-9999, a whole number (1-117 are D\'s groups, 900-999 '
     'the test surfaces)'),
    ('[[group]]\nname = "wide"\nfirst = 850\nlast = 1050\n',
     'group[1] "wide": first = 850, last = 1050: spans the test surfaces\' 900-999'),
    ('[[group]]\nname = "overlap"\nfirst = 240\nlast = 260\n',
     'group[1] "overlap": first = 240, last = 260: overlaps group "3D prints" (200-249)'),
    ('[[group]]\nname = "backwards"\nfirst = 320\nlast = 310\n',
     'group[1] "backwards": first = 320, last = 310: first must not exceed last'),
    ('[[group]]\nname = "huge"\nfirst = 5000\nlast = 10000\n',
     'group[1] "huge": last = 10000: allowed 118-899 or 1000-9999'),
    ('[[group]]\nname = "no end"\nfirst = 300\n', 'group[1] "no end": last is missing (a whole number, 118-899'),
    ('[[group]]\nname = "typo"\nfirst = 300\nlasts = 310\n',
     'group[1] "typo": unknown field "lasts" (did you mean "last"?); known fields: first, last, name'),
])
def test_a_bad_group_is_named_with_its_field_value_and_allowed_range(tmp_path, more, expected):
    problems = _problems(tmp_path, more)
    assert any(p.startswith(expected) for p in problems), problems


SECOND_PRINT = GROUPS_AND_ONE.split("[[texture]]")[1].replace("number = {number}", "number = 201").replace(
    '"a print"', '"another print"').replace("group = {group}", 'group = "3D prints"').replace("seed = 7", "seed = 8")


@pytest.mark.parametrize("broken, expected", [
    ("first = 249\nlast = 200", 'group[0] "3D prints": first = 249, last = 200: first must not exceed last'),
    ("first = 200\nlast = 99999", 'group[0] "3D prints": last = 99999: allowed 118-899 or 1000-9999'),
    ("first = 200\nlast = 249\ncolour = 1", 'group[0] "3D prints": unknown field "colour"'),
])
def test_a_broken_group_is_named_once_not_again_for_each_texture_in_it(tmp_path, broken, expected):
    """A [[group]] table with a problem is named once: its textures (by their group's name, or by a number in its
    first-last) get no problem of their own for a number no sound group holds or a group not declared — they
    had had two each — while a problem of their own (a field out of range) is still named."""
    text = GROUPS_AND_ONE.replace("first = 200\nlast = 249", broken).format(more="", number=200, group='"3D prints"')
    path = tmp_path / "mine.toml"
    path.write_text(text + "[[texture]]" + SECOND_PRINT.replace("hurst = 0.8", "hurst = 7"))
    with pytest.raises(TextureError) as e:
        L.read_library(path)
    (group_problem, hurst) = e.value.problems
    assert group_problem.startswith(expected), e.value.problems
    assert hurst == 'T201 "another print": hurst = 7: allowed range is 0.1 to 1'


def test_a_texture_in_a_nameless_broken_groups_range_is_not_named_again(tmp_path):
    """A broken group without a name is found by its numbers: a texture numbered within them, naming a group no
    table declares, gets no problem beside the group's."""
    path = tmp_path / "mine.toml"
    path.write_text(GROUPS_AND_ONE.replace('name = "3D prints"\n', "").format(more="", number=200,
                                                                             group='"3D prints"'))
    with pytest.raises(TextureError) as e:
        L.read_library(path)
    assert e.value.problems == ["group[0]: name is missing (text)"]


def test_a_texture_outside_every_group_or_in_the_wrong_one_is_named(tmp_path):
    """A number past 117 in no declared group names every group's range and what a [[group]] allows; a texture in
    a declared group's range naming another group names the right one, as D's groups are checked."""
    (problem,) = _problems(tmp_path, number=300)
    assert problem == ('T300 "a print": number = 300: allowed 1 to 117 (D\'s library), 900 to 999 (test surfaces), '
                       '200 to 249 (group "3D prints"); numbers 118-899 or 1000-9999 need a [[group]] of the '
                       "library's own, a whole number")
    (problem,) = _problems(tmp_path, group='"glass"')
    assert problem.startswith('T200 "a print": group = "glass": texture 200 is in group "3D prints" (numbers '
                              '200-249); groups: paper-like, ')
    (problem,) = _problems(tmp_path, number=30)  # D's numbers keep D's groups
    assert problem.startswith('T30 "a print": group = "3D prints": texture 30 is in group "foam" (numbers 29-31)')


def test_a_library_without_groups_refuses_numbers_past_117_as_before(tmp_path):
    text = GROUPS_AND_ONE.format(more="", number=200, group='"3D prints"').split("[[texture]]")[1]
    with pytest.raises(TextureError, match=r"number = 200: allowed 1 to 117 \(D's library\), 900 to 999 \(test "
                                           r"surfaces\); numbers 118-899 or 1000-9999 need a \[\[group\]\]"):
        L.parse_library(tomllib.loads("[[texture]]" + text))


def test_texture_sweep_slides_the_example_librarys_own_textures(tmp_path):
    """README: the example file through texture-sweep, on Dask: a texture of each of its groups slides, and the
    outputs name the library."""
    out = tmp_path / "sweep"
    assert cli.main(["texture-sweep", "--library", str(EXAMPLE), "--textures", "200,urethane gripper pad",
                     "--movements", "7", "--trials", "1", "--workers", "1", "--fidelity", "fast", "--quiet",
                     "--out", str(out)]) == 0
    doc = read_trials(out / "trials.json")
    assert [r["texture"] for r in doc["rows"]] == [200, 1000]
    assert all(r["traction"] > 0 and r["roughness"] is not None for r in doc["rows"])
    assert doc["library"]["path"] == str(EXAMPLE) and doc["library"]["shipped"] is False
    with open(out / "trials.csv", newline="") as f:
        assert [r["library"] for r in csv.DictReader(f)] == [str(EXAMPLE)] * 2


def test_a_scene_and_an_experiment_take_the_example_librarys_own_textures(tmp_path):
    scene = parse_scene_text(f"""\
[scene]
name = "own-group-slide"
duration_s = 2.0
library = "{EXAMPLE}"

[[stimulus]]
kind = "slide"
start_s = 0.05
texture = 1000
force_N = 0.5
velocity_mm_per_s = 50
distance_mm = 20
""", "slide.toml")
    assert scene.library["path"] == str(EXAMPLE)
    experiment = tmp_path / "own.toml"
    experiment.write_text(f"""\
[experiment]
name = "own"
seed = 1
fidelity = "fast"
library = "{EXAMPLE}"
[pilot]
textures = [200, 201, 1000]
trials = 2
movements = [0, 7, 14]
[training]
textures = [200, 201, 1000]
trials = 2
[validation]
pairs = [[200, 201]]
trials = 1
[exploration]
max_moves = 5
pair_simulations = 20
identification_simulations = 20
""")
    assert E.load_experiment(experiment).training_textures == [200, 201, 1000]
    out = tmp_path / "explore"
    assert cli.main(["explore", str(experiment), "--no-cache", "--workers", "1", "--quiet", "--out", str(out)]) == 0
    rows = read_trials(out / "trials.json")["rows"]
    assert {r["texture"] for r in rows} == {200, 201, 1000} and {r["library"] for r in rows} == {str(EXAMPLE)}
    assert "T200 PLA print, 0.2 mm layers / T201 PLA print, 0.1 mm layers" in (out / "report.md").read_text()


def test_similar_pairs_weigh_features_by_the_spread_of_the_librarys_own_textures(tmp_path):
    """The description distance divides each feature by its spread over the library's textures outside the test
    surfaces: for the shipped library D's 117, bit for bit as before; for a library of its own groups alone, its own
    textures (over D's 117 there were none: every spread NaN with a warning, every distance 0, the pair choice
    blind).  A feature they all share (the example's correlation length) or fewer than two have weighs nothing,
    without a warning."""
    import warnings

    import numpy as np

    from bench.experiments import pairs

    shipped = L.load_library()
    d = np.array([pairs.description_features(t) for n, t in sorted(shipped.items()) if n <= 117])
    assert pairs.feature_scales(shipped).tobytes() == np.nanstd(d, axis=0).tobytes()
    own = L.load_library(EXAMPLE)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scales = pairs.feature_scales(own)
        far = pairs.description_distance(own[200], own[1000], scales)
    assert np.isnan(scales[1]) and np.isfinite(np.delete(scales, 1)).all()
    assert far > pairs.description_distance(own[200], own[201], scales) > 0
    one_ridged = {n: t for n, t in own.items() if n != 201}
    assert np.isnan(pairs.feature_scales(one_ridged)[4:]).all()


@pytest.mark.parametrize("pilot, training, expected", [
    ({}, {"textures": [200, 201, 1000]},
     ["pilot.textures (the default, D's pilot textures [10, 30, 43, 46, 47, 84, 87, 100, 38, 58]): no texture "
      "[10, 30, 43, 46, 47, 84, 87, 100, 38, 58] in the library; list the textures to use (`biotac-bench textures "
      f"--library {EXAMPLE}` lists them)"]),
    ({"textures": "all"}, {"textures": [200, 201, 1000]},
     ['pilot.textures = "all": D\'s textures, numbered 1 to 117, and the library holds none; give "library" for every '
      f"texture it holds, or list the textures to use (`biotac-bench textures --library {EXAMPLE}` lists them)"]),
    ({"textures": [200, 201, 1000]}, {},
     ['training.textures = "all" (the default): D\'s textures, numbered 1 to 117, and the library holds none; give '
      f'"library" for every texture it holds, or list the textures to use (`biotac-bench textures --library {EXAMPLE}` '
      "lists them)"]),
])
def test_an_experiment_on_a_library_without_ds_textures_names_what_all_and_the_pilots_default_miss(
        tmp_path, pilot, training, expected):
    """"all" means D's T1..T117 and the pilot's default D's pilot textures: on a library of its own groups alone, a
    problem naming it (the default pilot had been accepted, and failed on the workers over textures not there)."""
    with pytest.raises(E.ExperimentError) as e:
        E.parse_experiment({"experiment": {"name": "own", "seed": 1, "library": str(EXAMPLE)},
                            "pilot": {"trials": 2, "movements": [0, 7, 14], **pilot}, "training": {"trials": 2,
                                                                                                 **training},
                            "validation": {"n_pairs": 1, "pair_choice": "random-within-group"}}, "own.toml")
    assert [p for p in e.value.problems if "textures" in p.split(":")[0]] == expected


def _experiment(pilot, training, library=None) -> E.ExperimentSpec:
    lib = {"library": str(library)} if library else {}
    return E.parse_experiment({"experiment": {"name": "own", "seed": 1, **lib},
                               "pilot": {"trials": 2, "movements": [0, 7, 14], **pilot},
                               "training": {"trials": 2, **training},
                               "validation": {"n_pairs": 1, "pair_choice": "random-within-group"}}, "own.toml")


def test_library_in_an_experiment_takes_every_texture_the_library_holds_and_all_stays_ds_117():
    """"all" is the dissertation's experiment, D's T1..T117 whatever else the library holds; "library" is every
    texture of the library: the example's own groups, and the shipped library's test surfaces beside D's 117."""
    own = _experiment({"textures": "library"}, {"textures": "library"}, EXAMPLE)
    assert own.pilot_textures == own.training_textures == sorted(L.load_library(EXAMPLE)) == [200, 201, 1000]
    shipped = sorted(L.load_library())
    every = _experiment({"textures": "library"}, {"textures": "library"})
    assert every.pilot_textures == every.training_textures == shipped and 901 in shipped
    d117 = _experiment({"textures": "all"}, {"textures": "all"})
    assert d117.pilot_textures == L.dissertation_textures(shipped) == list(range(1, 118))
    assert d117.training_textures is None  # (run as D's 117: experiment.run_experiment)


@pytest.mark.parametrize("word", ["All", " LIBRARY ", "all", "Library"])
def test_all_and_library_are_read_by_one_rule_in_an_experiment_file_and_on_the_command_line(word):
    """"all" and "library" in any case, spaces around ignored, on both routes (the command line took " All ", the
    experiment file refused it as neither a list nor a word): the same textures either way."""
    from bench.cli.args import library_option
    from bench.cli.experiments import _texture_numbers

    for library in (None, EXAMPLE):
        if word.strip().casefold() == "all" and library:  # (no D texture in the example: refused on both routes)
            continue
        spec = _experiment({"textures": word}, {"textures": word}, library)
        cli_textures = _texture_numbers(word, library_option(None if library is None else str(library)))
        assert spec.pilot_textures == cli_textures
        assert spec.training_textures == (None if word.strip().casefold() == "all" else cli_textures)


def test_all_in_any_case_on_a_library_without_ds_textures_is_the_same_problem_as_all():
    """"ALL" is "all": on a library without D's textures, the problem "all" has (it had been read as D's textures and
    left the pilot empty, with no problem said)."""
    with pytest.raises(E.ExperimentError) as e:
        _experiment({"textures": "ALL"}, {"textures": [200, 201, 1000]}, EXAMPLE)
    assert [p for p in e.value.problems if p.startswith("pilot.textures")] == [
        'pilot.textures = "ALL": D\'s textures, numbered 1 to 117, and the library holds none; give "library" for every '
        f"texture it holds, or list the textures to use (`biotac-bench textures --library {EXAMPLE}` lists them)"]


def test_textures_library_on_a_library_of_no_texture_says_so_not_what_all_would():
    """--textures library on a library holding no texture (a file of none is refused as it is read; a LibraryFile
    built in code can hold none): its own message, not "all"'s about D's T1..T117."""
    from bench.cli.experiments import _texture_numbers

    empty = L.LibraryFile(path="lab/empty.toml", sha256="0" * 64, textures={}, shipped=False)
    with pytest.raises(ValueError) as e:
        _texture_numbers(" Library", empty)
    assert str(e.value) == ("--textures library: every texture the library lab/empty.toml holds, and it holds none: "
                            "name a library with textures (--library)")


def test_a_textures_value_neither_list_nor_all_nor_library_names_both_spellings():
    with pytest.raises(E.ExperimentError) as e:
        _experiment({"textures": "every"}, {"textures": [200, 201, 1000]}, EXAMPLE)
    assert 'pilot.textures = "every": a list of texture numbers, "all" (D\'s T1..T117) or "library" (every texture ' \
           "the library holds: D's, the test surfaces, groups of its own)" in e.value.problems


def test_explore_notes_the_own_textures_all_leaves_out(tmp_path, capsys):
    """On a library holding D's 117 and groups of its own, "all" (training's default here) is still D's 117, and
    explore says at once which of the library's textures that leaves out and how to take them; the test surfaces
    (T901, T902) are not counted, nor is a stage that lists its textures."""
    library = tmp_path / "d_and_mine.toml"
    library.write_text((FIXTURES / "textures" / "library.toml").read_text() + "\n" + EXAMPLE.read_text())
    experiment = tmp_path / "mixed.toml"
    experiment.write_text(f'[experiment]\nname = "mixed"\nlibrary = "{library}"\n[pilot]\ntextures = [10, 30, 200]\n')
    assert E.all_leaves_out_note(E.load_experiment(experiment)) == (
        'training.textures: D\'s T1..T117 ("all"), so the library\'s own T200, T201, T1000 are left out ("library" '
        "takes every texture it holds)")
    out = tmp_path / "same"  # (refused once the file is read: --cache is --out)
    assert cli.main(["explore", str(experiment), "--cache", str(out), "--out", str(out)]) == 2
    assert 'note: training.textures: D\'s T1..T117 ("all"), so the library\'s own T200' in capsys.readouterr().err
    experiment.write_text(experiment.read_text() + '[training]\ntextures = "library"\n')
    assert E.all_leaves_out_note(E.load_experiment(experiment)) is None
    assert E.all_leaves_out_note(E.load_experiment(FIXTURES / "experiments" / "fishel2012.toml")) is None


def test_texture_sweep_takes_all_and_library_as_the_experiment_file_does(capsys):
    """--textures library: every texture of the library (the example's own, or the shipped 117 and the test
    surfaces); --textures all: D's T1..T117, refused in one line on a library without them (before any trial)."""
    from bench.cli.args import library_option
    from bench.cli.experiments import _texture_numbers

    assert _texture_numbers("library", library_option(str(EXAMPLE))) == [200, 201, 1000]
    assert _texture_numbers("library", None) == sorted(L.load_library())
    assert _texture_numbers(" All ", None) == list(range(1, 118))
    assert cli.main(["texture-sweep", "--library", str(EXAMPLE), "--textures", "all", "--movements", "7"]) == 2
    err = capsys.readouterr().err
    assert ("--textures all: D's T1..T117, and the library holds none; --textures library takes every texture it "
            f"holds (`biotac-bench textures --library {EXAMPLE}` lists them)") in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("name", ["all", "Library"])
def test_a_texture_may_not_take_a_name_that_names_textures(tmp_path, name):
    (problem,) = _problems_named(tmp_path, name)
    assert problem == (f'T200 "{name}": name = "{name}": names textures without listing them ("all": D\'s T1..T117, '
                       f'"library": every texture of the library), so it would not look this one up; give it another '
                       f"name")


def _problems_named(tmp_path, name: str) -> list[str]:
    path = tmp_path / "named.toml"
    path.write_text(GROUPS_AND_ONE.format(more="", number=200, group='"3D prints"').replace('"a print"', f'"{name}"'))
    with pytest.raises(TextureError) as e:
        L.read_library(path)
    return e.value.problems
