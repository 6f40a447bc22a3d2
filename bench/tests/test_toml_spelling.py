"""Messages about a TOML file (scene, experiment, texture library) spell values as the file does
(:func:`bench.tomlfile.spelled`): ``"x"`` not ``'x'``, ``true`` not ``True``, ``{a = 1}`` not ``{'a': 1}``."""

import datetime
import math
import re
import tomllib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bench.errors import SceneError
from bench.experiments import experiment as E
from bench.paths import FIXTURES
from bench.scenes.scene import load_scene, parse_scene_text
from bench.tomlfile import spelled

NO_LIMIT = 10 ** 9

#: what tomllib can give: text without surrogates (TOML cannot hold them), 64-bit integers, finite floats, dates
_TEXT = st.text(st.characters(exclude_categories=("Cs",)), max_size=20)
_SCALARS = (st.booleans() | st.integers(-2 ** 63, 2 ** 63 - 1) | st.floats(allow_nan=False) | _TEXT
            | st.dates() | st.times() | st.datetimes()
            | st.builds(lambda d, minutes: d.replace(tzinfo=datetime.timezone(datetime.timedelta(minutes=minutes))),
                        st.datetimes(), st.integers(-1439, 1439)))  # TOML's offsets: whole minutes
_VALUES = st.recursive(_SCALARS, lambda inner: st.lists(inner, max_size=4)
                       | st.dictionaries(_TEXT, inner, max_size=4), max_leaves=12)


@settings(max_examples=300, deadline=None)
@given(_VALUES)
def test_a_value_spelled_for_a_message_reads_back_as_the_same_value(value):
    """Round trip: what a message shows, pasted into a TOML file, is the value the file held."""
    assert tomllib.loads(f"x = {spelled(value, NO_LIMIT)}")["x"] == value


@pytest.mark.parametrize("value, text", [
    ("x", '"x"'), (True, "true"), (False, "false"), (7, "7"), (0.5, "0.5"), (1e300, "1e+300"),
    (math.inf, "inf"), (-math.inf, "-inf"), (math.nan, "nan"), ([1, "a"], '[1, "a"]'), ({"a": 1}, "{a = 1}"),
    ({"b c": [True]}, '{"b c" = [true]}'), ({}, "{}"), ('a"b\\c\nd', r'"a\"b\\c\nd"'), ("\x1b[31m", r'"\u001B[31m"'),
    ("é☃", '"é☃"'), (datetime.date(2020, 1, 2), "2020-01-02"),
    (None, "None"), (object, repr(object)),  # not TOML values (a Python caller's): Python's spelling
])
def test_values_are_spelled_as_toml_does(value, text):
    assert spelled(value, NO_LIMIT) == text


@pytest.mark.parametrize("value, text", [
    ("copy\ud800paper", '"copy\ufffdpaper" (\ufffd stands for the lone surrogate \\ud800, which TOML text cannot hold)'),
    (["\udfff", {"k\ud800": "\udfff"}],
     '["\ufffd", {"k\ufffd" = "\ufffd"}] (\ufffd stands for the lone surrogates \\udfff, \\ud800, which TOML text '
     'cannot hold)'),
])
def test_a_lone_surrogate_shows_as_a_replacement_character_and_says_which(value, text):
    """Only a JSON library can hold a lone surrogate ("\\ud800"), and no TOML text can (it showed as "\\uD800",
    which TOML refuses): the value is shown as valid TOML with U+FFFD in its place, and a note after it names the
    surrogate as JSON escapes it."""
    assert spelled(value, NO_LIMIT) == text


@settings(max_examples=200, deadline=None)
@given(st.lists(st.lists(st.characters() | st.sampled_from(["\ud800", "\udfff", "\udc80"]), max_size=6).map("".join),
                min_size=1, max_size=3))  # (st.text leaves surrogates out, whatever its alphabet)
def test_text_with_lone_surrogates_is_shown_as_toml_reading_back_with_replacement_characters(texts):
    """Any text, lone surrogates among it: what precedes the note reads back as the text, U+FFFD for each."""
    shown = spelled(texts, NO_LIMIT)
    has = any(0xD800 <= ord(ch) <= 0xDFFF for t in texts for ch in t)
    value = shown[:shown.rindex(" (\ufffd stands for")] if has else shown
    assert tomllib.loads(f"x = {value}")["x"] == [re.sub("[\ud800-\udfff]", "\ufffd", t) for t in texts]


def test_a_long_value_is_shortened_saying_its_length():
    text = spelled("x" * 1000)
    assert len(text) <= 80 and text.startswith('"xxx') and "(1002 characters)" in text


def test_a_hostile_scenes_message_shows_the_value_as_toml_does():
    """fixtures/hostile: ``scene = "x"`` names the value as the file spells it, not Python's ``'x'``."""
    with pytest.raises(SceneError) as e:
        load_scene(FIXTURES / "hostile" / "scenes" / "shape-scene-string.toml")
    assert e.value.problems[0].startswith('scene = "x": must be a table') and "'x'" not in str(e.value)


@pytest.mark.parametrize("fidelity", ['a"b', "back\\slash", "new\nline", "tab\there", "bell\x07", "ünïcödé"])
def test_a_scene_message_quotes_awkward_text_as_a_valid_toml_string(fidelity):
    """Quotes, backslashes, line breaks and control characters come out escaped: the shown value reads back."""
    text = f'[scene]\nname = "s"\nduration_s = 1.0\nfidelity = {spelled(fidelity)}\n'
    with pytest.raises(SceneError) as e:
        parse_scene_text(text)
    (shown,) = [m.group(1) for p in e.value.problems if (m := re.fullmatch(r"scene\.fidelity = (.*): must be.*", p))]
    assert tomllib.loads(f"x = {shown}")["x"] == fidelity


def test_an_experiment_files_message_shows_the_value_as_toml_does(tmp_path):
    """The experiment file's checks (its ``get`` of a typed field) speak TOML too: ``true``, not ``True``."""
    f = tmp_path / "x.toml"
    f.write_text('[experiment]\nname = "x"\n[pilot]\ntrials = true\n')
    with pytest.raises(E.ExperimentError) as e:
        E.load_experiment(f)
    assert "pilot.trials = true: must be a whole number (2 to 100)" in str(e.value)


@pytest.mark.parametrize("table, shown", [
    ('unit = "BT!x"', 'sensor.unit = "BT!x": a serial number starts with "BT" and has 3 to 16'),
    ('unit = "BTU9999999999999"', 'sensor.unit = "BTU9999999999999": unit seed 9999999999999 is above'),
    ('inflation_volume_mL = "x"', 'sensor.inflation_volume_mL = "x": must be a finite number in mL'),
    ("inflation_volume_mL = true", "sensor.inflation_volume_mL = true: must be a finite number in mL"),
])
def test_a_scene_message_about_a_sensors_unit_or_parameter_speaks_toml(table, shown):
    """A bad serial or parameter is named once, as the file spells it: the emulator's own check quoted it again in
    Python's spelling (``sensor.unit = "BT!x": serial 'BT!x': ... starts with 'BT'``, ``= True``)."""
    with pytest.raises(SceneError) as e:
        parse_scene_text(f'[scene]\nname = "s"\nduration_s = 1.0\n[sensor]\n{table}\n')
    (problem,) = e.value.problems
    assert problem.startswith(shown) and "serial '" not in problem and "True" not in problem, problem
