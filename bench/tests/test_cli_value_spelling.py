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
