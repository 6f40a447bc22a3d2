"""What a run hands its user, checked against independent figures (from a mutation hunt in the exports, the report,
the slide recorder and the scene parser, where a wrong baseline, unit or window passed every earlier test):
codes.npz's force column, the report's sliding table, a slide's properties recomputed from the exported codes, the
recorder keeping only good samples, the HDF5 rate attribute, the resting σ without a quiet lead-in, and the scene's
pressure calibrator in kPa and slides that overrun the scene."""

from __future__ import annotations

import numpy as np
import pytest

from bench.reporting.report import write_outputs
from bench.running.runner import run_scene
from bench.scenes.scene import SceneError, load_scene, parse_scene
from bench.paths import SCENES_DIR

pytestmark = pytest.mark.unit


@pytest.fixture(scope="module")
def press_run(tmp_path_factory):
    """press_hold (1.5 N from 1.0 s, ramp 0.5 s, held 2 s), its codes.npz exported."""
    out = tmp_path_factory.mktemp("press")
    record = write_outputs(run_scene(load_scene(SCENES_DIR / "press_hold.toml"), progress=False), out, plots=False,
                           npz=True)
    return record, np.load(out / "codes.npz")


def test_the_force_column_reads_zero_at_rest_and_the_press_while_pressed(press_run):
    """codes.npz's PDC_force_N is PDC's rise over PDC's own resting code × D's 0.0115 N/bit: ~0 N before the press
    (± 0.02 N), the pressed 1.5 N during the hold (± 15 %: D's linear range, R² ≈ 0.995), and the same offset as
    PDC_kPa's (their ratio is that of the two published scales, sample by sample)."""
    from emulator.conversions import FORCE_N_PER_PDC_BIT, PDC_KPA_PER_BIT

    _, d = press_run
    t, force, kpa = d["PDC_t"], d["PDC_force_N"], d["PDC_kPa"]
    assert abs(np.median(force[t < 0.9])) < 0.02
    assert np.median(force[(t > 1.7) & (t < 3.4)]) == pytest.approx(1.5, rel=0.15)
    moved = np.abs(kpa) > 1e-9
    assert np.allclose(force[moved] / kpa[moved], FORCE_N_PER_PDC_BIT / PDC_KPA_PER_BIT, rtol=1e-9)


def test_the_other_physical_columns_are_the_published_conversions_of_the_codes(press_run):
    """codes.npz (README): PAC_Pa is PAC's code over its resting lead-in × 0.37 Pa/bit (D Table 4-1: ~0 Pa before
    the press, within a bit), TDC_C the thermistor curve of D eq. 4.4 (a skin between 20 and 45 °C), E<n>_ohm
    D eq. 4.1's impedance of each of the 19 electrodes' codes — sample for sample."""
    from emulator import conversions as conv

    _, d = press_run
    t, pa, code = d["PAC_t"], d["PAC_Pa"], d["PAC_code"].astype(float)
    assert abs(np.median(pa[t < 0.9])) < conv.PAC_PA_PER_BIT
    assert np.allclose(np.diff(pa), np.diff(code) * conv.PAC_PA_PER_BIT)
    rest = np.median(code[t < 0.9])
    assert np.allclose(pa, (code - rest) * conv.PAC_PA_PER_BIT, atol=conv.PAC_PA_PER_BIT)
    assert np.array_equal(d["TDC_C"], conv.tdc_to_celsius(d["TDC_code"]))
    assert 20 < np.median(d["TDC_C"]) < 45
    electrodes = sorted({k.split("_")[0] for k in d.files if k.startswith("E") and k.endswith("_ohm")},
                        key=lambda e: int(e[1:]))
    assert electrodes == [f"E{n}" for n in range(1, 20)]
    for e in electrodes:
        assert np.array_equal(d[f"{e}_ohm"], conv.impedance_ohm(d[f"{e}_code"])), e


def test_the_hdf5_rate_attribute_is_each_channels_sample_rate(press_run, tmp_path):
    """samples.h5's per-channel rate_Hz is what the samples' spacing says (PAC 2200 Hz, the others 100 Hz in the
    default frame): MATLAB and pandas readers take it as the sampling rate."""
    import h5py

    out = tmp_path / "o"
    sc = parse_scene({"scene": {"name": "r", "duration_s": 1.0}})
    write_outputs(run_scene(sc, progress=False), out, plots=False)
    with h5py.File(out / "samples.h5") as f:
        for name in ("PAC", "PDC", "TDC", "E7"):
            t = f[name]["t"][:]
            assert f[name].attrs["rate_Hz"] == pytest.approx(1.0 / np.median(np.diff(t)), rel=1e-6), name
        assert f["PAC"].attrs["rate_Hz"] == pytest.approx(2200.0) and f["PDC"].attrs["rate_Hz"] == pytest.approx(100.0)


@pytest.fixture(scope="module")
def slip_run(tmp_path_factory):
    """slip_onset (3 mm grating, 1 N, 20 mm/s), with its report and codes.npz."""
    out = tmp_path_factory.mktemp("slip")
    scene = load_scene(SCENES_DIR / "slip_onset.toml")
    record = write_outputs(run_scene(scene, progress=False), out, plots=False, npz=True)
    return scene, record, out


def test_the_report_prints_the_slides_velocity_in_cm_per_s(slip_run):
    _, _, out = slip_run
    row = next(line for line in (out / "report.md").read_text().splitlines() if line.startswith("| 0 |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[2:4] == ["1", "2"], row  # 1 N, 20 mm/s = 2 cm/s under "velocity (cm/s)"


def test_a_slides_roughness_and_fineness_are_those_of_its_exported_codes(slip_run):
    """Recomputed from codes.npz alone — the good PAC and PDC samples from 0.1 s before the slide to its end, contact
    at start + approach (D's background is measured after contact, before sliding) — roughness and fineness equal
    the run's row (the stage current matters only to traction)."""
    from bench.textures.properties import TrialRecording, properties

    scene, record, out = slip_run
    s = scene.stimuli[0]
    d = np.load(out / "codes.npz")
    take = {}
    for ch in ("PAC", "PDC"):
        t, code, status = d[f"{ch}_t"], d[f"{ch}_code"], d[f"{ch}_status"]
        sel = (t >= s.start_s - 0.1) & (t <= s.end_s) & (status == 0)
        take[ch] = (t[sel], code[sel])
    rec = TrialRecording(*take["PAC"], *take["PDC"], take["PAC"][0], np.zeros(take["PAC"][0].size),
                         s.start_s + s.approach_s, s.slide_start_s, s.slide_end_s)
    row = record["sliding"]["trials"][0]
    again = properties(rec)
    assert again["roughness"] == pytest.approx(row["roughness"], rel=1e-9, abs=1e-12)
    assert again["fineness"] == pytest.approx(row["fineness"], rel=1e-9, abs=1e-12)


def test_the_slide_recorder_keeps_only_good_samples(slip_run):
    """An error word or a parity failure (status ≠ 0) inside a slide's window is not a PAC sample of the slide."""
    from bench.running.slides import SlideRecorder

    scene, _, _ = slip_run
    s = scene.stimuli[0]
    recorder = SlideRecorder(scene)
    t = np.linspace(s.start_s, s.end_s, 5)
    recorder.add({"PAC": (t, np.array([2048, 4095, 2050, 0, 2049]), np.array([0, 2, 0, 1, 0], np.uint8)),
                  "PDC": (t, np.full(5, 800), np.zeros(5, np.uint8))})
    kept_t, kept_code = recorder._parts[0]["PAC"][0]
    assert kept_code.tolist() == [2048, 2050, 2049] and kept_t.tolist() == t[[0, 2, 4]].tolist()


def test_the_resting_sigma_is_the_noise_without_a_quiet_lead_in():
    """A drop at 30 ms leaves no quiet lead-in: PAC's resting σ then comes from the robust spread of the whole
    record (1.4826 × MAD, a normal's σ), and still reads D's 1.4 ± 0.15 bits, as with a second of rest before."""
    from bench.reporting.report import resting_stats

    def sigma(at_s):
        sc = parse_scene({"scene": {"name": "s", "duration_s": 2.0, "seed": 5},
                          "stimulus": [{"kind": "sphere_drop", "sphere": "1 mm steel bearing", "at_s": [at_s]}]})
        return resting_stats(run_scene(sc, progress=False), "PAC")[1]

    early, late = sigma(0.03), sigma(1.5)
    assert early == pytest.approx(1.4, abs=0.15) and early == pytest.approx(late, rel=0.1)


def test_the_pressure_calibrators_offset_is_in_kpa():
    """offset_kPa = 1 is 1000 Pa in the stimulus (read as Pa it was a thousandth of the asked step)."""
    sc = parse_scene({"scene": {"name": "p", "duration_s": 2.0},
                      "stimulus": [{"kind": "pressure", "start_s": 0.5, "duration_s": 1.0, "offset_kPa": 1.0}]})
    assert sc.stimuli[0].offset_Pa == pytest.approx(1000.0)


def test_a_slide_that_ends_after_the_scene_by_its_acceleration_is_refused():
    """A slide lasts approach + hold + distance/velocity + the stage's acceleration + lift: a scene shorter by only
    the acceleration is refused (its slide would be dropped from the results, silently)."""
    slide = {"kind": "slide", "start_s": 0.2, "texture": "3 mm grating", "force_N": 1.0, "velocity_mm_per_s": 20,
             "distance_mm": 20, "approach_s": 0.03, "hold_s": 0.2, "accel_s": 0.2}
    end = parse_scene({"scene": {"name": "long", "duration_s": 30.0}, "stimulus": [slide]}).stimuli[0].end_s
    parse_scene({"scene": {"name": "ok", "duration_s": end + 1e-3}, "stimulus": [slide]})
    with pytest.raises(SceneError, match="after the end of the scene"):
        parse_scene({"scene": {"name": "short", "duration_s": end - 0.1}, "stimulus": [slide]})


def _accumulated_and_scipys(x: np.ndarray, fs: float, t0: float, max_columns: int):
    """(freqs Hz, times s, Sxx) of the run's spectrogram accumulator fed ``x`` (sampled at ``fs`` Hz from ``t0`` s)
    in chunks of 1000, and scipy's spectrogram of the whole record with the same window (80 ms, half overlap)."""
    from scipy.signal import spectrogram

    from bench.running.aggregate import SpectrogramAccumulator

    t = t0 + np.arange(x.size) / fs
    acc = SpectrogramAccumulator(duration_s=x.size / fs, max_columns=max_columns)
    for a in range(0, x.size, 1000):
        acc.add(t[a:a + 1000], x[a:a + 1000])
    acc.finish()
    return acc.result(), spectrogram(x, fs, window=("tukey", 0.25), nperseg=176, noverlap=88)


def test_the_streamed_spectrogram_is_scipys_column_for_column():
    """The PAC spectrogram computed chunk by chunk (80 ms Tukey(0.25) windows, half overlap, no averaging for a short
    run) equals scipy.signal.spectrogram of the whole record: every row, the Nyquist row too (one-sided density:
    doubled except DC and Nyquist), and column times at the windows' centres after the first sample."""
    fs, t0 = 2200.0, 0.3
    x = np.random.default_rng(3).normal(size=4400) + np.sin(2 * np.pi * 1100.0 * np.arange(4400) / fs)
    (freqs, times, sxx), (f_ref, t_ref, s_ref) = _accumulated_and_scipys(x, fs, t0, max_columns=10_000)
    assert np.allclose(freqs, f_ref) and np.allclose(times, t0 + t_ref, rtol=0, atol=1e-9)
    assert np.allclose(sxx, s_ref, rtol=1e-9, atol=0)


def test_a_long_runs_spectrogram_averages_consecutive_windows_into_at_most_the_column_limit():
    """README: the PAC spectrogram is averaged to at most 1000 columns. With a limit of 10 columns, 4 s at 2200 Hz
    (99 windows of 80 ms, half overlap) gives 10 columns, each the mean — not the sum — of 10 consecutive windows
    of scipy's spectrogram of the whole record (the last of the remaining 9), at the mean of their instants."""
    fs = 2200.0
    x = np.random.default_rng(5).normal(size=8800)
    (_, times, sxx), (_, t_ref, s_ref) = _accumulated_and_scipys(x, fs, 0.0, max_columns=10)
    assert s_ref.shape[1] == 99 and sxx.shape[1] == 10
    groups = [slice(10 * i, min(10 * i + 10, 99)) for i in range(10)]
    assert np.allclose(sxx, np.stack([s_ref[:, g].mean(axis=1) for g in groups], axis=1), rtol=1e-9, atol=0)
    assert np.allclose(times, [t_ref[g].mean() for g in groups], rtol=0, atol=1e-9)


def test_a_drop_is_counted_when_its_100_ms_window_fits_in_the_run():
    """The impact table counts a drop whose 100 ms detection window ends inside the run (at 0.85 s of 1 s); only an
    interrupted run leaves a drop out (the scene refuses a window that would run past its end)."""
    from bench.reporting.report import impact_results

    sc = parse_scene({"scene": {"name": "late", "duration_s": 1.0, "seed": 2}, "analysis": {"impact_detection": True},
                      "stimulus": [{"kind": "sphere_drop", "sphere": "1 mm steel bearing", "at_s": [0.85]}]})
    steel = impact_results(run_scene(sc, progress=False))["spheres"]["1 mm steel bearing"]
    assert (steel["drops"], steel["detected"]) == (1, 1)


def test_the_electrode_maps_resting_codes_are_the_first_twentieth_of_the_run():
    """The electrode map compares each electrode with its resting code, the median of the samples in the first 5 % of
    the run (before a touch at 30 %): the streamed early histogram holds exactly those samples."""
    sc = parse_scene({"scene": {"name": "map", "duration_s": 4.0, "seed": 1},
                      "stimulus": [{"kind": "touch", "electrode": "E7", "start_s": 1.2, "force_N": 1.0}]})
    rec = run_scene(sc, progress=False, keep_samples=True)
    for name in ("E1", "E7"):
        ch = rec.channels[name]
        early = ch.codes[ch.times < 0.05 * sc.duration_s]
        hist = rec.summary.channels[name].early_hist
        assert hist.sum() == early.size and np.array_equal(np.flatnonzero(hist), np.unique(early)), name


def test_tac_in_the_exports_uses_tdc_interpolated_at_each_tac_instant(tmp_path):
    """TAC in °C/s needs the TDC code at each TAC instant: codes.npz and samples.csv (in any time blocks) both give
    the published conversion with TDC linearly interpolated at the TAC sample times (TDC's codes jitter by its noise,
    so TDC taken at its own instants, or a block's edge mishandled, reads differently)."""
    import csv

    from bench.reporting import exports
    from emulator.conversions import tac_to_celsius_per_s

    sc = parse_scene({"scene": {"name": "tac", "duration_s": 2.0, "seed": 8}})
    write_outputs(run_scene(sc, progress=False), tmp_path / "a", plots=False, npz=True)
    d = np.load(tmp_path / "a" / "codes.npz")
    base = {"PAC": 2048.0, "PDC": 700.0, "TAC": float(np.median(d["TAC_code"]))}
    tdc_at_tac = np.interp(d["TAC_t"], d["TDC_t"], d["TDC_code"].astype(float))
    expected = tac_to_celsius_per_s(d["TAC_code"], tdc_at_tac, base["TAC"])
    exports.export_npz(tmp_path / "a" / "samples.h5", tmp_path / "x.npz", base)
    assert np.allclose(np.load(tmp_path / "x.npz")["TAC_C_per_s"], expected, rtol=1e-9, atol=1e-12)
    for block_s in (60.0, 0.137):
        exports.export_csv(tmp_path / "a" / "samples.h5", tmp_path / "x.csv", base, block_s=block_s)
        with open(tmp_path / "x.csv") as fh:
            values = np.array([float(r["value"]) for r in csv.DictReader(fh) if r["channel"] == "TAC"])
        assert np.allclose(values, expected, rtol=1e-6, atol=1e-9), block_s


def test_error_words_in_the_lead_in_never_reach_the_baseline():
    """A lead-in where every 7th PAC word is an error word (status 2, code 0) or a parity error (status 1, code 4095):
    the resting baseline and σ are those of the good words alone — the offsets every physical conversion subtracts
    would otherwise move by hundreds of codes."""
    from bench.running.aggregate import RunSummary

    scene = load_scene(SCENES_DIR / "rest.toml")
    rng = np.random.default_rng(3)
    t = np.arange(0, 2.0, 1 / 2200)
    code = np.round(2000 + 1.4 * rng.standard_normal(t.size)).astype(np.uint16)
    status = np.zeros(t.size, np.uint8)
    status[::7], status[3::7] = 2, 1
    code[::7], code[3::7] = 0, 4095
    summary = RunSummary(scene, ["PAC"])
    summary.add_parts({"PAC": (t, code, status)})
    good = (status == 0) & (t < 1.0)  # no stimulus: the lead-in is the first second
    base, sigma = summary.resting_stats("PAC", 2.0)
    assert base == pytest.approx(np.mean(code[good]), abs=1e-9)
    assert sigma == pytest.approx(np.std(code[good].astype(float)), abs=1e-9)


def test_samples_csv_names_each_channels_unit_and_samples_h5_each_datasets(tmp_path):
    """samples.csv (long format: time_s, channel, code, status, value, unit): PAC in Pa, PDC in kPa, TDC in degC,
    TAC in degC/s, the electrodes in ohm, each value the published conversion (an electrode's D eq. 4.1, never
    empty); samples.h5 (README): `units` on each dataset — t in s, code an ADC code."""
    import csv

    import h5py

    from bench.scenes.scene import parse_scene
    from emulator import conversions as conv

    scene = parse_scene({"scene": {"name": "units", "duration_s": 0.5, "seed": 2}})
    write_outputs(run_scene(scene, progress=False), tmp_path, plots=False, csv=True)
    with open(tmp_path / "samples.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    units = {}
    for r in rows:
        units.setdefault(r["channel"], set()).add(r["unit"])
    expected = {"PAC": "Pa", "PDC": "kPa", "TDC": "degC", "TAC": "degC/s", **{f"E{n}": "ohm" for n in range(1, 20)}}
    assert units == {k: {v} for k, v in expected.items()}
    e7 = [r for r in rows if r["channel"] == "E7"]
    assert e7 and all(float(r["value"]) == pytest.approx(float(conv.impedance_ohm(int(r["code"]))), rel=1e-6)
                      for r in e7)
    with h5py.File(tmp_path / "samples.h5", "r") as f:
        for name in ("PAC", "E7"):
            units = {field: f[name][field].attrs["units"] for field in ("t", "code", "status")}
            assert units == {"t": "s", "code": "ADC code", "status": ""}, name


def test_samples_csv_holds_every_sample_of_samples_h5_in_time_order(tmp_path):
    """samples.csv (exports: "rows in time order", written in time blocks) holds each sample of samples.h5 once,
    with its channel, code and status, and its instant to the 0.1 µs the CSV prints (slots are 227 µs apart; a
    coarser instant would merge or misplace samples) — sorted by time across channels and across blocks."""
    import csv

    from bench.reporting import exports, store

    sc = parse_scene({"scene": {"name": "rows", "duration_s": 0.5, "seed": 4}})
    write_outputs(run_scene(sc, progress=False), tmp_path, plots=False)
    h5 = tmp_path / "samples.h5"
    channels = store.read_channels(h5)
    exports.export_csv(h5, tmp_path / "x.csv", {"PAC": 2048.0, "PDC": 700.0, "TAC": 2048.0}, block_s=0.137)
    with open(tmp_path / "x.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    t = np.array([float(r["time_s"]) for r in rows])
    assert t.size == sum(r.times.size for r in channels.values())
    assert np.all(np.diff(t) > 0)  # one channel sampled per slot: strictly increasing
    for name, r in channels.items():
        mine = [row for row in rows if row["channel"] == name]
        assert np.allclose([float(row["time_s"]) for row in mine], r.times, rtol=0, atol=1e-7), name
        assert [int(row["code"]) for row in mine] == r.codes.tolist(), name
        assert [int(row["status"]) for row in mine] == r.status.tolist(), name


def test_a_rejected_sample_has_no_physical_value_and_a_rejected_tdc_word_no_say_in_tac(tmp_path):
    """codes.npz and samples.csv: a sample the host rejected (status 1 parity error, 2 error word) is no
    measurement, its physical value NaN (an error word had been converted like a code: 5540.8 ohm for E24 on a
    19-electrode sensor), and TAC's TDC reference at each instant interpolates between accepted TDC words only."""
    import csv

    import h5py

    from bench.reporting import exports
    from emulator import conversions as conv

    h5 = tmp_path / "samples.h5"
    channels = {"TDC": ([0.0, 1.0, 2.0], [1200, 4000, 1210], [0, 2, 0]), "TAC": ([1.0], [2050], [0]),
                "E24": ([0.0, 1.0], [2900, 2635], [0, 2]), "PAC": ([0.5, 1.5], [2048, 2100], [1, 0])}
    with h5py.File(h5, "w") as f:  # the store's layout: /<CH>/t, code, status
        for name, (t, code, status) in channels.items():
            g = f.create_group(name)
            g["t"], g["code"], g["status"] = np.array(t), np.array(code, np.uint16), np.array(status, np.uint8)
    base = {"PAC": 2048.0, "PDC": 735.0, "TAC": 2048.0}
    exports.export_npz(h5, tmp_path / "codes.npz", base)
    exports.export_csv(h5, tmp_path / "samples.csv", base)
    tac_want = conv.tac_to_celsius_per_s(np.array([2050]), np.array([1205.0]), 2048.0)[0]  # TDC between good words
    with np.load(tmp_path / "codes.npz") as z:
        assert z["E24_ohm"][0] == conv.impedance_ohm(np.array([2900]))[0] and np.isnan(z["E24_ohm"][1])
        assert np.isnan(z["TDC_C"][1]) and not np.isnan(z["TDC_C"][[0, 2]]).any()
        assert np.isnan(z["PAC_Pa"][0]) and z["PAC_Pa"][1] == pytest.approx(conv.pac_to_pa(np.array([2100]), 2048.0)[0])
        assert z["TAC_C_per_s"][0] == pytest.approx(tac_want)
    with open(tmp_path / "samples.csv", newline="") as fh:
        rows = {(r["channel"], r["time_s"][:3]): r["value"] for r in csv.DictReader(fh)}
    assert np.isnan(float(rows[("E24", "1.0")]))
    assert float(rows[("TAC", "1.0")]) == pytest.approx(tac_want, rel=1e-5)  # the CSV prints 6 digits
