"""A first-day user's review of the command line: help pages that teach (a description with an example, defaults,
choices from the real registries), quiet exits into a closed pipe, shipped scenes by name and paths that work
from any folder, texture look-ups that name their flag, a texture library read back from its JSON, and the pytest
plugin's serial fixtures used as their documentation says."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from bench.cli import main as cli
from bench.paths import REPO, SCENES_DIR
from bench.tests.cli_runs import CLI

unit = pytest.mark.unit

#: Every subcommand (texture-sweep, explore, record and bridge have reviews of their own too; their help pages are
#: held to the same rule here: texture-sweep's --fidelity had none).
COMMANDS = [("run",), ("validate",), ("scenes",), ("profiles",), ("params",), ("units",), ("textures",),
            ("texture-sweep",), ("explore",), ("noise-budget",), ("claims",), ("benchmark",), ("rtl",), ("bridge",),
            ("record",), ("cheetah",), ("cheetah", "serve"), ("campaign",)]


def invoke(argv, capsys) -> tuple[int, str, str]:
    """``biotac-bench ARGV`` in process: exit status, stdout, stderr."""
    try:
        status = cli.main([str(a) for a in argv])
    except SystemExit as e:
        status = e.code
    out = capsys.readouterr()
    return status, out.out, out.err


def subcommand(*names):
    parser = cli.build_parser()
    for name in names:
        parser = next(a for a in parser._actions if a.dest in ("command", "cheetah_command")).choices[name]
    return parser


# ------------------------------------------------------------------------------------------ help pages
@unit
@pytest.mark.parametrize("names", COMMANDS, ids=" ".join)
def test_every_help_page_has_a_description_with_an_example_and_every_argument_a_help(names, capsys):
    status, out, _ = invoke([*names, "--help"], capsys)
    assert status == 0
    description = out.split("\n\n", 1)[1].split("\npositional arguments:")[0].split("\noptions:")[0]
    assert len(description) > 150, out
    assert f"biotac-bench {names[0]}" in description, f"no example in the help of {' '.join(names)}"
    undocumented = [a.dest for a in subcommand(*names)._actions if not a.help and a.dest != "help"
                    and a.dest not in ("cheetah_command",)]
    assert not undocumented, f"{' '.join(names)}: no help for {undocumented}"


@unit
def test_run_help_names_every_file_a_run_can_write(capsys):
    """`run --help` lists what a run writes into --out: every file of outdir.RUN_FILES (the files --force may
    replace), the plots of a placed contact and of a sliding run included (electrode_map.png, forces.png and
    properties.png had been left out of it)."""
    from bench.reporting.outdir import RUN_FILES

    _, out, _ = invoke(["run", "--help"], capsys)
    listed = out.split("It writes, into --out:")[1].split("\n\n")[0]
    assert [name for name in RUN_FILES if name not in listed] == []


@unit
@pytest.mark.parametrize("names, shown", [
    (("benchmark",), ["(default: 60.0)"]),
    (("claims",), ["(default: 2012)", "(default: default)"]),
    (("texture-sweep",), ["fidelity profile of every trial (biotac-bench profiles) (default: default)"]),
    (("campaign",), ["(default: 1)", "(default: out/campaign.xml)", "(default: all)"]),
    (("rtl",), ["(default: 1)"]),
    (("cheetah", "serve"), ["(default: the scene's count with SCENE, else 3"]),
    (("run",), ["(default gzip"]),
])
def test_help_pages_show_their_defaults(names, shown, capsys):
    _, out, _ = invoke([*names, "--help"], capsys)
    text = " ".join(out.split())  # argparse wraps lines
    assert all(s in text for s in shown), text
    assert "(default: None)" not in text and "(default: False)" not in text


@unit
def test_campaign_help_lists_the_faults_and_scenes_of_the_campaign_itself(capsys):
    from bench.campaigns import faults as campaign

    _, out, _ = invoke(["campaign", "--help"], capsys)
    for name, fault in campaign.FAULTS.items():
        assert re.search(rf"^  {name} +{re.escape(fault.expected)}$", out, re.M), name
    for name in campaign.SCENES:
        assert re.search(rf"^  {name} +\S", out, re.M), name
    # its "taps" is not the shipped scene taps: bare names are its own sets, scene files are paths or NAME.toml
    assert "the bare names above are always the campaign's own sets" in " ".join(out.split())


@unit
def test_the_top_level_help_names_every_file_a_run_writes(capsys):
    _, out, _ = invoke(["--help"], capsys)
    assert all(f in out for f in ("samples.h5", "codes.npz", "record.json", "report.md"))


@unit
def test_rtl_help_says_when_waves_are_vcd(capsys):
    _, out, _ = invoke(["rtl", "--help"], capsys)
    text = " ".join(out.split())
    assert "VCD" in text and "lz4" in text and "out/rtl_build_waves/" in text


@unit
@pytest.mark.parametrize("argv, words", [
    (["rtl", "lint", "extra.json"], ["argument files", "extra.json"]),
    (["rtl", "stream", "a.json", "--seconds", "1"], ["argument files", "a.json"]),
    (["rtl", "lint", "--waves"], ["argument --waves"]),
    (["rtl", "lint", "--seconds", "5"], ["argument --seconds", "lint"]),
    (["rtl", "vectors", "fixtures/spi_vectors/properties.json", "--seconds", "5"], ["argument --seconds", "vectors"]),
])
def test_rtl_refuses_what_its_action_would_ignore(argv, words, capsys):
    status, _, err = invoke(argv, capsys)
    assert status == 2 and len(err.strip().splitlines()) == 1 and all(w in err for w in words), err


# ------------------------------------------------------------------------------------------ closed pipes
@unit
@pytest.mark.parametrize("argv, status", [(["params"], {141}), (["scenes"], {141}),
                                          (["run", "--help"], {0, 141})], ids=["params", "scenes", "run --help"])
def test_a_reader_that_has_gone_ends_the_command_quietly(argv, status):
    """As `biotac-bench params | head -1`, made certain: the pipe's reader is closed before the command writes.
    (argparse itself ignores a failed write of --help: that exits 0 or, when the text was still buffered, 141.)"""
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        r = subprocess.run([*CLI, *argv], stdout=write_end, stderr=subprocess.PIPE, text=True, timeout=120,
                           cwd=REPO)
    finally:
        os.close(write_end)
    assert cli.READER_GONE == 141 and r.returncode in status
    assert r.stderr == ""


@unit
@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux): a device every write to fails")
@pytest.mark.parametrize("argv", [["units", "--json"], ["params"], ["textures"]], ids=" ".join)
def test_output_that_cannot_be_written_to_stdout_is_a_failure_naming_stdout(argv):
    """As `biotac-bench units --json > results.json` on a full disk: exit status 1 (results not written), one line
    that names stdout and the reason — not the bad-input status with a bare errno, not a second report at exit."""
    with open("/dev/full", "w") as full:
        r = subprocess.run([*CLI, *argv], stdout=full, stderr=subprocess.PIPE, text=True, timeout=120, cwd=REPO)
    assert r.returncode == 1, r.stderr
    assert r.stderr.splitlines() == [r.stderr.strip()] and r.stderr.startswith("error: stdout: ")
    assert "No space left on device" in r.stderr and "cut short" in r.stderr


@unit
def test_a_broken_pipe_elsewhere_is_still_an_error(monkeypatch, capsys):
    from bench.cli import scenes

    def broken(a):
        raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(scenes, "_cmd_profiles", broken)
    status, _, err = invoke(["profiles"], capsys)
    assert status == 2 and err.startswith("error: ") and "Broken pipe" in err


# ------------------------------------------------------------------------------------------ scenes by name
@unit
def test_scenes_prints_names_and_paths_that_work_from_another_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    status, out, _ = invoke(["scenes"], capsys)
    assert status == 0
    listed = dict(re.findall(r"^(\w+) +(\S+\.toml)$", out, re.M))
    assert set(listed) == {f.stem for f in SCENES_DIR.glob("*.toml")}
    assert all(Path(p).is_file() for p in listed.values())
    monkeypatch.chdir(REPO)
    _, out, _ = invoke(["scenes"], capsys)
    assert re.search(r"^taps +fixtures/scenes/taps\.toml$", out, re.M)  # inside the repository: relative


@unit
def test_a_shipped_scene_is_found_by_name_from_any_folder(tmp_path, monkeypatch, capsys):
    from bench.cli.scenes import scene_argument, scene_file

    monkeypatch.chdir(tmp_path)
    assert scene_argument("taps") == scene_file("taps.toml") == str(SCENES_DIR / "taps.toml")
    status, out, err = invoke(["validate", "taps", "rest"], capsys)
    assert status == 0 and "taps: ok (taps, 6.0 s" in out, err
    (tmp_path / "taps").write_text('[scene]\nname = "mine"\nduration_s = 1.0\n')
    assert scene_file("taps") == "taps"  # a file of that name comes first
    _, out, _ = invoke(["validate", "taps"], capsys)
    assert "taps: ok (mine, 1.0 s" in out


@unit
@pytest.mark.parametrize("argv", [["run", "tap"], ["validate", "tap"]], ids=" ".join)
def test_a_name_that_is_neither_a_file_nor_a_shipped_scene_points_at_the_list(argv, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    status, _, err = invoke(argv, capsys)
    assert status == (2 if argv[0] == "run" else 1)
    assert "No such file or directory" in err and "biotac-bench scenes" in err and "close matches: taps" in err


@unit
def test_a_repository_path_given_from_another_folder_gets_the_full_path(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    status, _, err = invoke(["run", "fixtures/scenes/taps.toml"], capsys)
    assert status == 2 and str(SCENES_DIR / "taps.toml") in err and len(err.strip().splitlines()) == 1


# ------------------------------------------------------------------------------------------ textures
@unit
@pytest.mark.parametrize("query, words", [("999", ["no texture number 999", "closest: "]),
                                          ("burlapp", ['no texture named "burlapp"', 'T100 "burlap"'])])
def test_an_unknown_texture_names_the_flag_not_a_broken_library(query, words, capsys):
    status, _, err = invoke(["textures", "--show", query], capsys)
    assert status == 2 and err.startswith("error: --show: ") and all(w in err for w in words), err
    assert "library.toml" not in err and "problem(s)" not in err


@unit
def test_an_unknown_texture_is_still_a_texture_error_with_its_problem():
    from bench.errors import TextureError
    from bench.textures.library import UnknownTextureError, texture

    with pytest.raises(TextureError) as e:
        texture(999)
    assert isinstance(e.value, UnknownTextureError) and e.value.query == 999
    assert e.value.problems == [e.value.problem] and "problem(s)" not in str(e.value)
    assert e.value.for_option("--textures").startswith("--textures: no texture number 999")


@unit
def test_the_json_listing_is_a_library_the_command_reads_back(tmp_path, capsys):
    _, listing, _ = invoke(["textures", "--json"], capsys)
    (tmp_path / "lib.json").write_text(listing)
    status, again, err = invoke(["textures", "--library", tmp_path / "lib.json", "--json"], capsys)
    assert status == 0 and json.loads(again) == json.loads(listing), err
    _, one, _ = invoke(["textures", "--show", "burlap", "--json"], capsys)
    (tmp_path / "one.json").write_text(one)
    status, out, err = invoke(["textures", "--library", tmp_path / "one.json"], capsys)
    assert status == 0 and "T100  burlap" in out and "1 texture(s)" in out, err


@unit
@pytest.mark.parametrize("name", ["lib.json", "my libs/lib's.json", "-lib.json"])
def test_the_listings_footer_suggests_a_command_that_works_as_typed(name, tmp_path, capsys, monkeypatch):
    """The footer named `--show N` without --library: typed, it showed the shipped library's texture or none. It is
    now a whole command — the --library given (quoted for the shell, a leading '-' made a path) and a number the
    listing holds — and that command, split as a shell splits it, shows the library's texture."""
    import shlex

    _, one, _ = invoke(["textures", "--show", "burlap", "--json"], capsys)
    monkeypatch.chdir(tmp_path)
    (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
    (tmp_path / name).write_text(one.replace('"name": "burlap"', '"name": "my burlap"'))
    status, out, err = invoke(["textures", f"--library={name}"], capsys)
    assert status == 0, err
    (typed,) = re.findall(r"`(biotac-bench [^`]*)`", out.splitlines()[-1])
    argv = shlex.split(typed)
    assert argv[0] == "biotac-bench" and "--show" in argv
    status, shown, err = invoke(argv[1:], capsys)
    assert status == 0 and shown.startswith("T100 my burlap"), (typed, err)
    status, out, err = invoke(["textures", f"--library={name}", "--group", "glass"], capsys)
    assert status == 0 and out.splitlines()[-1] == "0 texture(s)", out  # nothing to show: no suggestion


@unit
def test_a_listing_suggested_for_a_library_of_ones_own_lists_that_library(tmp_path, capsys, monkeypatch):
    """`textures --library X --show zzzz` and an experiment naming a texture its own library lacks suggested
    `biotac-bench textures`, which lists the shipped library: the suggestion names the library, and works typed."""
    import shlex

    from bench.experiments import experiment as E

    _, one, _ = invoke(["textures", "--show", "burlap", "--json"], capsys)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my lib.json").write_text(one.replace('"name": "burlap"', '"name": "my burlap"'))
    status, _, err = invoke(["textures", "--library", "my lib.json", "--show", "zzzz"], capsys)
    assert status == 2 and 'no texture named "zzzz"' in err, err
    (typed,) = re.findall(r"`(biotac-bench [^`]*)` lists them all", err)
    status, out, err = invoke(shlex.split(typed)[1:], capsys)
    assert status == 0 and "T100  my burlap" in out and "1 texture(s)" in out, (typed, err)
    with pytest.raises(E.ExperimentError) as e:
        E.parse_experiment({"experiment": {"name": "x", "library": "my lib.json"}, "pilot": {"textures": [7]}},
                           str(tmp_path / "x.toml"))
    (typed,) = re.findall(r"no texture \[7\] in the library \(`(biotac-bench [^`]*)`\)", str(e.value))
    status, out, err = invoke(shlex.split(typed)[1:], capsys)
    assert status == 0 and "T100  my burlap" in out, (typed, err)


@unit
@pytest.mark.parametrize("path", ["plain.json", "it's here.json", "-dash.json", "new\nline.json", "\x1b[31mred.json",
                                  "back\\slash\x07.json", "ünï\u200bcode.json", "bad\udcffbyte.json"])
def test_a_path_suggested_in_a_command_is_one_word_the_shell_reads_back(path):
    """bash reads :func:`shell_word` back as the path (a leading '-' as ./-…), and the word itself holds no line
    break or control character (so the footer shows them rather than acting on the terminal)."""
    from bench.errors import shell_word

    word = shell_word(path)
    assert word.isprintable(), word
    done = subprocess.run(["bash", "-c", f"printf %s {word}"], capture_output=True, check=True)
    assert done.stdout == os.fsencode(("./" if path.startswith("-") else "") + path)


@unit
@pytest.mark.parametrize("text, words", [("[", ["JSON syntax error", "line 1"]),
                                         ("[" * 5000 + "]" * 5000, ["nested too deeply"]),
                                         ('[{"texture": [[[[[[[[[1]]]]]]]]]}]', ["nested more than 8"]),
                                         ("[]", ["no [[texture]] tables"])])
def test_a_broken_json_library_is_refused_naming_the_file(text, words, tmp_path, capsys):
    f = tmp_path / "bad.json"
    f.write_text(text)
    status, _, err = invoke(["textures", "--library", f], capsys)
    assert status == 2 and str(f) in err and all(w in err for w in words), err


# ------------------------------------------------------------------------------------------ pytest plugin
def _documented_test(name: str) -> str:
    """A test function from the plugin's documentation (bench/pytest_plugin/fixtures.py), as a user copies it."""
    from bench.pytest_plugin import fixtures

    block = re.search(rf"^    def {name}\(.*?(?=^\s*$)", fixtures.__doc__, re.M | re.S)
    assert block, f"{name} is not in the plugin's documentation"
    return textwrap.dedent(block.group(0))


@pytest.mark.firmware
def test_the_serial_fixtures_work_as_their_documentation_says(tmp_path):
    from bench.hosts.driver import CMD_START, encode
    from bench.pytest_plugin import fixtures

    start = bytes(int(b, 16) for b in re.search(r"until the host sends START \(((?:0x[0-9A-F]{2} ?){7})",
                                                 fixtures.__doc__).group(1).split())
    assert start == encode(CMD_START)  # the documented bytes are the START frame
    user_tests = "\n".join([
        "import serial",
        "from bench.hosts.driver import BridgeDriver",
        "from emulator.stimuli import Tap",
        "",
        _documented_test("test_with_the_bench_driver"),
        _documented_test("test_my_host_code"),
        "def test_nothing_comes_before_start_and_frames_after_the_raw_start_frame(biotac_serial_port):",
        "    port = serial.Serial(biotac_serial_port, 3000000, timeout=0.5)",
        "    assert port.read(100) == b''",
        f"    port.write({start!r})",
        "    assert b'\\xaa\\x55\\x10' in port.read(2000)",
        "    port.close()",
    ])
    (tmp_path / "test_user.py").write_text(user_tests)
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(tmp_path)],
                       capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert "3 passed" in r.stdout, r.stdout + r.stderr


@unit
def test_explore_help_describes_every_ablation_from_its_registry(capsys):
    """The list came from a paragraph that fell behind (stepper-noise was missing); now from ABLATIONS."""
    from bench.experiments.design import ABLATIONS

    _, out, _ = invoke(["explore", "--help"], capsys)
    for name, (what, _) in ABLATIONS.items():
        assert re.search(rf"^  {name}: {re.escape(what)}$", out, re.M), name


@pytest.mark.rtl
def test_cheetah_serve_names_a_scenes_rtl_spi_as_the_file_spells_it(tmp_path, capsys):
    """A scene whose [host] spi is "rtl" is served over the Verilog RTL (CheetahBench(spi="rtl"), as
    ``biotac_cheetah(scene=...)`` serves it), and the adapter says so, the value in TOML spelling (not Python's
    ``'rtl'``); it had been refused, "the Cheetah adapter serves the software SPI model only", after the adapter had
    learnt to clock the RTL."""
    scene = tmp_path / "rtl.toml"
    scene.write_text('[scene]\nname = "r"\nduration_s = 0.1\n[host]\nspi = "rtl"\n')
    status, out, err = invoke(["cheetah", "serve", str(scene), "--seconds", "0.1"], capsys)
    assert status == 0, err
    assert "their SPI side the Verilog RTL (the scene says host.spi = \"rtl\")" in err, err
    assert "software SPI model only" not in err
