"""The three texture properties of D ch. 6 — traction, roughness, fineness — from one trial's recorded data.

The functions take a :class:`TrialRecording`: PAC and PDC codes with their instants, the linear stage's motor
current, and the instants of the trial's phases. A recording can come from the emulator or from a real rig, as
long as it is in this layout (:func:`save_npz` / :func:`load_npz` document the file format).

Phases of a trial (D Fig. 6-4)::

    finger lowered ──► contact_s ── hold (stepper locked) ──► slide_start_s ── sliding ──► slide_end_s
                         └── background window ──┘                └─ measurement window ─┘

* **measurement window**: the part of the slide the properties are computed over. D: it "occurs shortly after
  the sliding [starts] and stops before the sliding is completed"; before it the motor current "is initially
  high due to the acceleration of the linear stage". D gives no numbers; here it is
  ``[slide_start + lead·D, slide_end − tail·D]`` with ``D`` the slide duration, ``lead = 0.2`` (past the stage's
  acceleration at every velocity of the 1–10 cm/s grid) and ``tail = 0.1`` (clear of the deceleration).
* **background window**: the hold between reaching the target force and the start of sliding, shortened by
  ``guard_s = 0.05`` s at both ends so neither the end of the approach nor the onset of sliding leaks in through
  the band-pass filter (its half-length is 33 samples = 15 ms at 2.2 kS/s).

Definitions (D eqs 6.14–6.19):

* **traction** (A) = mean stage motor current over the measurement window (D 6.14: traction ∝ motor current; the
  current rises linearly with normal force while sliding at constant velocity, so the accelerating start is
  excluded). Plain mean of the current samples inside the window.
* **roughness** = ln(Power − background), D 6.15–6.16, with ``Power = (1/N) Σ PAC_filt(n)²`` over the
  measurement window, ``background`` the same power over the background window, and ``PAC_filt`` PAC (codes,
  mean removed) through a 20–700 Hz band-pass FIR of order 66 (67 taps; :func:`roughness_filter`). Units of the
  power: bits² (PAC codes). The log is natural (MATLAB's ``log``, in which D analysed the data; another base
  only rescales the property). A difference ≤ ``power_floor`` (default 1e-3 bits², far below the 1/12 bits²
  of ADC quantisation, so no measurable vibration is clipped) is replaced by ``power_floor``: the result is
  always finite.
* **fineness** = ln(SC), D 6.18–6.19, with SC (Hz) the spectral centroid ``Σ|FFT|²·f / Σ|FFT|²`` of the
  *unfiltered* PAC (D Fig. 6-4 C) over the measurement window. D: "a sliding window was used to collect the
  Fourier transform at different sections of the signal, which were averaged and used for the spectral
  centroid estimation" — so the power spectra of the windows are averaged and the centroid is taken of the
  average (not an average of per-window centroids). D gives no window length: here 256 samples (116 ms at
  2.2 kS/s, 8.6 Hz bins), 50 % overlap, each segment mean-removed and Hann-tapered (the PAC code carries a
  mid-scale offset whose DC bin would otherwise dominate; the taper limits leakage). All bins 0…fs/2 count.

Samples are taken as uniformly spaced; the sampling rate is 1 / median spacing of the instants.  Instants that
do not strictly increase (a restarted logger, frames written out of order) make the recording malformed: the error
names the array and the index.  A PAC gap — two successive instants more than :data:`MAX_GAP_INTERVALS` (1.5) median
spacings apart, i.e. at least one sample lost — between ``contact_s`` and ``slide_end_s`` (where every window the
properties use lies) leaves roughness and fineness undefined (:func:`pac_gap`; :func:`properties` gives None and the
gap): the band-pass filter and the spectra would run across the join as if the samples were adjacent, and filling
the gap in would invent vibration.  Traction, a plain mean of current readings, does not need uniform spacing and
stays defined.  1.5 spacings because one lost sample already makes an interval of 2, while a logger's time stamps
may jitter by a fraction of an interval without anything being lost.  A gap before contact or after the slide
(the approach, the lift) touches no window and is allowed.

What each property needs of a recording (:data:`PROPERTY_NEEDS`): traction the stage current; roughness and
fineness PAC only.  PDC is not used by any of them (it is kept for the rig's force control and for plots), so a
recording may leave it out; one without the stage current has roughness and fineness but no traction.
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy import signal

from bench.errors import BenchError

#: Order of the roughness band-pass FIR (D: "66th order FIR"): 67 taps.
FIR_ORDER = 66
#: Band edges of the roughness filter (Hz), D: "20-700Hz digital band-pass filter".
BAND_HZ = (20.0, 700.0)
#: Default measurement window: fractions of the slide duration skipped at its start and end.
MEASURE_LEAD, MEASURE_TAIL = 0.2, 0.1
#: Default guard (s) trimmed from both ends of the hold to form the background window.
BACKGROUND_GUARD_S = 0.05
#: Floor (bits²) for the background-subtracted vibration power.
POWER_FLOOR = 1e-3
#: Spectral-centroid segments: length (samples) and overlap (fraction).
CENTROID_WINDOW, CENTROID_OVERLAP = 256, 0.5
#: The 12-bit ADC's lowest and highest codes: a PAC sample at either is clipped (the vibration went there or beyond).
PAC_RAILS = (0, 4095)
#: Layout tag written into every trial file.
NPZ_FORMAT = "biotac-bench trial recording v1"
#: Arrays every trial file holds (see :func:`save_npz`).
NPZ_REQUIRED = ("PAC_t", "PAC_code")
#: Pairs of arrays a trial file may leave out (both or neither), each with what cannot be computed without it.
NPZ_OPTIONAL = {("PDC_t", "PDC_code"): "nothing of the three properties (PDC is not used by them)",
                ("stage_current_t", "stage_current_A"): "traction (the mean stage motor current)"}
NPZ_SCALARS = ("contact_s", "slide_start_s", "slide_end_s")
#: Which recorded series each property is computed from.
PROPERTY_NEEDS = {"traction": ("stage current",), "roughness": ("PAC",), "fineness": ("PAC",)}
#: A PAC interval longer than this many median spacings is a gap (samples lost): see the module's docstring.
MAX_GAP_INTERVALS = 1.5


class RecordingError(BenchError, ValueError):
    """A trial recording is malformed (missing or bad array, inconsistent phases, windows without data)."""


class UndefinedProperty(RecordingError):
    """A property that this trial's codes leave without a value, the recording itself being sound: no valid sample
    in a window (the host rejected every word there), or a PAC constant over the measurement window (no spectral
    centroid). :func:`properties` records it as None with this reason."""


def _series(name: str, key: str, t: Any, x: Any) -> tuple[np.ndarray, np.ndarray]:
    """Validate one (instants, values) pair: 1-D, same length, non-empty, finite, instants strictly increasing
    (``key``: the instants' name in a trial file, ``PAC_t``, which the error for a step back names with its index)."""
    try:
        t = np.asarray(t, dtype=np.float64)
        x = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise RecordingError(f"{name}: not numeric ({e})") from None
    if t.ndim != 1 or x.ndim != 1:
        raise RecordingError(f"{name}: instants and values must be 1-D (got shapes {t.shape} and {x.shape})")
    if t.size != x.size:
        raise RecordingError(f"{name}: {t.size} instants but {x.size} values")
    if t.size == 0:
        raise RecordingError(f"{name}: empty")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise RecordingError(f"{name}: contains NaN or infinite values")
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        k = int(back[0]) + 1
        raise RecordingError(f"{name}: instants are not strictly increasing: {key}[{k}] = {float(t[k])!r} s after "
                             f"{key}[{k - 1}] = {float(t[k - 1])!r} s (a restarted logger, or frames out of order?)")
    return t, x


@dataclass(frozen=True)
class TrialRecording:
    """One exploratory trial: what the sensor and the stage recorded, and when the phases began.

    ``pac_t``/``pac`` — PAC instants (s) and 12-bit codes (2.2 kS/s in the default frame);
    ``pdc_t``/``pdc`` — PDC instants (s) and codes, or both None (no property uses PDC);
    ``current_t``/``current_A`` — stage motor current instants (s) and current (A), or both None (then traction is
    undefined); ``contact_s`` — the finger reached the target force (the stepper stops); ``slide_start_s`` /
    ``slide_end_s`` — the stage starts / stops sliding. All instants share one clock (s).
    Metadata (free, not used by the computations): ``texture`` (id or name), ``force_N``, ``velocity_m_s``,
    ``trial`` (repetition number), ``seed``, and ``extra`` (any JSON-serialisable dict).
    Arrays are converted to float64 and validated on construction (:class:`RecordingError` names the problem).
    """

    pac_t: np.ndarray
    pac: np.ndarray
    pdc_t: np.ndarray | None
    pdc: np.ndarray | None
    current_t: np.ndarray | None
    current_A: np.ndarray | None
    contact_s: float
    slide_start_s: float
    slide_end_s: float
    texture: int | str | None = None
    force_N: float | None = None
    velocity_m_s: float | None = None
    trial: int | None = None
    seed: int | None = None
    extra: dict = field(default_factory=dict)

    def __post_init__(self):
        for name, (tf, xf, key) in {"PAC": ("pac_t", "pac", "PAC_t"), "PDC": ("pdc_t", "pdc", "PDC_t"),
                                    "stage current": ("current_t", "current_A", "stage_current_t")}.items():
            if name != "PAC" and getattr(self, tf) is None and getattr(self, xf) is None:
                continue  # not recorded (the module's docstring: what each property needs)
            if name != "PAC" and (getattr(self, tf) is None or getattr(self, xf) is None):
                raise RecordingError(f"{name}: {tf} and {xf} are given both or neither (one of them is None)")
            t, x = _series(name, key, getattr(self, tf), getattr(self, xf))
            object.__setattr__(self, tf, t)
            object.__setattr__(self, xf, x)
        phases = {}
        for name in NPZ_SCALARS:
            try:
                v = float(getattr(self, name))
            except (TypeError, ValueError):
                raise RecordingError(f"{name}: not a number ({getattr(self, name)!r})") from None
            if not math.isfinite(v):
                raise RecordingError(f"{name}: not finite ({v})")
            phases[name] = v
            object.__setattr__(self, name, v)
        if not phases["contact_s"] <= phases["slide_start_s"] < phases["slide_end_s"]:
            raise RecordingError(
                "phases must satisfy contact_s <= slide_start_s < slide_end_s (got "
                + ", ".join(f"{k}={v}" for k, v in phases.items()) + ")")
        covered = self.pac_t[0] <= phases["contact_s"] and phases["slide_end_s"] <= self.pac_t[-1]
        if self.pac_t.size < 2 or not covered:
            raise RecordingError(
                f"PAC ({self.pac_t[0]:.4g}…{self.pac_t[-1]:.4g} s) must cover contact_s…slide_end_s "
                f"({phases['contact_s']:.4g}…{phases['slide_end_s']:.4g} s)")

    @functools.cached_property
    def pac_rate_hz(self) -> float:
        """PAC sampling rate (Hz): 1 / median spacing of the instants (computed once: the record is frozen)."""
        return 1.0 / float(np.median(np.diff(self.pac_t)))

    def metadata(self) -> dict:
        """The free metadata as a JSON-serialisable dict."""
        return {"texture": self.texture, "force_N": self.force_N, "velocity_m_s": self.velocity_m_s,
                "trial": self.trial, "seed": self.seed, "extra": self.extra}


def save_npz(rec: TrialRecording, path: str | Path) -> Path:
    """Write ``rec`` to ``path`` (compressed NPZ; ".npz" added when the name lacks it) and return the path; the file
    is written whole or not at all (:func:`bench.atomic.atomic_write`: an earlier file there stays as it was).

    Layout: ``PAC_t``, ``PDC_t``, ``stage_current_t`` — instants (s, float64); ``PAC_code``, ``PDC_code`` — codes
    (float64; integers for real 12-bit data); ``stage_current_A`` — motor current (A); ``contact_s``,
    ``slide_start_s``, ``slide_end_s`` — 0-d float64 (s); ``meta_json`` — 0-d string, the JSON of
    :meth:`TrialRecording.metadata`; ``format`` — 0-d string :data:`NPZ_FORMAT`.  The PDC pair and the stage
    current pair are left out when the recording has none (:data:`NPZ_OPTIONAL`).  The PAC/PDC names match the
    ``codes.npz`` a scene run writes.
    """
    from bench.atomic import atomic_write

    path = Path(path)
    final = path if path.suffix == ".npz" else path.with_name(path.name + ".npz")
    optional = {k: v for k, v in (("PDC_t", rec.pdc_t), ("PDC_code", rec.pdc), ("stage_current_t", rec.current_t),
                                  ("stage_current_A", rec.current_A)) if v is not None}
    with atomic_write(final) as tmp, open(tmp, "wb") as out:  # whole or not at all: an earlier file stays if it fails
        np.savez_compressed(
            out, PAC_t=rec.pac_t, PAC_code=rec.pac, **optional,
            contact_s=np.float64(rec.contact_s), slide_start_s=np.float64(rec.slide_start_s),
            slide_end_s=np.float64(rec.slide_end_s), meta_json=np.array(json.dumps(rec.metadata())),
            format=np.array(NPZ_FORMAT))
    return final


def load_npz(path: str | Path) -> TrialRecording:
    """Read a trial written by :func:`save_npz` (or by anything producing the same layout).

    ``meta_json`` and ``format`` are optional, and so are the PDC pair and the stage current pair
    (:data:`NPZ_OPTIONAL`: a pair is given whole or not at all; without the stage current there is no traction);
    PAC and the phases are required.  Raises :class:`RecordingError` naming each missing key, or the malformed array
    (instants that do not strictly increase: the array and the index).  PAC gaps are not an error here: they leave
    roughness and fineness undefined (:func:`pac_gap`).
    """
    try:
        data = np.load(Path(path), allow_pickle=False)
    except (OSError, ValueError) as e:
        raise RecordingError(f"{path}: cannot read as NPZ ({e})") from None
    with data:
        missing = [k for k in NPZ_REQUIRED + NPZ_SCALARS if k not in data.files]
        for pair, lost in NPZ_OPTIONAL.items():
            absent = [k for k in pair if k not in data.files]
            if len(absent) == 1:
                missing.append(f"{absent[0]} (given with {pair[pair.index(absent[0]) - 1]}; without both, {lost} "
                               "cannot be computed)")
        if missing:
            raise RecordingError(f"{path}: missing array(s): {', '.join(missing)}")
        arrays = {k: data[k] if k in data.files else None
                  for k in ("PDC_t", "PDC_code", "stage_current_t", "stage_current_A")}
        if "format" in data.files and str(data["format"]) != NPZ_FORMAT:
            raise RecordingError(f"{path}: format is {str(data['format'])!r}, expected {NPZ_FORMAT!r}")
        for k in NPZ_SCALARS:
            if data[k].shape not in ((), (1,)):
                raise RecordingError(f"{path}: {k} must be a scalar (got shape {data[k].shape})")
        meta: dict = {}
        if "meta_json" in data.files:
            try:
                meta = json.loads(str(data["meta_json"]))
            except json.JSONDecodeError as e:
                raise RecordingError(f"{path}: meta_json is not valid JSON ({e})") from None
            if not isinstance(meta, dict):
                raise RecordingError(f"{path}: meta_json must hold an object")
        known = ("texture", "force_N", "velocity_m_s", "trial", "seed", "extra")
        kwargs = {k: meta[k] for k in known if k in meta and meta[k] is not None}
        try:
            return TrialRecording(
                pac_t=data["PAC_t"], pac=data["PAC_code"], pdc_t=arrays["PDC_t"], pdc=arrays["PDC_code"],
                current_t=arrays["stage_current_t"], current_A=arrays["stage_current_A"],
                contact_s=data["contact_s"].reshape(()), slide_start_s=data["slide_start_s"].reshape(()),
                slide_end_s=data["slide_end_s"].reshape(()), **kwargs)
        except RecordingError as e:
            raise RecordingError(f"{path}: {e}") from None


# ---------------------------------------------------------------------------------------------------- windows


def measurement_window(rec: TrialRecording, lead: float = MEASURE_LEAD,
                       tail: float = MEASURE_TAIL) -> tuple[float, float]:
    """(start, end) instants (s) of the measurement window: the slide minus ``lead``/``tail`` of its duration."""
    if not (0.0 <= lead and 0.0 <= tail and lead + tail < 1.0):
        raise ValueError(f"lead={lead}, tail={tail}: need lead, tail >= 0 and lead + tail < 1")
    d = rec.slide_end_s - rec.slide_start_s
    return rec.slide_start_s + lead * d, rec.slide_end_s - tail * d


def background_window(rec: TrialRecording, guard_s: float = BACKGROUND_GUARD_S) -> tuple[float, float]:
    """(start, end) instants (s) of the background window: the hold minus ``guard_s`` at both ends."""
    t0, t1 = rec.contact_s + guard_s, rec.slide_start_s - guard_s
    if not t1 > t0:
        raise RecordingError(
            f"the hold ({rec.contact_s:.4g}…{rec.slide_start_s:.4g} s) is too short for a background window "
            f"with guard {guard_s} s at both ends")
    return t0, t1


def _in(t: np.ndarray, window: tuple[float, float]) -> np.ndarray:
    return (t >= window[0]) & (t <= window[1])


def pac_gap(rec: TrialRecording) -> str | None:
    """The first PAC gap between ``contact_s`` and ``slide_end_s`` — an interval longer than
    :data:`MAX_GAP_INTERVALS` median spacings, samples lost there — said in words (the array, the index, the
    instants, the gap and the tolerance, s), or None.  The module's docstring says why roughness and fineness are
    then undefined."""
    first, last = np.searchsorted(rec.pac_t, [rec.contact_s, rec.slide_end_s], side="left")
    lo, hi = max(int(first) - 1, 0), min(int(last) + 1, rec.pac_t.size)  # the intervals that reach into the span
    dt = np.diff(rec.pac_t[lo:hi])
    limit = MAX_GAP_INTERVALS / rec.pac_rate_hz
    wide = np.flatnonzero(dt > limit)
    if not wide.size:
        return None
    k = lo + int(wide[0]) + 1
    return (f"PAC has a gap between contact_s and slide_end_s: PAC_t[{k}] = {rec.pac_t[k]:.6g} s is "
            f"{dt[wide[0]]:.4g} s after PAC_t[{k - 1}] = {rec.pac_t[k - 1]:.6g} s, more than {MAX_GAP_INTERVALS:g} "
            f"median spacings ({limit:.4g} s): samples were lost, and the filter and spectra would join across it")


# ---------------------------------------------------------------------------------------------------- properties


def roughness_filter(fs_hz: float, order: int = FIR_ORDER, band_hz: tuple[float, float] = BAND_HZ) -> np.ndarray:
    """Taps (``order + 1``) of the roughness band-pass: a Hamming-windowed linear-phase FIR, as MATLAB's
    ``fir1(66, [20 700]/(fs/2))``, unity gain at the band centre. With 67 taps at 2.2 kS/s the edges are soft
    (−6 dB at 20 and 700 Hz; 0.41 at DC, which is why PAC's mean is removed before filtering; < 0.01 beyond
    750 Hz)."""
    if not band_hz[1] < fs_hz / 2:
        raise RecordingError(f"PAC sampled at {fs_hz:.1f} Hz: the {band_hz[1]} Hz band edge is above Nyquist")
    return _fir_taps(fs_hz, order, tuple(band_hz)).copy()


@functools.lru_cache(maxsize=16)
def _fir_taps(fs_hz: float, order: int, band_hz: tuple) -> np.ndarray:
    """:func:`roughness_filter`'s taps, designed once per (rate Hz, order, band Hz) and kept read-only."""
    taps = signal.firwin(order + 1, list(band_hz), pass_zero=False, window="hamming", fs=fs_hz)
    taps.setflags(write=False)
    return taps


def _centred_convolution(x: np.ndarray, h: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """``np.convolve(x, h, "same")[lo:hi]``, computed only there where the filter lies wholly inside ``x`` (the
    same dot products, so the same values), else over the whole of ``x``."""
    left, right = h.size - 1 - (h.size - 1) // 2, (h.size - 1) // 2
    if lo - left >= 0 and hi + right <= x.size and x.size >= h.size:
        return np.convolve(x[lo - left:hi + right], h, mode="valid")
    return np.convolve(x, h, mode="same")[lo:hi]


def traction(rec: TrialRecording, lead: float = MEASURE_LEAD, tail: float = MEASURE_TAIL) -> float:
    """Traction (A): the mean stage motor current over the measurement window (D eq. 6.14); undefined for a
    recording without the stage current."""
    if rec.current_t is None:
        raise UndefinedProperty("stage current: not recorded, so traction (the mean motor current) is undefined")
    w = measurement_window(rec, lead, tail)
    sel = _in(rec.current_t, w)
    if not sel.any():
        raise UndefinedProperty(f"stage current: no samples in the measurement window {w[0]:.4g}…{w[1]:.4g} s")
    return float(rec.current_A[sel].mean())


def band_powers(rec: TrialRecording, lead: float = MEASURE_LEAD, tail: float = MEASURE_TAIL,
                guard_s: float = BACKGROUND_GUARD_S) -> tuple[float, float]:
    """(sliding power, background power) of band-passed PAC (bits²): mean square over each window.

    PAC's mean is removed, the record is filtered with :func:`roughness_filter` (zero-phase alignment: centred
    convolution of the whole record, i.e. the 33-sample delay compensated; evaluated only inside the windows),
    then each window's samples are averaged.
    """
    gap = pac_gap(rec)
    if gap:
        raise UndefinedProperty(gap)
    h = roughness_filter(rec.pac_rate_hz)
    x = rec.pac - rec.pac.mean()
    out = []
    windows = (("measurement", measurement_window(rec, lead, tail)), ("background", background_window(rec, guard_s)))
    for name, w in windows:
        inside = np.flatnonzero(_in(rec.pac_t, w))  # (instants increase: one run of samples)
        if not inside.size:
            raise UndefinedProperty(f"PAC: no samples in the {name} window {w[0]:.4g}…{w[1]:.4g} s")
        out.append(float(np.mean(_centred_convolution(x, h, int(inside[0]), int(inside[-1]) + 1) ** 2)))
    return out[0], out[1]


def roughness(rec: TrialRecording, lead: float = MEASURE_LEAD, tail: float = MEASURE_TAIL,
              guard_s: float = BACKGROUND_GUARD_S, power_floor: float = POWER_FLOOR) -> float:
    """Roughness = ln(max(P_slide − P_background, power_floor)), powers in bits² (D eqs 6.15–6.16)."""
    if not power_floor > 0:
        raise ValueError(f"power_floor must be > 0 (got {power_floor})")
    p, bg = band_powers(rec, lead, tail, guard_s)
    return float(math.log(max(p - bg, power_floor)))


def averaged_spectrum(x: np.ndarray, fs_hz: float, window: int = CENTROID_WINDOW,
                      overlap: float = CENTROID_OVERLAP) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies (Hz), mean |FFT|² over segments) of ``x``: segments of ``window`` samples (or the whole of
    ``x`` if shorter) stepping by ``window·(1 − overlap)``, each mean-removed and Hann-tapered."""
    if not 0.0 <= overlap < 1.0:
        raise ValueError(f"overlap must be in [0, 1) (got {overlap})")
    x = np.asarray(x, dtype=np.float64)
    n = min(int(window), x.size)
    if n < 2:
        raise UndefinedProperty(f"PAC: {x.size} sample(s) in the measurement window; need at least 2")
    step = max(1, int(round(n * (1.0 - overlap))))
    seg = np.lib.stride_tricks.sliding_window_view(x, n)[::step]
    seg = (seg - seg.mean(axis=1, keepdims=True)) * _hann(n)  # periodic Hann
    power = (np.abs(np.fft.rfft(seg, axis=1)) ** 2).mean(axis=0)
    return np.fft.rfftfreq(n, 1.0 / fs_hz), power


@functools.lru_cache(maxsize=8)
def _hann(n: int) -> np.ndarray:
    """The periodic Hann window of ``n`` samples (scipy's ``get_window("hann", n)``), read-only."""
    w = signal.get_window("hann", n)
    w.setflags(write=False)
    return w


def spectral_centroid(rec: TrialRecording, lead: float = MEASURE_LEAD, tail: float = MEASURE_TAIL,
                      window: int = CENTROID_WINDOW, overlap: float = CENTROID_OVERLAP) -> float:
    """Spectral centroid (Hz) Σ|FFT|²·f / Σ|FFT|² of unfiltered PAC over the measurement window (D eq. 6.18)."""
    gap = pac_gap(rec)
    if gap:
        raise UndefinedProperty(gap)
    w = measurement_window(rec, lead, tail)
    f, p = averaged_spectrum(rec.pac[_in(rec.pac_t, w)], rec.pac_rate_hz, window, overlap)
    total = p.sum()
    if not total > 0:
        raise UndefinedProperty(f"PAC is constant over the measurement window {w[0]:.4g}…{w[1]:.4g} s: "
                             "spectral centroid undefined")
    return float((p * f).sum() / total)


def fineness(rec: TrialRecording, lead: float = MEASURE_LEAD, tail: float = MEASURE_TAIL,
             window: int = CENTROID_WINDOW, overlap: float = CENTROID_OVERLAP) -> float:
    """Fineness = ln(spectral centroid / 1 Hz) (D eq. 6.19)."""
    return float(math.log(spectral_centroid(rec, lead, tail, window, overlap)))


def pac_at_rails(rec: TrialRecording, lead: float = MEASURE_LEAD, tail: float = MEASURE_TAIL) -> int:
    """PAC samples at the ADC's rails (:data:`PAC_RAILS`) in the measurement window: where they are not 0, the
    roughness and fineness are of a clipped vibration (the properties do not see it; a reader of them should)."""
    x = rec.pac[_in(rec.pac_t, measurement_window(rec, lead, tail))]
    return int(np.count_nonzero((x <= PAC_RAILS[0]) | (x >= PAC_RAILS[1])))


def properties(rec: TrialRecording, lead: float = MEASURE_LEAD, tail: float = MEASURE_TAIL,
               guard_s: float = BACKGROUND_GUARD_S, power_floor: float = POWER_FLOOR,
               window: int = CENTROID_WINDOW, overlap: float = CENTROID_OVERLAP) -> dict:
    """All three properties of one trial: ``{"traction": A, "roughness": ln bits², "fineness": ln Hz}``.

    A property this trial's codes leave undefined (:class:`UndefinedProperty`) is None, and the dict then holds
    ``"undefined": {name: why}``; a malformed recording or window still raises :class:`RecordingError`."""
    measures = {"traction": lambda: traction(rec, lead, tail),
                "roughness": lambda: roughness(rec, lead, tail, guard_s, power_floor),
                "fineness": lambda: fineness(rec, lead, tail, window, overlap)}
    out, undefined = {}, {}
    for name, measure in measures.items():
        try:
            out[name] = measure()
        except UndefinedProperty as e:
            out[name], undefined[name] = None, str(e)
    if undefined:
        out["undefined"] = undefined
    return out
