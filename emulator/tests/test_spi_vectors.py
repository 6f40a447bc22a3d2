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
