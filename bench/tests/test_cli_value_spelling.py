"""A value the user typed comes back in a message as the rest of the CLI spells values — text in double quotes, as
TOML and the scene and texture messages write it (``--show: no texture named "nope"``) — never in Python's repr
quoting (``'abc'``, or ``"BT x'y"`` only when the text holds a single quote)."""

import pytest

from bench.tests.test_cli_review import invoke

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("argv, shown", [
    (["units", "--serial", "abc"], 'argument --serial: serial "abc": a serial number starts with "BT"'),
    (["units", "--serial", "BT x'y"], 'argument --serial: serial "BT x\'y": a serial number starts with "BT"'),
    (["units", "--serial", "BTU9999999999999"], 'serial "BTU9999999999999": unit seed 9999999999999 is above'),
    (["claims", "--unit", "foo"], 'argument --unit: unit "foo": a unit seed 0 to'),
    (["textures", "--group", "plastics"], 'error: --group "plastics": unknown; groups: paper-like, '),
    (["textures", "--group", "it's"], 'error: --group "it\'s": unknown; groups: paper-like, '),
    (["textures", "--group", ""], 'error: --group "": empty; groups: paper-like, '),
    (["textures", "--group", "s"], 'error: --group "s": ambiguous, part of 10 groups: art supplies and misc., glass'),
])
def test_units_serial_and_textures_group_spell_the_value_as_the_cli_does(argv, shown, capsys):
    status, out, err = invoke(argv, capsys)
    assert status == 2 and out == "" and err.count("\n") == 1 and "Traceback" not in err, err
    assert shown in err, err
    typed = argv[-1]
    assert repr(typed) not in err.replace(f'"{typed}"', ""), err  # Python's quoting nowhere else in the line


def test_an_empty_group_is_refused_rather_than_listing_every_texture(capsys):
    """``--group ""`` (an empty shell variable, say) listed the whole library as if no group were given."""
    status, out, err = invoke(["textures", "--group", ""], capsys)
    assert status == 2 and "T1 " not in out and 'error: --group "": empty' in err, (out, err)


@pytest.mark.parametrize("argv, shown", [
    (["run", "--seed", "abc", "rest"], 'argument --seed: "abc" is not a whole number'),
    (["benchmark", "--seconds", "ten"], 'argument --seconds: "ten" is not a number'),
    (["campaign", "--faults", ",", "--scenes", "rest"], 'argument --faults: ",": comma-separated names (or all)'),
    (["campaign", "--scheduler", "nowhere"], 'argument --scheduler: "nowhere": not a scheduler address'),
    (["texture-sweep", "--textures", "43", "--movements", "ab"], 'error: --movements = "ab": give comma-separated'),
    (["texture-sweep", "--textures", "43, 43"], 'error: --textures = "43, 43": texture(s) [43] listed twice'),
])
def test_the_bench_s_own_checks_spell_the_value_typed_in_double_quotes(argv, shown, capsys):
    """--seed, --seconds (every number() and whole() flag), --faults, --scheduler, --movements and --textures showed
    the value in Python's repr ('abc'), unlike the scene, texture and unit messages."""
    status, out, err = invoke(argv, capsys)
    assert status == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert shown in err and repr(argv[-1]) not in err and repr(argv[2]) not in err, err


@pytest.mark.parametrize("argv, shown", [
    (["frobnicate"], 'argument COMMAND: invalid choice: "frobnicate" (choose from run, validate, scenes, '),
    (["run", "--fidelity", "it's", "rest"], 'argument --fidelity: invalid choice: "it\'s" (choose from fast, '
                                            'default, reference) (see biotac-bench run --help)'),
    (["run", "--spi", "a\x1bb", "rest"], 'argument --spi: invalid choice: "a\\u001Bb" (choose from software, rtl)'),
    (["run", "--quiet=yes", "rest"], 'argument --quiet: ignored explicit argument "yes" (see'),
])
def test_argparse_s_own_messages_spell_the_value_and_list_the_choices_as_the_bench_does(argv, shown, capsys):
    """argparse quotes the value (and each choice) with repr: its messages are rewritten to the bench's spelling,
    one line, a control character escaped."""
    status, out, err = invoke(argv, capsys)
    assert status == 2 and err.count("\n") == 1 and "\x1b" not in err, err
    assert shown in err, err
    assert "'" not in err.replace("it's", ""), err  # no repr quoting left, of the value or of a choice


def test_only_argparse_s_quoting_is_rewritten():
    """The bench's own messages (raised through argparse too) pass unchanged; a choice that is no text (an int)
    leaves argparse's list as it is."""
    from bench.cli.args import argparse_message

    for text in ("argument --seed: expected one argument", "unrecognized arguments: 'x'",
                 "argument --seed: -1: must be 0 to 9", "argument --n: invalid choice: 3 (choose from 1, 2)"):
        assert argparse_message(text) == text
