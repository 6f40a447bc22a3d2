"""Every subcommand ``biotac-bench --help`` lists (and their own subcommands: ``cheetah serve``) refuses bad input
in one line on stderr naming the command, exit status 2 — never argparse's usage block (``biotac-bench --help``:
"2 bad input (one line on stderr)")."""

from __future__ import annotations

import argparse

import pytest

from bench.cli import main as cli

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
    assert err.startswith("biotac-bench: error: argument COMMAND: invalid choice: 'no-such-command'")


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
