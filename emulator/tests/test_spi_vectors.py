"""The golden protocol vectors replay bit for bit on the software model (the RTL test does the same)."""

from pathlib import Path

import pytest

from emulator.spi import vectors as V

pytestmark = pytest.mark.unit
GOLDEN = sorted((Path(__file__).resolve().parents[2] / "fixtures" / "spi_vectors").glob("*.json"))


def test_the_golden_set_covers_every_command_error_word_and_fault():
    names = {p.stem for p in GOLDEN}
    assert {"sampling_and_errors", "properties", "resend_and_write", "five_sensors", "random"} <= names
    faults = {n for n in names if n.startswith("fault_")}
    assert len(faults) >= 12
    words = {d["miso"] for p in GOLDEN for d in V.load(p)["transfers"]}
    for err in ("a545", "a53f", "a52e", "a52d", "a558", "a55f", "a552", "a557"):
        assert err in words, f"no golden vector shows error word {err}"


@pytest.mark.parametrize("path", GOLDEN, ids=[p.stem for p in GOLDEN])
def test_software_model_reproduces_golden_vectors(path):
    vec = V.load(path)
    expected = [int(d["miso"], 16) for d in vec["transfers"]]
    got = V.replay(vec)
    bad = [(i, f"{e:x}", f"{g:x}") for i, (e, g) in enumerate(zip(expected, got)) if e != g]
    assert not bad, f"{path.name}: {len(bad)} transfers differ, first: {bad[:5]}"


@pytest.mark.parametrize("edit, words", [
    (lambda c: c.append({**c[-1], "t_ps": c[-1]["t_ps"] + 500_000_000}), "recorded conversions never requested"),
    (lambda c: c[0].update(channel=c[0]["channel"] ^ 1), "recorded channel"),
    (lambda c: c[0].update(t_ps=c[0]["t_ps"] + 2_000), "recorded channel"),  # 2 ns late
    (lambda c: c.pop(), "unexpected conversion"),
], ids=["extra", "other-channel", "2-ns-late", "missing"])
def test_a_replay_refuses_conversions_that_differ_from_the_recording(edit, words):
    """`replay` holds the model to a file's ADC conversions as well as its words: one the model never asks for, a
    conversion of another channel or 2 ns off its recorded instant, or one the model asks for that is not recorded,
    each fails the replay naming it."""
    vec = V.load(next(p for p in GOLDEN if p.stem == "sampling_and_errors"))
    assert len(vec["conversions"]) >= 2
    edit(vec["conversions"])
    with pytest.raises(AssertionError, match=words):
        V.replay(vec)


def test_the_generator_still_makes_the_shipped_golden_set_but_for_its_adc_codes():
    """`python -m emulator.spi.golden` regenerates fixtures/spi_vectors/: the same files with the same transfers
    (instants, selects, bits, MOSI, clocks, held selects), the same error words (of one sensor), faults, resets and
    conversions (sensor, channel, instant) — only the ADC codes and the data words carrying them may differ, as the sensor
    model evolves. A traffic script that drifted from the fixtures would otherwise go unnoticed."""
    from emulator.spi import golden as G

    made = G.all_vectors()
    assert set(made) == {p.stem for p in GOLDEN}
    for path in GOLDEN:
        old, new = V.load(path), made[path.stem]
        assert [{k: v for k, v in d.items() if k != "miso"} for d in new["transfers"]] == \
               [{k: v for k, v in d.items() if k != "miso"} for d in old["transfers"]], path.stem
        errors = [(i, d["miso"]) for i, d in enumerate(old["transfers"])  # (to all sensors: ORed with data)
                  if int(d["miso"], 16) >> 8 == 0xA5 and d["nbits"] == 16 and d["cs"] != 7]
        assert all(new["transfers"][i]["miso"] == w for i, w in errors), path.stem
        assert [{k: c[k] for k in ("sensor", "channel", "t_ps")} for c in new["conversions"]] == \
               [{k: c[k] for k in ("sensor", "channel", "t_ps")} for c in old["conversions"]], path.stem
        assert (new["faults"], new.get("resets", {}), new["sensors"], new["pull_up"]) == \
               (old["faults"], old.get("resets", {}), old["sensors"], old["pull_up"]), path.stem
        assert (new.get("variants"), new.get("provided")) == (old.get("variants"), old.get("provided")), path.stem


def test_a_vector_file_carries_the_sensors_variants_and_provided_channels():
    """An SP beside a partial BioTac: the file says which sensor is an SP and what the other provides, and a
    replay honours both — E20..E24 answer data from the SP, and a replay that forgot either (every sensor a BioTac,
    or providing all its channels) differs from the recorded words."""
    vec = V.load(next(p for p in GOLDEN if p.stem == "variants_and_provided"))
    assert vec["variants"] == {"1": "biotac-sp"} and vec["provided"] == {"2": [0, 1, 3, 17]}
    assert {c["channel"] for c in vec["conversions"] if c["sensor"] == 1} >= {36, 37, 38, 39, 40}
    words = [int(d["miso"], 16) for d in vec["transfers"]]
    assert V.replay(vec) == words
    for forgotten in ("variants", "provided"):
        other = {k: v for k, v in vec.items() if k != forgotten}
        with pytest.raises(AssertionError):  # conversions the recording has not, or never asked for
            assert V.replay(other) == words


def test_record_refuses_variants_or_provided_channels_for_sensors_not_on_the_bus():
    with pytest.raises(ValueError, match=r"name sensors \[3\] not among the sensors \[1, 2\]"):
        V.record("x", [V.tr(1_000_005, 1, 0x8300)], sensors=(1, 2), variants={3: "biotac-sp"})
