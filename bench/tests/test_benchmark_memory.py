"""The benchmark's memory figures (README, Performance) come from these two measurements; here they run small: the
machinery is what is checked — each in a child process of its own, the figures read from that child."""

import pytest

from bench.verification.benchmark import run_memory, stream_hour

pytestmark = pytest.mark.unit


def test_streaming_memory_is_measured_in_a_child_that_streams_the_asked_seconds():
    """`benchmark` (and `--hour`) stream the full frame at rest in a subprocess: its simulated seconds, its own peak
    RSS (VmHWM, not this test process's), and the resting PAC it read (≈ 2048)."""
    m = stream_hour(4.0)
    assert m["simulated_s"] == 4.0 and m["realtime_factor"] == pytest.approx(4.0 / m["wall_s"])
    assert 20 < m["peak_rss_MB"] < 1000
    assert abs(m["pac_mean"] - 2048) < 1


def test_run_memory_measures_two_runs_with_every_output_and_their_ratio():
    """`run_memory` times and measures two `biotac-bench run`s of the full frame at rest with samples.h5 and plots,
    each in its own child (the peak its child reports), and states their ratio and whether the targets hold."""
    said = []
    res = run_memory(1.0, 2.0, say=said.append)
    short, long_ = res["short"], res["long"]
    assert (short["simulated_s"], long_["simulated_s"]) == (1.0, 2.0)
    for run in (short, long_):
        assert {"samples.h5", "traces.png", "spectrogram.png", "record.json", "report.md"} <= set(run["outputs"])
        assert 50 < run["peak_rss_MB"] < 1000
    assert res["ratio"] == pytest.approx(long_["peak_rss_MB"] / short["peak_rss_MB"])
    assert res["met"] == (max(short["peak_rss_MB"], long_["peak_rss_MB"]) <= 300 and abs(res["ratio"] - 1) <= 0.2)
    assert len(said) == 1 and f"ratio {res['ratio']:.2f}" in said[0]
