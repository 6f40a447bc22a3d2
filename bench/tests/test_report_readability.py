"""What a run's report.md tells a reader without opening record.json: which SPI side answered (software model or
RTL), a real-time factor below 10× with its digits (0.74×, not "1×"), what the channel table's numbers are (ADC
codes; bad words), and where a channel reached the ADC's rails — a firm tap rails PAC, and those codes are the rail,
not the signal."""

from __future__ import annotations

import numpy as np
import pytest

from bench.paths import FIXTURES
from bench.reporting.report import build_record, markdown_report
from bench.running.runner import run_scene
from bench.scenes.scene import load_scene, parse_scene_text


@pytest.fixture(scope="module")
def taps():
    scene = load_scene(FIXTURES / "scenes" / "taps.toml")
    rec = run_scene(scene, progress=False)
    assert rec.error is None, rec.error
    return rec, build_record(rec, [])


def test_a_railed_channel_is_counted_and_named(taps):
    rec, record = taps
    pac = rec.channels["PAC"]
    good = pac.codes[pac.status == 0]
    at_rails = int(np.count_nonzero((good == 0) | (good == 4095)))
    assert at_rails > 0  # the shipped taps rail PAC (0.5 N at 4 s, 1 N at 5 s)
    assert record["channels"]["PAC"]["rail_samples"] == at_rails
    assert record["channels"]["PDC"]["rail_samples"] == 0
    report = markdown_report(record)
    assert f"**Clipped:** PAC reached the ADC's rails in {at_rails} samples" in report
    assert "PDC reached" not in report
    assert "Statistics of the 12-bit ADC codes (0–4095)" in report and "| at rails | bad |" in report


def test_a_quiet_run_reports_no_clipping_and_says_its_spi_side():
    rec = run_scene(parse_scene_text('[scene]\nname = "rest"\nduration_s = 0.3\n'), progress=False)
    report = markdown_report(build_record(rec, []))
    assert "Clipped" not in report and "SPI side: the software model" in report


def test_a_slow_run_keeps_the_digits_of_its_real_time_factor(taps):
    _, record = taps
    assert "(0.74× real time)" in markdown_report({**record, "realtime_factor": 0.7412})
    assert "(1234× real time)" in markdown_report({**record, "realtime_factor": 1234.4})


def test_a_channel_at_rest_is_drawn_as_a_band_not_a_barcode(taps, tmp_path):
    """traces.png: a channel whose codes stay within a few codes (noise) is at rest and drawn as its mean in a band;
    one that moves (PDC under the taps) keeps its full trace; PAC is always traced (its noise is the signal)."""
    from bench.reporting.plots import QUIET_SPAN_CODES, at_rest, scene_plots

    rec, _ = taps
    pdc, tdc = rec.channels["PDC"].codes, rec.channels["TDC"].codes
    assert np.ptp(tdc) <= QUIET_SPAN_CODES < np.ptp(pdc)
    assert at_rest(rec.summary, "TDC") and not at_rest(rec.summary, "PDC")
    draw = dict(scene_plots(rec, {"PAC": 2048.0, "PDC": float(np.median(pdc[:50])), "TAC": 2048.0}))["traces.png"]
    draw(tmp_path / "traces.png")
    assert (tmp_path / "traces.png").stat().st_size > 10_000


def test_a_frame_of_electrodes_without_e1_still_gets_its_traces(tmp_path):
    """Found by a hostile pass: the traces' electrode panel needed E1 in the frame, so a frame sampling only E19
    wrote no traces.png and said nothing. Any sampled electrode makes the panel."""
    from bench.reporting.plots import scene_plots
    from bench.reporting.report import baselines

    scene = parse_scene_text('[scene]\nname = "p"\nduration_s = 0.5\n[host]\nsequence = ["E19"]\n')
    rec = run_scene(scene, progress=False)
    plots = dict(scene_plots(rec, baselines(rec)))
    assert "traces.png" in plots
    plots["traces.png"](tmp_path / "traces.png")
    assert (tmp_path / "traces.png").stat().st_size > 10_000
