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


def _md_table(report: str, header_start: str) -> list[dict[str, str]]:
    """The rows of the Markdown table whose header line starts with ``header_start``, as header → cell text."""
    lines = report.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith(header_start))
    head = [c.strip() for c in lines[i].strip("|").split("|")]
    rows = []
    for line in lines[i + 2:]:
        if not line.startswith("|"):
            break
        rows.append(dict(zip(head, (c.strip() for c in line.strip("|").split("|")))))
    return rows


def test_the_channel_tables_columns_are_the_codes_own_min_max_rails_and_bad_words(taps):
    """report.md's channel table, cell by cell under its header (min, max, at rails, bad), against the figures
    recomputed from the samples the host read: min/max and rail counts over the good samples (the README: bad words
    are left out), bad = samples with status ≠ 0. Exact (integers)."""
    rec, record = taps
    rows = {r["channel"]: r for r in _md_table(markdown_report(record), "| channel |")}
    for name in ("PAC", "PDC", "TDC"):
        ch = rec.channels[name]
        good = ch.codes[ch.status == 0]
        want = {"min": str(int(good.min())), "max": str(int(good.max())),
                "at rails": str(int(np.count_nonzero((good == 0) | (good == 4095)))),
                "bad": str(int(np.count_nonzero(ch.status != 0))), "samples": str(ch.codes.size)}
        assert {k: rows[name][k] for k in want} == want, name
    assert rows["PAC"]["min"] == "0" and rows["PAC"]["max"] == "4095"  # the 1 N tap rails PAC both ways


def test_an_interrupted_runs_report_names_the_signal(taps):
    """A run stopped by a signal says so in report.md's status line with the signal's name (record.json's
    ``interrupted_by``), as the README's Ctrl-C section describes: "interrupted by SIGINT"."""
    _, record = taps
    report = markdown_report({**record, "status": "interrupted", "interrupted_by": "SIGINT"})
    assert "- status: **interrupted by SIGINT**" in report
    assert "- status: **ok**" in markdown_report(record)


def test_the_impact_tables_energy_is_d_table_5_2s_in_microjoules():
    """The impact table's "energy (µJ)" of a 1 mm steel bearing dropped from 7 cm is D Table 5-2's 2.805 µJ
    (m·g·h = 4.089 mg · 9.807 m/s² · 0.07 m); printed to 3 decimals, so within 0.002 µJ.  The record's mass is that
    4.089 mg, and the "rate" column is detected / drops in percent.  (A mutation hunt: a mass in grams and a rate
    printed as a fraction passed.)"""
    sc = parse_scene_text('[scene]\nname = "drop"\nduration_s = 0.6\nseed = 1\n[analysis]\nimpact_detection = true\n'
                          '[[stimulus]]\nkind = "sphere_drop"\nsphere = "1 mm steel bearing"\nat_s = 0.3\n')
    record = build_record(run_scene(sc, progress=False), [])
    report = markdown_report(record)
    row = _md_table(report, "| sphere |")[0]
    assert row["sphere"] == "1 mm steel bearing"
    assert float(row["energy (µJ)"]) == pytest.approx(2.805, abs=0.002)
    assert record["impact_detection"]["spheres"]["1 mm steel bearing"]["mass_mg"] == pytest.approx(4.089, rel=1e-3)
    assert row["rate"] == f"{100 * int(row['detected']) / int(row['drops']):.0f} %"


def test_the_effects_table_gives_milliseconds_per_simulated_second(taps):
    """"ms per simulated s" is the record's seconds_per_simulated_s × 1000 (printed to 3 decimals, so within
    0.0005 ms); the effects of a 6 s run cost well under a simulated second each, so each cell is below 1000."""
    _, record = taps
    rows = {r["effect"]: r for r in _md_table(markdown_report(record), "| effect |")}
    assert rows and set(rows) == {e["name"] for e in record["effects"]}
    for e in record["effects"]:
        ms = float(rows[e["name"]]["ms per simulated s"])
        assert ms == pytest.approx(1e3 * e["seconds_per_simulated_s"], abs=5e-4) and ms < 1000, e["name"]


@pytest.fixture
def drawn(monkeypatch):
    """The figures the scene plots draw, kept (file name → (figure, axes)) after they are saved and closed."""
    import contextlib
    from pathlib import Path

    from bench.reporting import plots

    kept, real = {}, plots.figure_file

    @contextlib.contextmanager
    def keeping(path, *args, **kw):
        with real(path, *args, **kw) as (fig, axes):
            kept[Path(path).name] = (fig, axes)
            yield fig, axes

    monkeypatch.setattr(plots, "figure_file", keeping)
    return kept


def test_the_traces_mark_each_tap_where_it_starts(taps, tmp_path, drawn):
    """traces.png's stimulus markers: each tap of taps.toml is a vertical line at its ``at_s`` (1, 2, 3, 4, 5 s, the
    scene file's), in every panel — not at the pulse's end 30–50 ms later. Exact to 1e-9 s."""
    from bench.reporting.plots import scene_plots
    from bench.reporting.report import baselines

    rec, _ = taps
    dict(scene_plots(rec, baselines(rec)))["traces.png"](tmp_path / "traces.png")
    _, axes = drawn["traces.png"]
    for ax in axes[:, 0]:
        xs = sorted(float(line.get_xdata()[0]) for line in ax.get_lines()
                    if list(line.get_ydata()) == [0, 1] and len(set(line.get_xdata())) == 1)
        assert xs == pytest.approx([1.0, 2.0, 3.0, 4.0, 5.0], abs=1e-9), ax.get_ylabel()


def test_the_spectrogram_is_drawn_in_db_re_one_pa_squared_per_hz(taps, tmp_path, drawn):
    """spectrogram.png's colours are 10·log10 of the PAC PSD in Pa²/Hz (its colour bar's label): the streamed
    spectrogram's codes²/Hz times (0.37 Pa/bit)² — D Table 4-1's PAC scale, the spec's — in decibels (power: 10, not
    20). To 1e-9 dB."""
    from bench.reporting.plots import scene_plots
    from bench.reporting.report import baselines

    rec, _ = taps
    dict(scene_plots(rec, baselines(rec)))["spectrogram.png"](tmp_path / "spectrogram.png")
    _, ax = drawn["spectrogram.png"]
    f, t, sxx = rec.summary.spectrogram.result()
    shown = np.asarray(ax.images[0].get_array(), float)
    want = 10 * np.log10(np.maximum(sxx * 0.37 ** 2, 1e-12))
    assert shown.shape == want.shape and np.allclose(shown, want, rtol=0, atol=1e-9)
    assert ax.get_ylabel() == "frequency (Hz)" and ax.get_xlabel() == "time (s)"


def test_the_electrode_maps_cross_sits_on_the_touched_electrode(tmp_path, drawn):
    """electrode_map.png marks a touch given by electrode (E7) with a red × on that electrode's own disc: the ×
    sits where the map writes "E7" (to 1e-9 mm), not on a neighbour."""
    from bench.reporting.plots import scene_plots
    from bench.reporting.report import baselines

    sc = parse_scene_text('[scene]\nname = "map"\nduration_s = 3.0\nseed = 1\n[[stimulus]]\nkind = "touch"\n'
                          'electrode = "E7"\nstart_s = 0.4\nforce_N = 1.0\n')
    rec = run_scene(sc, progress=False)
    dict(scene_plots(rec, baselines(rec)))["electrode_map.png"](tmp_path / "electrode_map.png")
    _, ax = drawn["electrode_map.png"]
    crosses = [line for line in ax.get_lines() if line.get_marker() == "x"]
    label = next(a for a in ax.texts if a.get_text() == "E7")
    assert len(crosses) == 1
    assert (float(crosses[0].get_xdata()[0]), float(crosses[0].get_ydata()[0])) == pytest.approx(label.xy, abs=1e-9)


def test_the_electrode_map_is_drawn_for_a_frame_without_e1_and_leaves_unread_electrodes_hollow(tmp_path, drawn):
    """A scene that reads E7 but not E1 and presses on E7 gets its electrode_map.png (it had been skipped without a
    word: the map asked for E1); E7's disc takes the scale's colour of its change, and the 18 electrodes the host
    never read are hollow discs labelled "not read", not 0 % on the colour scale."""
    from bench.reporting.plots import scene_plots
    from bench.reporting.report import baselines

    sc = parse_scene_text('[scene]\nname = "map"\nduration_s = 2.0\nseed = 1\nfidelity = "fast"\n'
                          '[host]\nsequence = ["PAC", "PDC", "E7"]\n[[stimulus]]\nkind = "press"\n'
                          'electrode = "E7"\nstart_s = 0.4\nforce_N = 1.0\nramp_s = 0.2\nhold_s = 0.3\n')
    rec = run_scene(sc, progress=False)
    plots = dict(scene_plots(rec, baselines(rec)))
    assert "electrode_map.png" in plots
    plots["electrode_map.png"](tmp_path / "electrode_map.png")
    assert (tmp_path / "electrode_map.png").stat().st_size > 0
    _, ax = drawn["electrode_map.png"]
    coloured, hollow = ax.collections
    label_at = {a.get_text(): a.xy for a in ax.texts}
    assert np.allclose(coloured.get_offsets(), [label_at["E7"]], rtol=0, atol=1e-9)
    assert float(coloured.get_array()[0]) > 1.0  # % change of E7's impedance under the 1 N press on it
    assert hollow.get_label() == "not read" and len(hollow.get_offsets()) == 18
    assert np.allclose(hollow.get_offsets(), [label_at[f"E{n}"] for n in range(1, 20) if n != 7], rtol=0, atol=1e-9)


def test_the_electrode_map_marks_a_placed_tap_and_leaves_a_bare_press_out(tmp_path, drawn):
    """A tap given x_mm/angle_deg dents the electrodes: electrode_map.png is drawn with one red × at its place
    (x_mm, and R·angle around the finger, to 1e-9 mm); a press given no place is not marked (only the fluid felt it)."""
    from bench.reporting.plots import scene_plots
    from bench.reporting.report import baselines
    from emulator.electrodes import CORE_RADIUS_MM

    sc = parse_scene_text('[scene]\nname = "map"\nduration_s = 2.0\nseed = 1\n[[stimulus]]\nkind = "tap"\n'
                          'at_s = 0.4\npeak_N = 2.0\nx_mm = -8.0\nangle_deg = 20.0\n[[stimulus]]\nkind = "press"\n'
                          'start_s = 0.6\nforce_N = 1.0\nramp_s = 0.2\nhold_s = 0.2\n')
    rec = run_scene(sc, progress=False)
    dict(scene_plots(rec, baselines(rec)))["electrode_map.png"](tmp_path / "electrode_map.png")
    _, ax = drawn["electrode_map.png"]
    crosses = [line for line in ax.get_lines() if line.get_marker() == "x"]
    assert len(crosses) == 1
    assert (float(crosses[0].get_xdata()[0]), float(crosses[0].get_ydata()[0])) == pytest.approx(
        (-8.0, CORE_RADIUS_MM * np.radians(20.0)), abs=1e-9)
