"""Every subcommand ``biotac-bench --help`` lists (and their own subcommands: ``cheetah serve``) refuses bad input
in one line on stderr naming the command, exit status 2 — never argparse's usage block (``biotac-bench --help``:
"2 bad input (one line on stderr)")."""

from __future__ import annotations

import argparse

import pytest

from bench.cli import main as cli
from bench.paths import REPO

pytestmark = pytest.mark.unit


def _commands(parser: argparse.ArgumentParser, path: tuple = ()) -> dict[tuple, argparse.ArgumentParser]:
    """Each (sub)command's words -> its parser, found through the subparsers actions (what --help lists)."""
    out = {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                out[path + (name,)] = sub
                out.update(_commands(sub, path + (name,)))
    return out


COMMANDS = _commands(cli.build_parser())


def _bad_inputs(words: tuple) -> list[list[str]]:
    """An unknown flag, and the first option that takes a value given none (argparse's own error path)."""
    argvs = [[*words, "--no-such-flag"]]
    takes_value = [a for a in COMMANDS[words]._actions
                   if a.option_strings and a.nargs is None and not isinstance(a, argparse._HelpAction)
                   and a.const is None and not isinstance(a, argparse._VersionAction)]
    if takes_value:
        argvs.append([*words, takes_value[0].option_strings[-1]])
    return argvs


def test_the_list_is_the_one_help_shows(capsys):
    with pytest.raises(SystemExit):
        cli.main(["--help"])
    shown = capsys.readouterr().out
    assert {w[0] for w in COMMANDS} >= {"run", "validate", "texture-sweep", "explore", "claims", "bridge", "cheetah"}
    assert all(f"    {w[0]}" in shown for w in COMMANDS)


@pytest.mark.parametrize("words", sorted(COMMANDS), ids=" ".join)
def test_a_bad_flag_or_value_is_one_line_naming_the_command(words, capsys):
    for argv in _bad_inputs(words):
        try:
            status = cli.main(argv)
        except SystemExit as e:
            status = e.code
        out = capsys.readouterr()
        lines = out.err.splitlines()
        assert status == 2 and len(lines) == 1 and not out.out, (argv, out.out, out.err)
        assert lines[0].startswith(f"biotac-bench {' '.join(words)}: error: ") and "usage:" not in out.err


def test_an_unknown_command_is_one_line_too(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["no-such-command"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and len(err.splitlines()) == 1
    assert err.startswith('biotac-bench: error: argument COMMAND: invalid choice: "no-such-command" (choose from run, '
                          'validate, ')


@pytest.mark.parametrize("argv", [["record", "loop://", "--out", "{tmp}/a\nb/"],
                                  ["campaign", "--junit", "{tmp}/a\rb/", "--scenes", "rest"],
                                  ["record", "loop://", "--out", "{tmp}/a\x1b[2Jb/"]],
                         ids=["newline", "carriage-return", "escape-sequence"])
def test_a_path_with_line_breaks_or_control_characters_stays_one_line(argv, tmp_path, capsys):
    """A path may hold any byte but NUL and '/': a line break in it must not split the one error line (nor an escape
    sequence clear the terminal); it is shown escaped, as Python writes it in a string."""
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    try:
        status = cli.main(argv)
    except SystemExit as e:
        status = e.code
    lines = capsys.readouterr().err.splitlines()
    assert status == 2 and len(lines) == 1, lines
    (path,) = [a for a in argv if a.startswith(str(tmp_path))]
    shown = path.encode("unicode_escape").decode("ascii")
    assert f": {shown}: is a folder" in lines[0] and "\x1b" not in lines[0], lines


@pytest.mark.parametrize("case", ["claims-plots-group", "claims-plots-in-the-way", "validate-bad-scene",
                                  "validate-ok-line"])
def test_a_path_with_control_characters_is_shown_escaped_in_command_messages(case, tmp_path, capsys):
    """Messages a command writes after parsing (not argparse's, which escape already) show a path a user gave with
    its control characters escaped: ``claims --plots`` refused, a scene file's problems and its "ok" line printed
    the raw escape sequence (which acts on the terminal) or line break (which splits the line)."""
    odd = tmp_path / "a\x1b[2Jb\nc"
    if case.startswith("claims"):
        if case.endswith("in-the-way"):
            odd.mkdir()
            (odd / "frequency_sensitivity.png").write_text("my notes")
        argv = ["claims", "--quick", "--plots", str(odd), "--only", "vibration" if "way" in case else "scales"]
    else:
        odd = odd.with_suffix(".toml")
        text = (REPO / "fixtures" / "scenes" / "taps.toml").read_text()
        odd.write_text(text if case.endswith("ok-line") else "[scene]\nname = \"x\"\n")
        argv = ["validate", str(odd)]
    status = cli.main(argv)
    out = capsys.readouterr()
    shown = str(odd).encode("unicode_escape").decode("ascii")
    printed = (out.out if case.endswith("ok-line") else out.err).splitlines()
    assert status == {"validate-ok-line": 0, "validate-bad-scene": 1}.get(case, 2), out
    named = f"error: --plots {shown}: " if case.startswith("claims") else f"{shown}: "
    assert printed and printed[0].startswith(named) and "\x1b" not in out.out + out.err, printed
    if case.startswith("claims"):
        assert len(printed) == 1, printed
    if case.endswith("in-the-way"):  # the plot's own path, in argparse's message passed on
        assert f"{shown}/frequency_sensitivity.png: already there" in printed[0], printed
