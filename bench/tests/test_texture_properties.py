"""Texture properties (traction, roughness, fineness) on synthetic trials with known answers."""

import math
import re

import numpy as np
import pytest
from scipy import signal

from bench.textures import properties as tp

pytestmark = pytest.mark.unit

FS = 2200.0
CONTACT, START, END, STOP = 0.5, 1.5, 3.5, 4.0  # s


def make_trial(slide_signal=None, bg_sigma=0.0, seed=0, current=None, **meta) -> tp.TrialRecording:
    """A 4 s trial at 2.2 kS/s: PAC = mid-scale + background noise everywhere + ``slide_signal(t)`` while sliding."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(STOP * FS)) / FS
    pac = 2048.0 + bg_sigma * rng.standard_normal(t.size)
    sliding = (t >= START) & (t <= END)
    if slide_signal is not None:
        pac[sliding] += slide_signal(t[sliding], rng)
    tc = np.arange(0.0, STOP, 0.1)  # current every 100 ms, as D's stage controller
    cur = np.full(tc.size, 0.05) if current is None else current(tc)
    pdc = np.where(t > CONTACT, 2100.0, 2000.0)[::22]
    return tp.TrialRecording(pac_t=t, pac=pac, pdc_t=t[::22], pdc=pdc, current_t=tc, current_A=cur,
                             contact_s=CONTACT, slide_start_s=START, slide_end_s=END, **meta)


# ------------------------------------------------------------------------------------------------ the FIR filter


def test_filter_is_66th_order_linear_phase():
    h = tp.roughness_filter(FS)
    assert h.size == 67 and tp.FIR_ORDER == 66
    assert np.allclose(h, h[::-1])  # symmetric: linear phase, delay 33 samples


def test_filter_passband_is_20_to_700_hz():
    h = tp.roughness_filter(FS)
    _, H = signal.freqz(h, worN=[10.0, 20.0, 30.0, 400.0, 690.0, 700.0, 900.0], fs=FS)
    a10, a20, a30, a400, a690, a700, a900 = np.abs(H)
    assert a10 < 0.5 < a30          # the low edge lies between 10 and 30 Hz
    assert a400 == pytest.approx(1.0, abs=0.01)
    assert a690 > 0.5 > a900 and a900 < 0.01  # the high edge between 690 and 900 Hz; stop band beyond
    assert a20 == pytest.approx(0.5, abs=0.06) and a700 == pytest.approx(0.5, abs=0.06)  # −6 dB at the edges


def test_filter_is_designed_once_and_handed_out_as_a_copy():
    """Consistency: the remembered design is scipy's firwin to the bit, and a caller changing its taps changes
    no later design."""
    h = tp.roughness_filter(FS)
    assert np.array_equal(h, signal.firwin(67, [20.0, 700.0], pass_zero=False, window="hamming", fs=FS))
    h[:] = 0.0
    assert np.array_equal(tp.roughness_filter(FS), signal.firwin(67, [20.0, 700.0], pass_zero=False, fs=FS))


@pytest.mark.parametrize("lead, tail, guard_s, taps", [(0.2, 0.1, 0.05, None), (0.0, 0.0, 0.0, None),
                                                       (0.0, 0.0, 0.0, 4), (0.2, 0.1, 0.05, 8)])
def test_band_powers_are_the_mean_squares_of_the_whole_record_filtered(lead, tail, guard_s, taps, monkeypatch):
    """Consistency, bit for bit: the window powers equal the mean squares, over each window, of the whole
    mean-removed record convolved ("same") with the filter, though only the windows' samples are filtered — also
    for windows reaching to within the filter's half-length of the record's ends (here the background window
    from the first sample, the measurement window to the last) and for even filters (``taps``: a stand-in filter
    of that many taps, whose centring is one sample off the middle)."""
    rng = np.random.default_rng(3)
    t = np.arange(int(STOP * FS)) / FS
    rec = tp.TrialRecording(pac_t=t, pac=2048.0 + 5.0 * rng.standard_normal(t.size), pdc_t=t, pdc=t, current_t=t,
                            current_A=t, contact_s=0.0, slide_start_s=1.0, slide_end_s=t[-1] if not lead else END)
    if taps is not None:
        stand_in = rng.random(taps)
        monkeypatch.setattr(tp, "roughness_filter", lambda fs: stand_in)
    y = np.convolve(rec.pac - rec.pac.mean(), tp.roughness_filter(rec.pac_rate_hz), mode="same")
    windows = tp.measurement_window(rec, lead, tail), tp.background_window(rec, guard_s)
    expected = tuple(float(np.mean(y[(t >= w[0]) & (t <= w[1])] ** 2)) for w in windows)
    assert tp.band_powers(rec, lead, tail, guard_s) == expected


# ------------------------------------------------------------------------------------------------ fineness


@pytest.mark.parametrize("f", [80.0, 250.0, 600.0])
def test_tone_gives_centroid_at_its_frequency(f):
    rec = make_trial(lambda t, rng: 40.0 * np.sin(2 * np.pi * f * t), bg_sigma=0.01)
    sc = tp.spectral_centroid(rec)
    assert sc == pytest.approx(f, rel=0.01)
    assert tp.fineness(rec) == pytest.approx(math.log(f), abs=0.01)


def test_a_gap_in_the_recording_leaves_the_sampling_rate_and_the_centroid_alone():
    """The module's docstring: the sampling rate is 1 / the *median* spacing of the instants, so frames lost before
    contact (here 0.3 s of PAC, 660 samples, a host that fell behind) leave it at 2200 Hz and a 250 Hz tone's
    centroid at 250 Hz.  (A mutation hunt: the mean spacing, 8 % longer with this gap, passed.)"""
    full = make_trial(lambda t, rng: 40.0 * np.sin(2 * np.pi * 250.0 * t), bg_sigma=0.01)
    kept = (full.pac_t < 0.1) | (full.pac_t >= 0.4)
    rec = tp.TrialRecording(pac_t=full.pac_t[kept], pac=full.pac[kept], pdc_t=full.pdc_t, pdc=full.pdc,
                            current_t=full.current_t, current_A=full.current_A, contact_s=CONTACT,
                            slide_start_s=START, slide_end_s=END)
    assert rec.pac_rate_hz == pytest.approx(FS, rel=1e-9)
    assert tp.spectral_centroid(rec) == pytest.approx(250.0, rel=0.01)


def test_centroid_weights_by_power_not_amplitude():
    # 100 Hz at amplitude 30 and 500 Hz at amplitude 10: powers 900 and 100 -> (900·100 + 100·500) / 1000 = 140 Hz
    rec = make_trial(lambda t, rng: 30 * np.sin(2 * np.pi * 100 * t) + 10 * np.sin(2 * np.pi * 500 * t))
    assert tp.spectral_centroid(rec) == pytest.approx(140.0, rel=0.02)


def test_centroid_ignores_the_pac_offset_and_uses_only_the_measurement_window():
    # a loud 900 Hz tone during the hold and the first 20 % of the slide must not count
    def sig(t, rng):
        return np.where(t < START + 0.15 * (END - START), 200 * np.sin(2 * np.pi * 900 * t), 0) + \
            20 * np.sin(2 * np.pi * 200 * t)
    rec = make_trial(sig)
    assert tp.spectral_centroid(rec) == pytest.approx(200.0, rel=0.01)


# ------------------------------------------------------------------------------------------------ roughness


def test_white_noise_above_background_gives_expected_roughness():
    sigma_bg, sigma_x = 5.0, 8.0
    rec = make_trial(lambda t, rng: sigma_x * rng.standard_normal(t.size), bg_sigma=sigma_bg, seed=3)
    g = float(np.sum(tp.roughness_filter(FS) ** 2))  # white-noise power gain of the filter
    p, bg = tp.band_powers(rec)
    assert bg == pytest.approx(sigma_bg**2 * g, rel=0.1)
    assert p == pytest.approx((sigma_bg**2 + sigma_x**2) * g, rel=0.1)
    assert tp.roughness(rec) == pytest.approx(math.log(sigma_x**2 * g), abs=0.08)


def test_roughness_scales_as_log_of_power():
    a = make_trial(lambda t, rng: 4.0 * rng.standard_normal(t.size), bg_sigma=1.0, seed=1)
    b = make_trial(lambda t, rng: 40.0 * rng.standard_normal(t.size), bg_sigma=1.0, seed=1)
    assert tp.roughness(b) - tp.roughness(a) == pytest.approx(math.log(100.0), abs=0.1)


def test_roughness_floor_when_sliding_is_quieter_than_background():
    rec = make_trial(None, bg_sigma=3.0)
    rec_loud_bg = tp.TrialRecording(
        pac_t=rec.pac_t, pac=np.where(rec.pac_t < START, rec.pac, 2048.0), pdc_t=rec.pdc_t, pdc=rec.pdc,
        current_t=rec.current_t, current_A=rec.current_A, contact_s=CONTACT, slide_start_s=START,
        slide_end_s=END)
    r = tp.roughness(rec_loud_bg)
    assert math.isfinite(r) and r == pytest.approx(math.log(1e-3))  # the documented default floor, bits²
    assert tp.roughness(rec_loud_bg, power_floor=1e-6) == pytest.approx(math.log(1e-6))


# ------------------------------------------------------------------------------------------------ traction


def test_traction_is_mean_current_over_the_measurement_window():
    def current(tc):
        c = np.full(tc.size, 0.05)                       # unloaded, outside the slide
        c[(tc >= START) & (tc < START + 0.3)] = 2.0      # acceleration surge: inside the skipped lead
        steady = (tc >= START + 0.3) & (tc <= END)
        c[steady] = 0.6 + 0.1 * np.sin(tc[steady] * 7)   # sliding at constant velocity
        return c
    rec = make_trial(None, bg_sigma=1.0, current=current)
    t0, t1 = tp.measurement_window(rec)
    assert (t0, t1) == pytest.approx((START + 0.4, END - 0.2))
    tc = rec.current_t
    expected = np.mean([0.6 + 0.1 * math.sin(x * 7) for x in tc if t0 <= x <= t1])
    assert tp.traction(rec) == pytest.approx(expected, rel=1e-12)
    assert tp.traction(rec, lead=0.0) > expected + 0.1  # including the surge changes the answer


def test_properties_returns_all_three():
    rec = make_trial(lambda t, rng: 10 * np.sin(2 * np.pi * 300 * t) + rng.standard_normal(t.size), bg_sigma=1.0)
    props = tp.properties(rec)
    assert set(props) == {"traction", "roughness", "fineness"}
    assert props == {"traction": tp.traction(rec), "roughness": tp.roughness(rec), "fineness": tp.fineness(rec)}


# ------------------------------------------------------------------------------------------------ files and errors


def test_npz_round_trip(tmp_path):
    rec = make_trial(lambda t, rng: 5 * rng.standard_normal(t.size), bg_sigma=1.0, texture=43, force_N=0.2,
                     velocity_m_s=0.0631, trial=4, seed=99, extra={"skin": "new"})
    path = tp.save_npz(rec, tmp_path / "trial")
    assert path.name == "trial.npz" and path.exists()
    back = tp.load_npz(path)
    for name in ("pac_t", "pac", "pdc_t", "pdc", "current_t", "current_A"):
        assert np.array_equal(getattr(back, name), getattr(rec, name)), name
    assert (back.contact_s, back.slide_start_s, back.slide_end_s) == (CONTACT, START, END)
    assert back.metadata() == rec.metadata()
    assert tp.properties(back) == tp.properties(rec)


def test_a_trial_file_is_written_whole_or_not_at_all(tmp_path, monkeypatch):
    """A write that fails midway (injected: the NPZ writer puts out part of a file, then the disk fills) leaves the
    earlier trial.npz as it was and no temporary file beside it; the error names trial.npz."""
    import errno

    rec = make_trial(lambda t, rng: 5 * rng.standard_normal(t.size), bg_sigma=1.0, texture=43, force_N=0.2,
                     velocity_m_s=0.0631, trial=4, seed=99)
    earlier = tp.save_npz(rec, tmp_path / "trial.npz").read_bytes()

    def fills_the_disk(out, **arrays):
        out.write(b"PK\x03\x04 half a zip")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(tp.np, "savez_compressed", fills_the_disk)
    with pytest.raises(OSError, match="trial.npz"):
        tp.save_npz(rec, tmp_path / "trial")
    assert (tmp_path / "trial.npz").read_bytes() == earlier
    assert sorted(p.name for p in tmp_path.iterdir()) == ["trial.npz"]


def _write(path, **arrays):
    np.savez(path, **arrays)
    return path


def _arrays(rec):
    return dict(PAC_t=rec.pac_t, PAC_code=rec.pac, PDC_t=rec.pdc_t, PDC_code=rec.pdc,
                stage_current_t=rec.current_t, stage_current_A=rec.current_A, contact_s=CONTACT,
                slide_start_s=START, slide_end_s=END)


def test_load_names_missing_arrays(tmp_path):
    a = _arrays(make_trial(None, bg_sigma=1.0))
    del a["PAC_code"], a["slide_end_s"]
    with pytest.raises(tp.RecordingError, match="missing array.*PAC_code, slide_end_s"):
        tp.load_npz(_write(tmp_path / "x.npz", **a))


def _nan_at_3(x):
    x = x.copy()
    x[3] = np.nan
    return x


@pytest.mark.parametrize("key, make_value, message", [
    ("PAC_code", lambda a: np.zeros(10), "PAC: .* instants but 10 values"),
    ("PDC_t", lambda a: a["PDC_t"][::-1].copy(), "PDC: instants are not strictly increasing"),
    ("stage_current_A", lambda a: _nan_at_3(a["stage_current_A"]), "stage current: contains NaN"),
    ("PAC_t", lambda a: np.zeros((2, 2)), "PAC: instants and values must be 1-D"),
    ("slide_start_s", lambda a: np.float64(0.2), "contact_s <= slide_start_s < slide_end_s"),
    ("slide_end_s", lambda a: np.array([1.0, 2.0]), "slide_end_s must be a scalar"),
    ("meta_json", lambda a: np.array("{not json"), "meta_json is not valid JSON"),
    ("format", lambda a: np.array("something else v9"), "format is 'something else v9'"),
])
def test_load_rejects_malformed_arrays(tmp_path, key, make_value, message):
    a = _arrays(make_trial(None, bg_sigma=1.0))
    a[key] = make_value(a)
    with pytest.raises(tp.RecordingError, match=message):
        tp.load_npz(_write(tmp_path / "x.npz", **a))


def test_windows_without_data_are_errors():
    rec = make_trial(None, bg_sigma=1.0)
    sparse = tp.TrialRecording(pac_t=rec.pac_t, pac=rec.pac, pdc_t=rec.pdc_t, pdc=rec.pdc,
                               current_t=np.array([0.0, 3.9]), current_A=np.array([0.1, 0.1]),
                               contact_s=CONTACT, slide_start_s=START, slide_end_s=END)
    with pytest.raises(tp.RecordingError, match="stage current: no samples in the measurement window"):
        tp.traction(sparse)
    short_hold = tp.TrialRecording(pac_t=rec.pac_t, pac=rec.pac, pdc_t=rec.pdc_t, pdc=rec.pdc,
                                   current_t=rec.current_t, current_A=rec.current_A,
                                   contact_s=START - 0.05, slide_start_s=START, slide_end_s=END)
    with pytest.raises(tp.RecordingError, match="too short for a background window"):
        tp.roughness(short_hold)
    with pytest.raises(tp.RecordingError, match="must cover contact_s"):
        tp.TrialRecording(pac_t=rec.pac_t, pac=rec.pac, pdc_t=rec.pdc_t, pdc=rec.pdc, current_t=rec.current_t,
                          current_A=rec.current_A, contact_s=CONTACT, slide_start_s=START, slide_end_s=9.0)
    flat = make_trial(None, bg_sigma=0.0)
    with pytest.raises(tp.RecordingError, match="constant"):
        tp.fineness(flat)


def test_properties_records_what_the_codes_leave_undefined_and_raises_on_a_malformed_recording():
    """properties() is the one place that says a property is undefined: a PAC constant over the slide has no
    spectral centroid (fineness None, with the reason), while its roughness is the power floor and its traction a
    mean — numbers; a stage current with no sample in the window leaves traction undefined. A recording whose
    windows do not fit (a hold too short for the background window) is still an error, not a null."""
    flat = tp.properties(make_trial(None, bg_sigma=0.0))
    assert flat["fineness"] is None and "constant" in flat["undefined"]["fineness"]
    assert flat["roughness"] == pytest.approx(math.log(tp.POWER_FLOOR)) and flat["traction"] == pytest.approx(0.05)
    assert set(flat["undefined"]) == {"fineness"}
    rec = make_trial(None, bg_sigma=1.0)
    sparse = tp.properties(tp.TrialRecording(pac_t=rec.pac_t, pac=rec.pac, pdc_t=rec.pdc_t, pdc=rec.pdc,
                                             current_t=np.array([0.0, 3.9]), current_A=np.array([0.1, 0.1]),
                                             contact_s=CONTACT, slide_start_s=START, slide_end_s=END))
    assert sparse["traction"] is None and set(sparse["undefined"]) == {"traction"}
    assert "undefined" not in tp.properties(rec)
    short_hold = tp.TrialRecording(pac_t=rec.pac_t, pac=rec.pac, pdc_t=rec.pdc_t, pdc=rec.pdc,
                                   current_t=rec.current_t, current_A=rec.current_A,
                                   contact_s=START - 0.05, slide_start_s=START, slide_end_s=END)
    with pytest.raises(tp.RecordingError, match="too short for a background window"):
        tp.properties(short_hold)


def test_the_touchdown_transient_stays_out_of_the_background():
    """D measures the background during the hold, after contact: a 30 ms ring at touchdown (6 cycles of 200 Hz,
    zero mean) leaves the background power exactly as without it — the 50 ms guard covers the ring plus the FIR's
    15 ms half-length — and the sliding power too."""
    quiet = make_trial(bg_sigma=1.0, seed=4)
    n = int(round(0.03 * FS))
    ring_at = np.searchsorted(quiet.pac_t, CONTACT)
    pac = quiet.pac.copy()
    pac[ring_at:ring_at + n] += 40.0 * np.sin(2 * np.pi * 200.0 * np.arange(n) / FS)
    rung = tp.TrialRecording(pac_t=quiet.pac_t, pac=pac, pdc_t=quiet.pdc_t, pdc=quiet.pdc, current_t=quiet.current_t,
                             current_A=quiet.current_A, contact_s=CONTACT, slide_start_s=START, slide_end_s=END)
    assert tp.band_powers(rung) == pytest.approx(tp.band_powers(quiet), rel=1e-9)


def test_the_stage_starting_stays_out_of_the_background():
    """The background ends a guard before sliding starts: a 30 ms ring ending just as the stage starts (the slide's
    first stick-slip, a stage a latency early) leaves the background power exactly as without it — the 50 ms guard
    covers the ring plus the FIR's 15 ms half-length — so the sliding's own start never counts against it."""
    quiet = make_trial(bg_sigma=1.0, seed=5)
    n = int(round(0.03 * FS))
    start_at = np.searchsorted(quiet.pac_t, START)
    pac = quiet.pac.copy()
    pac[start_at - n:start_at] += 40.0 * np.sin(2 * np.pi * 200.0 * np.arange(n) / FS)
    rung = tp.TrialRecording(pac_t=quiet.pac_t, pac=pac, pdc_t=quiet.pdc_t, pdc=quiet.pdc, current_t=quiet.current_t,
                             current_A=quiet.current_A, contact_s=CONTACT, slide_start_s=START, slide_end_s=END)
    assert tp.band_powers(rung)[1] == pytest.approx(tp.band_powers(quiet)[1], rel=1e-9)

def test_each_segment_loses_its_own_mean_so_a_drifting_pac_keeps_its_centroid():
    """PAC drifting by 300 codes over the slide (a slow pressure change) under a 200 Hz tone: each 256-sample
    segment's own mean is removed before the taper, so the drift's step from segment to segment does not pile up at
    0 Hz and the centroid stays the tone's (194 Hz, ± 5 %); one mean for all segments drags it to 9 Hz."""
    rec = make_trial(lambda t, rng: 20 * np.sin(2 * np.pi * 200 * t) + 300 * (t - START) / (END - START))
    assert tp.spectral_centroid(rec) == pytest.approx(200.0, rel=0.05)


def test_pac_at_rails_counts_the_clipped_samples_of_the_measurement_window_only():
    """Roughness and fineness cannot see clipping; pac_at_rails says where the vibration hit code 0 or 4095."""
    rec = make_trial(lambda t, rng: 3000.0 * np.sign(np.sin(2 * np.pi * 50.0 * t)))  # ±3000 on 2048: both rails
    w = tp.measurement_window(rec)
    inside = (rec.pac_t >= w[0]) & (rec.pac_t <= w[1])
    clipped = np.clip(rec.pac, 0, 4095)
    rec = tp.TrialRecording(pac_t=rec.pac_t, pac=clipped, pdc_t=rec.pdc_t, pdc=rec.pdc, current_t=rec.current_t,
                            current_A=rec.current_A, contact_s=CONTACT, slide_start_s=START, slide_end_s=END)
    expected = int(((clipped[inside] == 0) | (clipped[inside] == 4095)).sum())
    assert expected > 0.9 * inside.sum() and tp.pac_at_rails(rec) == expected
    assert ((clipped == 0) | (clipped == 4095))[~inside].any()  # clipped outside the window too: not counted
    assert tp.pac_at_rails(make_trial(lambda t, rng: 1500.0 * np.sin(2 * np.pi * 50.0 * t))) == 0  # 548..3548


# ------------------------------------------------------------------------------------------ partial and broken clocks


def test_a_recording_of_pac_alone_has_roughness_and_fineness_and_says_why_traction_is_missing(tmp_path):
    """PDC is used by no property and the stage current only by traction (PROPERTY_NEEDS): a trial file holding PAC
    and the stage current loads and gives all three properties exactly as the full recording; one holding only PAC
    gives the same roughness and fineness, and traction None with the reason."""
    rec = make_trial(lambda t, rng: 10 * np.sin(2 * np.pi * 300 * t) + rng.standard_normal(t.size), bg_sigma=1.0,
                     current=lambda tc: 0.1 + 0.01 * tc)
    full = tp.properties(rec)
    a = _arrays(rec)
    del a["PDC_t"], a["PDC_code"]
    no_pdc = tp.load_npz(_write(tmp_path / "pac_and_current.npz", **a))
    assert no_pdc.pdc_t is None and no_pdc.pdc is None and tp.properties(no_pdc) == full
    del a["stage_current_t"], a["stage_current_A"]
    pac_only = tp.load_npz(_write(tmp_path / "pac.npz", **a))
    props = tp.properties(pac_only)
    assert (props["roughness"], props["fineness"]) == (full["roughness"], full["fineness"])
    assert props["traction"] is None and "stage current: not recorded" in props["undefined"]["traction"]
    assert set(props["undefined"]) == {"traction"}
    back = tp.load_npz(tp.save_npz(pac_only, tmp_path / "again"))  # saved without them, read back alike
    assert back.current_t is None and back.pdc is None and tp.properties(back) == props


@pytest.mark.parametrize("drop, named", [("PDC_code", "PDC_code (given with PDC_t"),
                                         ("stage_current_t", "stage_current_t (given with stage_current_A")])
def test_half_an_optional_pair_is_a_missing_array(tmp_path, drop, named):
    a = _arrays(make_trial(None, bg_sigma=1.0))
    del a[drop]
    with pytest.raises(tp.RecordingError, match=r"missing array\(s\): " + re.escape(named)):
        tp.load_npz(_write(tmp_path / "x.npz", **a))


@pytest.mark.parametrize("key", ["PAC_t", "PDC_t", "stage_current_t"])
def test_instants_going_back_name_the_array_and_the_index(tmp_path, key):
    """A restarted logger: the clock jumps back at one sample; the error names the array and that index."""
    a = _arrays(make_trial(None, bg_sigma=1.0))
    t = a[key].copy()
    t[7:] -= t[7] - t[2]  # sample 7 is stamped as sample 2 was: back by five intervals
    a[key] = t
    with pytest.raises(tp.RecordingError, match=rf"x\.npz: .*not strictly increasing: {key}\[7\] = .* after "
                                                rf"{key}\[6\] = ") as e:
        tp.load_npz(_write(tmp_path / "x.npz", **a))
    # the instants as numbers are written (0.0123 s), not as numpy's repr of its scalar (np.float64(0.0123) s)
    assert f"{key}[7] = {float(t[7])!r} s after {key}[6] = {float(t[6])!r} s" in str(e.value), str(e.value)


def test_a_pac_gap_inside_the_trial_leaves_the_spectral_properties_undefined_and_traction_alone(tmp_path):
    """Dropped frames while sliding: roughness and fineness are None, the reason naming PAC_t and the index after
    the gap; traction is the full recording's.  One lost sample is already a gap (2 intervals > 1.5); a time
    stamp late by 0.4 of an interval is jitter, not a gap, and changes nothing of the data."""
    rec = make_trial(lambda t, rng: 10 * np.sin(2 * np.pi * 300 * t), bg_sigma=1.0)
    a = _arrays(rec)
    k = int(np.searchsorted(rec.pac_t, 2.0))  # in the measurement window
    keep = np.arange(rec.pac_t.size) != k
    a["PAC_t"], a["PAC_code"] = rec.pac_t[keep], rec.pac[keep]
    gapped = tp.properties(tp.load_npz(_write(tmp_path / "gap.npz", **a)))
    assert gapped["roughness"] is None and gapped["fineness"] is None
    assert gapped["traction"] == tp.traction(rec)
    why = gapped["undefined"]["roughness"]
    assert why == gapped["undefined"]["fineness"] and f"PAC_t[{k}] = " in why and f"PAC_t[{k - 1}] = " in why
    jitter = rec.pac_t.copy()
    jitter[k] += 0.4 / FS
    a["PAC_t"], a["PAC_code"] = jitter, rec.pac
    assert tp.pac_gap(tp.load_npz(_write(tmp_path / "jitter.npz", **a))) is None


def test_the_gap_check_spans_contact_to_the_end_of_the_slide():
    """A gap in the hold (between contact and the background window's guard) counts; one just before contact or
    just after the slide (the approach, the lift) does not."""
    rec = make_trial(None, bg_sigma=1.0)

    def without(t0):
        keep = np.abs(rec.pac_t - t0) > 0.6 / FS  # the one sample nearest t0 lost
        return tp.TrialRecording(pac_t=rec.pac_t[keep], pac=rec.pac[keep], pdc_t=None, pdc=None,
                                 current_t=rec.current_t, current_A=rec.current_A, contact_s=CONTACT,
                                 slide_start_s=START, slide_end_s=END)

    assert tp.pac_gap(without(CONTACT + 0.01)) is not None
    assert tp.pac_gap(without(END - 0.01)) is not None
    assert tp.pac_gap(without(CONTACT - 0.01)) is None
    assert tp.pac_gap(without(END + 0.01)) is None
