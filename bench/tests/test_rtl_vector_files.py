"""`rtl vectors FILE`: a file that is not a protocol vector file is refused before the RTL is built, naming what is
wrong — found by a hostile pass, these passed the check and then died in cocotb with a traceback, hung (t_ps 1e18),
blamed the RTL for a mismatch (a conversion for an absent sensor, a negative MOSI) or passed vacuously (no
transfers). Every shipped vector file passes."""

import copy
import json
from pathlib import Path

import pytest

from bench.cli.rtl import vector_file_problem

pytestmark = pytest.mark.unit

VECTORS = Path(__file__).resolve().parents[2] / "fixtures" / "spi_vectors"
BASE = json.loads((VECTORS / "fault_truncated_word.json").read_text())


def _with(change):
    v = copy.deepcopy(BASE)
    change(v)
    return v


def _set(path, value):
    def change(v):
        *where, last = path
        for k in where:
            v = v[k]
        v[last] = value
    return change


BAD = {
    "conversion for an absent sensor": (_set(("conversions", 0, "sensor"), 9), "conversions[0]"),
    "conversion code out of range": (_set(("conversions", 0, "code"), 99999), "conversions[0]"),
    "conversion not an object": (_set(("conversions", 0), "x"), "conversions[0]"),
    "faults not a sensor's": (_set(("faults",), {"1": "bogus"}), 'faults["1"]'),
    "faults with an unknown field": (_set(("faults",), {"1": {"melted": True}}), 'faults["1"]'),
    "resets not a table": (_set(("resets",), "x"), "resets"),
    "a sensor listed twice": (_set(("sensors",), [1, 1]), "listed twice"),
    "transfers going back in time": (_set(("transfers", 1, "t_ps"), 0), "t_ps must rise"),
    "an instant a thousand years on": (_set(("transfers", 2, "t_ps"), 10**18), "out of range"),
    "a million bits": (_set(("transfers", 0, "nbits"), 10**6), "out of range"),
    "a clock of 500 GHz": (_set(("transfers", 0, "half_ps"), 1), "out of range"),
    "negative MOSI": (_set(("transfers", 0, "mosi"), "-1"), 'mosi = "-1"'),
    "MOSI wider than its bits": (_set(("transfers", 0, "mosi"), "ffffffffff"), "at most its 16 bits"),
    "no transfers": (_set(("transfers",), []), "no transfers"),
    # a second hostile pass: an int() traceback without the file, and values read as something else
    "a reset key that is a superscript digit": (_set(("resets",), {"²": [1]}), "resets"),
    "a reset key written twice as 0 and 00": (_set(("resets",), {"0": [1], "00": [1]}), "resets"),
    "a sensor that is a boolean": (_set(("sensors",), [True]), "sensors must be a list of sensor numbers"),
    "MISO wider than its bits": (_set(("transfers", 0, "miso"), "ffffffffff"), 'miso = "ffffffffff"'),
    # from a mutation hunt: refusals nothing exercised
    "a select code past the 3 bits": (_set(("transfers", 0, "cs"), 8), "transfers[0]"),
    "a reset of an absent sensor": (_set(("resets",), {"0": [3]}), "resets"),
    "pull_up that is not a boolean": (_set(("pull_up",), 1), "pull_up"),
    # the sensors' variants and provided channels (the SP beside a partial BioTac)
    "a variant nobody makes": (_set(("variants",), {"1": "biotac-xl"}), "variants: a sensor of sensors"),
    "a variant for an absent sensor": (_set(("variants",), {"3": "biotac-sp"}), "variants: a sensor of sensors"),
    "provided channels that are names": (_set(("provided",), {"1": ["PAC"]}), 'provided["1"]'),
    "a provided channel its variant lacks": (_set(("provided",), {"1": [36]}), "its variant recognises"),
    "provided channels of an absent sensor": (_set(("provided",), {"4": [0]}), 'provided["4"]'),
    "provided not a table": (_set(("provided",), [0, 1]), "provided: a sensor of sensors"),
    # a sensor written two ways ("1" and "01"): the check looked the variant up by the text, the tools by the number
    # (variants {"1": SP, "01": BioTac} passed and ran sensor 1 as a BioTac on an SP-less build)
    "a sensor's variant given as 1 and as 01": (_set(("variants",), {"1": "biotac-sp", "01": "biotac"}),
                                                "variants: a sensor of sensors"),
    "a provided key 01": (_set(("provided",), {"01": [0]}), 'provided["01"]'),
    "a faults key 01": (_set(("faults",), {"01": {}}), 'faults["01"]'),
}


def test_an_sp_sensor_may_provide_the_channels_only_an_sp_has(tmp_path):
    """E20 (36) is refused for a BioTac (above) and accepted for a sensor the file makes an SP."""
    f = tmp_path / "v.json"
    f.write_text(json.dumps(_with(lambda v: v.update(variants={"1": "biotac-sp"}, provided={"1": [0, 36]}))))
    assert vector_file_problem(str(f)) is None


def test_every_shipped_vector_file_passes():
    files = sorted(VECTORS.glob("*.json"))
    assert len(files) >= 15
    assert {f.name: vector_file_problem(str(f)) for f in files} == {f.name: None for f in files}


@pytest.mark.parametrize("name", list(BAD))
def test_a_malformed_vector_file_is_refused_naming_what(name, tmp_path):
    change, words = BAD[name]
    f = tmp_path / "v.json"
    f.write_text(json.dumps(_with(change)))
    problem = vector_file_problem(str(f))
    assert problem is not None and problem.startswith("not a vector file") and words in problem, problem


def test_the_command_refuses_it_in_one_line_before_building(tmp_path, capsys):
    from bench.cli import main as cli

    f = tmp_path / "v.json"
    f.write_text(json.dumps(_with(_set(("transfers",), []))))
    try:
        status = cli.main(["rtl", "vectors", str(f)])
    except SystemExit as e:
        status = e.code
    err = capsys.readouterr().err
    assert status == 2 and "no transfers" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
