"""A texture library of one's own, named one way everywhere: a scene's ``[scene] library``, an experiment's
``[experiment] library`` (each relative to the file that names it), ``texture-sweep --library`` (relative to the
current folder) — validated alike, stated in the outputs (path and SHA-256), and part of every cache on the way."""

import hashlib
import json
import os

import pytest

from bench.cli import main as cli
from bench.errors import SceneError, TextureError
from bench.scenes.scene import load_scene, parse_scene_text
from bench.tests.cli_runs import run_cli
from bench.textures import library as L

#: one texture the shipped library does not have (T950), {mu} its friction, {hurst} its Hurst exponent
MY_LIBRARY = """\
[[texture]]
number = 950
name = "my coarse felt"
group = "test surfaces"
rms_height_um = 80.0
correlation_length_um = 300.0
hurst = {hurst}
mu_static = {mu}
mu_kinetic = {mu}
modulus_MPa = 0.5
material = "cotton fabric"
seed = 950
source = "made up for a test"
"""

#: a short slide over T950 at the fast profile (0.1 s approach, 0.3 s hold, 20 mm at 50 mm/s, 0.1 s lift)
SCENE = """\
[scene]
name = "my-slide"
duration_s = 1.0
fidelity = "fast"
library = {library}

[[stimulus]]
kind = "slide"
start_s = 0.05
texture = {texture}
force_N = 0.5
velocity_mm_per_s = 50
distance_mm = 20
approach_s = 0.1
hold_s = 0.3
lift_s = 0.1
"""


def _files(tmp_path, mu=0.55, hurst=0.7, texture="950", library='"../libs/mine.toml"'):
    """``tmp_path/scenes/slide.toml`` naming ``tmp_path/libs/mine.toml`` by a path relative to itself."""
    (tmp_path / "libs").mkdir(exist_ok=True)
    (tmp_path / "scenes").mkdir(exist_ok=True)
    lib = tmp_path / "libs" / "mine.toml"
    lib.write_text(MY_LIBRARY.format(mu=mu, hurst=hurst))
    scene = tmp_path / "scenes" / "slide.toml"
    scene.write_text(SCENE.format(library=library, texture=texture))
    return scene, lib


def _run(scene, out) -> dict:
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet", "--no-plots"]) == 0
    return json.loads((out / "record.json").read_text())


def test_a_scene_slides_over_a_texture_only_its_own_library_has_and_its_record_names_the_library(tmp_path):
    """[scene] library, relative to the scene file (here in another folder than the working one): the slide's T950
    is the library's, and record.json and report.md state the file and the SHA-256 of its content."""
    scene, lib = _files(tmp_path)
    record = _run(scene, tmp_path / "out")
    (trial,) = record["sliding"]["trials"]
    assert (trial["texture"], trial["texture_name"]) == (950, "my coarse felt")
    assert trial["traction"] > 0 and trial["true_normal_N"] == pytest.approx(0.5, rel=0.1)
    assert record["scene"]["library"] == {"path": str(lib.resolve()), "shipped": False,
                                          "sha256": hashlib.sha256(lib.read_bytes()).hexdigest()}
    report = (tmp_path / "out" / "report.md").read_text()
    assert f"texture library: `{lib.resolve()}` (the scene’s own, SHA-256 `{record['scene']['library']['sha256'][:16]}" \
        in report


def test_a_librarys_hash_is_that_of_its_bytes_as_stored_a_byte_order_mark_and_all(tmp_path):
    """Users compare the stated SHA-256 with sha256sum: a library saved with a UTF-8 byte-order mark is hashed with
    it (the mark was left out), in the library read, a scene's record and the check that the file did not change
    while trials ran; taking the mark out is a change of the file the outputs name."""
    scene, lib = _files(tmp_path)
    lib.write_bytes(b"\xef\xbb\xbf" + lib.read_bytes())
    stored = hashlib.sha256(lib.read_bytes()).hexdigest()
    read = L.read_library(lib)
    assert read.sha256 == stored and read.textures[950].name == "my coarse felt"
    assert load_scene(scene).library["sha256"] == stored
    L.check_unchanged(read, "the test")  # the same bytes: no change
    lib.write_bytes(lib.read_bytes()[3:])
    with pytest.raises(TextureError, match="the library file changed while the test ran"):
        L.check_unchanged(read, "the test")


def test_a_scene_without_a_library_of_its_own_states_the_shipped_one():
    sc = load_scene("fixtures/scenes/grating.toml")
    assert sc.library == {"path": str(L.LIBRARY_PATH), "shipped": True,
                          "sha256": hashlib.sha256(L.LIBRARY_PATH.read_bytes()).hexdigest()}
    assert load_scene("fixtures/scenes/taps.toml").library is None  # nothing slides: no library was used


def test_an_edited_library_changes_the_result(tmp_path):
    """The same scene file over the same library path, its texture's friction cut to a third: the trial's friction
    force and traction (the stage current) fall, and the record's hash follows the content."""
    scene, _ = _files(tmp_path, mu=0.9)
    grippy = _run(scene, tmp_path / "a")
    _files(tmp_path, mu=0.3)
    slippery = _run(scene, tmp_path / "b")
    assert slippery["scene"]["library"]["sha256"] != grippy["scene"]["library"]["sha256"]
    assert slippery["scene"]["library"]["path"] == grippy["scene"]["library"]["path"]
    (a,), (b,) = grippy["sliding"]["trials"], slippery["sliding"]["trials"]
    assert b["mean_tangential_N"] < 0.5 * a["mean_tangential_N"]  # µ a third: the friction force well under half
    assert b["traction"] < 0.8 * a["traction"]  # (the stage current has a share that no friction sets)


def test_a_bad_library_file_in_a_scene_is_one_clean_error_naming_the_file_and_field(tmp_path):
    scene, lib = _files(tmp_path, hurst=7)
    done = run_cli("run", scene, "--out", tmp_path / "out", "--quiet")
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    problems = [line for line in done.stderr.splitlines() if line.startswith("  - ")]
    assert problems == [f'  - scene.library = "../libs/mine.toml" ({lib.resolve()}): T950 "my coarse felt": '
                        f"hurst = 7: allowed range is 0.1 to 1"], done.stderr
    assert done.stderr.startswith(f"error: {scene}: 1 problem(s)")
    assert not (tmp_path / "out").exists()  # refused before anything ran


@pytest.mark.parametrize("value, words", [('"nothere.toml"', "cannot read the file: No such file or directory"),
                                          ("3", "the path of a texture library file"),
                                          ('""', "the path of a texture library file")])
def test_a_library_that_is_missing_or_no_path_is_a_scene_problem_naming_the_field(tmp_path, value, words):
    scene, _ = _files(tmp_path, library=value)
    with pytest.raises(SceneError) as e:
        load_scene(scene)
    (problem,) = e.value.problems  # the slide's texture is not looked up in a library that could not be read
    assert problem.startswith(f"scene.library = {value}")  # as the file spells it
    assert words in problem


def test_a_slide_naming_a_texture_the_scenes_library_lacks_is_a_problem_naming_the_stimulus(tmp_path):
    scene, lib = _files(tmp_path, texture='"T30"')  # in the shipped library, not in this one
    with pytest.raises(SceneError) as e:
        load_scene(scene)
    (problem,) = e.value.problems
    assert problem.startswith('stimulus[0].texture = "T30": no texture number 30; the library holds T950')
    assert problem.endswith(f"(the scene's library, scene.library: {lib.resolve()})")


def test_a_scene_and_an_experiment_name_a_bad_library_in_the_same_words(tmp_path):
    """One way of naming a library: the same key, path rule and problem text in a scene and an experiment file."""
    from bench.experiments.experiment import ExperimentError, load_experiment

    scene, lib = _files(tmp_path, hurst=7)
    experiment = tmp_path / "scenes" / "x.toml"  # beside the scene: the same relative path names the same file
    experiment.write_text('[experiment]\nname = "x"\nlibrary = "../libs/mine.toml"\n')
    with pytest.raises(SceneError) as s:
        load_scene(scene)
    with pytest.raises(ExperimentError) as x:
        load_experiment(experiment)
    assert [p.replace("scene.library", "experiment.library") for p in s.value.problems] == x.value.problems


def test_every_finger_of_a_scene_slides_on_the_scenes_library(tmp_path):
    _, lib = _files(tmp_path)
    text = SCENE.format(library='"libs/mine.toml"', texture="950").replace('kind = "slide"', 'kind = "slide"\nsensor = 2')
    sc = parse_scene_text(text, source=str(tmp_path / "s.toml"))
    (slide,) = sc.sensor_spec(2).stimuli
    assert slide.texture.name == "my coarse felt"
    assert sc.for_sensor(2).library == sc.library and sc.library["path"] == str(lib.resolve())


def test_the_library_cache_is_keyed_on_the_content(tmp_path):
    """An edit that keeps the file's size and modification time is still seen (a cache keyed on path, size and
    time returned the old textures)."""
    f = tmp_path / "lib.toml"
    f.write_text(MY_LIBRARY.format(mu=0.55, hurst=0.7))
    st = f.stat()
    assert L.read_library(f).textures[950].hurst == 0.7
    f.write_text(MY_LIBRARY.format(mu=0.55, hurst=0.8))
    os.utime(f, ns=(st.st_atime_ns, st.st_mtime_ns))
    assert f.stat().st_size == st.st_size and f.stat().st_mtime_ns == st.st_mtime_ns
    assert L.read_library(f).textures[950].hurst == 0.8


def test_texture_sweep_slides_the_textures_of_the_library_given(tmp_path, monkeypatch):
    """--library FILE, relative to the current folder: the trials slide its T950, trials.json states the library,
    trials.csv names the file on every row."""
    import csv

    _, lib = _files(tmp_path)
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "sweep"
    assert cli.main(["texture-sweep", "--library", "libs/mine.toml", "--textures", "950", "--movements", "7",
                     "--trials", "1", "--workers", "1", "--fidelity", "fast", "--out", str(out), "--quiet"]) == 0
    record = json.loads((out / "trials.json").read_text())
    assert record["library"] == {"path": str(lib.resolve()), "shipped": False,
                                 "sha256": hashlib.sha256(lib.read_bytes()).hexdigest()}
    (row,) = record["rows"]
    assert row["texture"] == 950 and row["library"] == str(lib.resolve()) and row["traction"] > 0
    with open(out / "trials.csv", newline="") as f:
        assert [r["library"] for r in csv.DictReader(f)] == [str(lib.resolve())]


def test_texture_sweep_names_a_bad_library_or_a_texture_it_lacks_in_one_line(tmp_path, monkeypatch, capsys):
    _, lib = _files(tmp_path, hurst=7)
    monkeypatch.chdir(tmp_path)
    assert cli.main(["texture-sweep", "--library", "libs/mine.toml", "--textures", "950"]) == 2
    err = capsys.readouterr().err
    assert err == (f'error: --library = "libs/mine.toml" ({lib.resolve()}): T950 "my coarse felt": hurst = 7: '
                   f"allowed range is 0.1 to 1\n")
    _files(tmp_path)
    assert cli.main(["texture-sweep", "--library", "libs/mine.toml", "--textures", "30"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --textures: no texture number 30; the library holds T950") and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_texture_sweep_and_textures_list_several_library_problems_one_a_line(tmp_path, monkeypatch, capsys):
    """Several problems (a research group's library with a slip in two fields) are listed one a line under the
    count, as explore lists an experiment file's library problems, not run together on one line with '; '."""
    _, lib = _files(tmp_path, hurst=7, mu=9)
    monkeypatch.chdir(tmp_path)
    where = f'--library = "libs/mine.toml" ({lib.resolve()}): T950 "my coarse felt": '
    for argv in (["texture-sweep", "--library", "libs/mine.toml", "--textures", "950"],
                 ["textures", "--library", "libs/mine.toml"]):
        assert cli.main(argv) == 2
        lines = capsys.readouterr().err.splitlines()
        assert lines[0] == "error: --library: 3 problem(s):" and len(lines) == 4, lines
        assert lines[1:] == [f"  - {where}hurst = 7: allowed range is 0.1 to 1",
                             f"  - {where}mu_static = 9: allowed range is 0.02 to 3",
                             f"  - {where}mu_kinetic = 9: allowed range is 0.02 to 3"]
    assert not (tmp_path / "out").exists()


def test_a_library_named_by_a_file_resolves_against_that_files_folder(tmp_path, monkeypatch):
    """The path rule itself: relative to the naming file's folder, whatever the working folder; a pseudo-source
    ("<scene>", a scene built in code) and a command line resolve against the working folder."""
    monkeypatch.chdir(tmp_path)
    where = tmp_path / "a" / "b"
    assert L.library_path("../lib.toml", "scene.library", where / "s.toml") == str(tmp_path / "a" / "lib.toml")
    assert L.library_path("lib.toml", "scene.library", "<scene>") == str(tmp_path / "lib.toml")
    assert L.library_path("lib.toml", "--library") == str(tmp_path / "lib.toml")
    with pytest.raises(TextureError, match=r'--library = "a\\u0000b": the path of a texture library file'):
        L.library_path("a\0b", "--library")


def test_a_hostile_library_value_is_named_in_a_message_of_bounded_length(tmp_path):
    """A 100 000-character path (its file name too long to open) is named shortened, value and resolved path
    both: the problem stays a readable line, not 200 kB."""
    scene, _ = _files(tmp_path, library='"' + "x" * 100_000 + '"')
    with pytest.raises(SceneError) as e:
        load_scene(scene)
    (problem,) = e.value.problems
    assert problem.startswith('scene.library = "xxx') and "(100002 characters)" in problem
    assert "cannot read the file" in problem and len(problem) < 600


def test_the_pytest_plugin_takes_a_scene_with_a_library_of_its_own(tmp_path):
    """biotac_sensor(scene=...) / biotac_bridge(scene=...) load a scene file as `run` does: its slides come from
    the scene's own library, found relative to the scene file."""
    from bench.pytest_plugin.fixtures import load_scene_like

    scene, lib = _files(tmp_path)
    sc = load_scene_like(str(scene))
    assert [s.texture.name for s in sc.stimuli] == ["my coarse felt"] and sc.library["path"] == str(lib.resolve())


def test_a_scene_takes_the_json_list_that_textures_json_prints(tmp_path, capsys):
    """`biotac-bench textures --library mine.toml --json > mine.json`: the scene naming mine.json slides over the
    same texture as the one naming mine.toml."""
    scene, lib = _files(tmp_path)
    assert cli.main(["textures", "--library", str(lib), "--json"]) == 0
    (tmp_path / "libs" / "mine.json").write_text(capsys.readouterr().out)
    from_json = parse_scene_text(SCENE.format(library='"../libs/mine.json"', texture="950"), source=str(scene))
    assert from_json.stimuli[0].texture == load_scene(scene).stimuli[0].texture
    assert from_json.library["path"].endswith("mine.json") and not from_json.library["shipped"]


def _edit_meanwhile(lib, rows_of):
    """A stand-in for the trials' ``sweep`` that edits the library file while the trials run (each trial reads it
    on its worker), then returns ``rows_of(tasks)``."""
    def sweep(tasks, **kw):
        lib.write_text(MY_LIBRARY.format(mu=0.9, hurst=0.7))
        return rows_of(tasks)
    return sweep


def test_a_library_edited_while_the_trials_run_is_refused_not_stated_or_cached(tmp_path, monkeypatch, capsys):
    """The trials read the library file on their workers, the outputs state its SHA-256 as read at the start, and a
    stage cache is keyed on it: an edit while they ran had mixed two libraries under the first one's name and hash
    (and cached the mix as the first). texture-sweep then writes nothing and says so in one line; an experiment
    stage caches nothing and says so; an unedited library runs as before."""
    from dataclasses import asdict

    from bench.experiments import experiment as E
    from bench.experiments import trials

    _, lib = _files(tmp_path)
    monkeypatch.chdir(tmp_path)

    def rows_of(tasks):
        return [dict(asdict(t), traction=0.1, roughness=1.0, fineness=2.0, rejected_samples=0, true_normal_N=0.5,
                     start_position_m=0.01, simulated_s=7.0, wall_s=1.0) for t in tasks]

    monkeypatch.setattr(trials, "sweep", _edit_meanwhile(lib, rows_of))
    out = tmp_path / "sweep"
    assert cli.main(["texture-sweep", "--library", "libs/mine.toml", "--textures", "950", "--movements", "7",
                     "--trials", "1", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    said = err.splitlines()[-1]  # (after the trials' count)
    assert said.startswith(f"error: {lib.resolve()}: the library file changed while the sweep ran (SHA-256 ") \
        and said.endswith("nothing is written; run again") and err.count("error") == 1, err
    assert not out.exists()
    _files(tmp_path)
    tasks = [E.TrialTask(texture=950, force_N=0.5, velocity_m_per_s=0.01, trial=0, seed=1, movement_id=7,
                         stage="pilot", library=str(lib.resolve()))]
    monkeypatch.setattr(E, "sweep", _edit_meanwhile(lib, rows_of))
    with pytest.raises(TextureError, match=r"changed while the pilot stage ran \(SHA-256 \w{16}… at the start, "):
        E.run_stage("pilot", tasks, tmp_path / "cache", progress=False)
    assert not (tmp_path / "cache").exists()
    monkeypatch.setattr(E, "sweep", lambda tasks, **kw: rows_of(tasks))  # unedited: run and cached
    assert E.run_stage("pilot", tasks, tmp_path / "cache", progress=False) == rows_of(tasks)
    assert len(list((tmp_path / "cache").iterdir())) == 1


def test_a_library_path_with_control_characters_is_shown_escaped_on_one_line(tmp_path):
    """A library file whose path holds a line break or a terminal escape: each problem names the path with those
    characters escaped (one line; nothing reaches the terminal as a control sequence)."""
    from bench.errors import TextureError
    from bench.textures.library import named_library

    odd = tmp_path / "no\x1bpe\nx.toml"
    odd.write_text("[[texture]]\nnumber = 1\n", encoding="utf-8")
    with pytest.raises(TextureError) as e:
        named_library(str(odd), "--library")
    assert e.value.problems and all("\n" not in p and "\x1b" not in p for p in e.value.problems)
    assert all("no\\x1bpe\\nx.toml" in p for p in e.value.problems)
