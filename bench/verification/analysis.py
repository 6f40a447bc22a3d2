"""Measurements on recorded channels, as the dissertation made them (D ch. 5–6).

All functions take plain arrays: codes or values, sample instants in s, rates in Hz.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy import optimize, signal


# --- impact detection (D ch. 5) -----------------------------------------------------------
@dataclass
class DetectionRule:
    """More than ``min_points`` samples beyond ``n_sigma`` standard deviations within ``window_s``."""

    n_sigma: float = 4.0
    min_points: int = 3
    window_s: float = 0.1


def exceedances(x: np.ndarray, baseline: float, sigma: float, rule: DetectionRule = DetectionRule()) -> np.ndarray:
    """Boolean mask of samples beyond ``n_sigma``·``sigma`` from ``baseline``."""
    return np.abs(np.asarray(x, float) - baseline) > rule.n_sigma * sigma


def detected_in_window(x, times, t_start: float, baseline: float, sigma: float,
                       rule: DetectionRule = DetectionRule()) -> bool:
    """True if the window [t_start, t_start + window) holds more than ``min_points`` exceedances."""
    sel = (times >= t_start) & (times < t_start + rule.window_s)
    return int(np.count_nonzero(exceedances(x[sel], baseline, sigma, rule))) > rule.min_points


class StreamingDetector:
    """Counts detection events in a stream processed block by block (sliding window, carried state).

    An event is declared when a sliding window of ``window_s`` holds more than ``min_points``
    exceedances; a new event needs the window to have dropped back to ``min_points`` or fewer first.
    """

    def __init__(self, baseline: float, sigma: float, rate_Hz: float, rule: DetectionRule = DetectionRule()):
        self.baseline, self.sigma, self.rule = baseline, sigma, rule
        self.window_n = max(1, int(round(rule.window_s * rate_Hz)))
        self._tail = np.zeros(0, dtype=np.int64)  # exceedance flags of the last window_n - 1 samples
        self._armed = True
        self.events = 0
        self.samples = 0

    def update(self, x: np.ndarray) -> int:
        """Process the next samples; returns the number of new events."""
        flags = np.concatenate([self._tail, exceedances(x, self.baseline, self.sigma, self.rule).astype(np.int64)])
        c = np.concatenate([[0], np.cumsum(flags)])
        n_prev = self._tail.size
        # window ending at each new sample i (index in flags): flags[i-window_n+1 .. i]
        idx = np.arange(n_prev, flags.size)
        lo = np.maximum(idx - self.window_n + 1, 0)
        counts = c[idx + 1] - c[lo]
        above = counts > self.rule.min_points
        was_above = np.concatenate([[not self._armed], above[:-1]])
        new = int(np.count_nonzero(above & ~was_above))  # rising edges: the window just filled up
        if above.size:
            self._armed = not bool(above[-1])
        self._tail = flags[-(self.window_n - 1):] if self.window_n > 1 else flags[:0]
        self.events += new
        self.samples += len(x)
        return new


# --- fitting -------------------------------------------------------------------------------
@dataclass
class RingFit:
    amplitude: float
    decay_s: float
    frequency_Hz: float
    phase: float


def fit_decaying_sinusoid(t: np.ndarray, x: np.ndarray) -> RingFit:
    """Least-squares fit of A·exp(−t/τ)·sin(2πft + φ) to a ringing response starting at t = 0."""
    t, x = np.asarray(t, float), np.asarray(x, float)
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), n=8 * x.size))
    f_guess = np.fft.rfftfreq(8 * x.size, np.median(np.diff(t)))[np.argmax(spec[1:]) + 1]

    def model(t, a, tau, f, ph):
        return a * np.exp(-t / tau) * np.sin(2 * np.pi * f * t + ph)

    best = None
    for ph in np.linspace(0, 2 * np.pi, 8, endpoint=False):
        try:
            # some starting phases leave the covariance undefined (only p is used), and trial steps through a
            # negative τ overflow exp: such a step's residual is infinite and the solver steps back
            with warnings.catch_warnings(), np.errstate(over="ignore", invalid="ignore"):
                warnings.simplefilter("ignore", optimize.OptimizeWarning)
                p, _ = optimize.curve_fit(model, t, x, p0=[np.abs(x).max(), 0.02, f_guess, ph], maxfev=4000)
                r = float(np.sum((model(t, *p) - x) ** 2))
        except RuntimeError:
            continue
        if not np.isfinite(r):
            continue
        if best is None or r < best[0]:
            best = (r, p)
    if best is None:
        raise ValueError("no decaying sinusoid fits this signal")
    a, tau, f, ph = best[1]
    return RingFit(abs(a), abs(tau), abs(f), ph)


@dataclass
class LineFit:
    slope: float
    intercept: float
    r_squared: float


def fit_line(x, y) -> LineFit:
    x, y = np.asarray(x, float), np.asarray(y, float)
    slope, intercept = np.polyfit(x, y, 1)
    resid = y - (slope * x + intercept)
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(np.sum(resid**2)) / ss_tot if ss_tot > 0 else 0.0
    return LineFit(float(slope), float(intercept), r2)


def fit_proportional(x, y) -> LineFit:
    """Fit y = slope·x through the origin; R² against the mean as usual."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    slope = float(np.dot(x, y) / np.dot(x, x))
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(np.sum((y - slope * x) ** 2)) / ss_tot if ss_tot > 0 else 0.0
    return LineFit(slope, 0.0, r2)


# --- spectra (D ch. 5) ----------------------------------------------------------------------
def spectrum_1s(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Power per bin (units² per bin) of the first second of ``x``: Hann window, 1 Hz bins, Parseval-true."""
    n = int(round(fs))
    if len(x) < n:
        raise ValueError(f"need at least 1 s of samples ({n}), got {len(x)}")
    f, pxx = signal.periodogram(np.asarray(x[:n], float), fs=fs, window="hann", scaling="density", detrend="constant")
    return f, pxx * (f[1] - f[0])


def band_power_2hz(x: np.ndarray, fs: float, f_center: float) -> float:
    """Power in the 2 Hz band centred on ``f_center`` (bins within ±1 Hz) of a 1 s spectrum."""
    f, p = spectrum_1s(x, fs)
    return float(p[np.abs(f - f_center) <= 1.0 + 1e-9].sum())


def largest_2hz_band(x: np.ndarray, fs: float, f_min: float = 2.0) -> tuple[float, float]:
    """(frequency, power) of the 2 Hz band with most power in a 1 s spectrum, centred at ``f_min`` (Hz) or above."""
    f, p = spectrum_1s(x, fs)
    band = np.convolve(p, np.ones(3), mode="same")  # bins k-1, k, k+1 at 1 Hz spacing
    band[f < f_min] = 0.0
    band[-1] = 0.0
    k = int(np.argmax(band))
    return float(f[k]), float(band[k])


def peak_2hz_band_power(x: np.ndarray, fs: float, f_min: float = 2.0) -> tuple[float, float]:
    """(frequency, power) of the 2 Hz band around the spectral peak, as D ch. 5 measured P_1µm."""
    return largest_2hz_band(x, fs, f_min)


def minimum_detectable_amplitude(drive_m: float, p_drive_bits2: float, noise_band_bits2: float = 0.2) -> float:
    """D eq. 5.3: d_min = drive · √(2·background / P_drive); background 0.2 bits² gives the 0.4 of the source."""
    return drive_m * float(np.sqrt(2.0 * noise_band_bits2 / p_drive_bits2))


# --- spectral error (fidelity benchmark) -------------------------------------------------
def welch_db(x: np.ndarray, fs: float, nperseg: int = 1024) -> tuple[np.ndarray, np.ndarray]:
    f, p = signal.welch(np.asarray(x, float), fs=fs, nperseg=min(nperseg, len(x)))
    return f, 10 * np.log10(np.maximum(p, 1e-30))


# --- sliding: slip onset and a grating's harmonics (D ch. 3) --------------------------------
def causal_band_pass(x: np.ndarray, fs: float, lo: float, hi: float, order: int = 4) -> np.ndarray:
    """``x`` through a causal Butterworth band-pass ``lo``–``hi`` Hz (``order`` poles per edge), started in the
    steady state of ``x[0]``: its output at an instant depends only on what came before, so the power of a short
    window (a stick phase) takes nothing from the louder phase that follows it."""
    x = np.asarray(x, float)
    sos = signal.butter(order, [lo, hi], "bandpass", fs=fs, output="sos")
    return signal.sosfilt(sos, x, zi=signal.sosfilt_zi(sos) * x[0])[0]


@dataclass
class StickPhase:
    """Where the skin sticks while the stage already moves (s, on the instants of a force log)."""

    stage_start_s: float  # the first instant the stage moves
    last_stuck_s: float  # the last instant the skin still moves with the stage
    slip_onset_s: float  # the first instant the skin slips


def stick_phase(t: np.ndarray, stage_velocity: np.ndarray, slip_velocity: np.ndarray,
                slipping_fraction: float = 0.5) -> StickPhase:
    """The stick phase of a slide from its log (instants ``t`` in s, stage and slip velocity in m/s): from the
    first instant the stage moves to the last one before slip onset, the first instant the slip reaches
    ``slipping_fraction`` of the stage's velocity. ValueError if the stage never moves, the skin never slips,
    or it slips at once (no instant of stick)."""
    t, v, slip = (np.asarray(a, float) for a in (t, stage_velocity, slip_velocity))
    moving = v > 0
    if not moving.any():
        raise ValueError("the stage never moves: no stick phase")
    slipping = moving & (slip >= slipping_fraction * v)
    if not slipping.any():
        raise ValueError("the skin never slips: no slip onset")
    onset = int(np.argmax(slipping))
    stuck = np.flatnonzero(moving[:onset])
    if not stuck.size:
        raise ValueError(f"the skin slips at the stage's first move ({t[onset]:.4g} s): no stick phase")
    return StickPhase(float(t[stuck[0]]), float(t[onset - 1]), float(t[onset]))


def ramp_ratio(force: np.ndarray, floor_fraction: float = 1e-3) -> float:
    """How much a force builds up over a phase (samples in time order): its last value over its first if a
    least-squares line through the samples rises (by more than rounding), else 0 (a flat or falling force). A
    first value below ``floor_fraction`` of the last counts as that fraction (the ratio is at most
    1/floor_fraction)."""
    f = np.asarray(force, float)
    if f.size < 3:
        raise ValueError(f"a ramp needs at least 3 samples, got {f.size}")
    rise = np.polyfit(np.arange(f.size), f, 1)[0] * (f.size - 1)
    if not (rise > 1e-9 * np.max(np.abs(f)) and f[-1] > 0):
        return 0.0
    return float(f[-1] / max(f[0], floor_fraction * f[-1]))


def harmonic_levels_db(x: np.ndarray, fs: float, f0: float, orders, tolerance: float = 0.05,
                       nperseg: int | None = None) -> dict[int, float]:
    """Level (dB) of each harmonic ``n·f0`` (n in ``orders``) of ``x`` over the local spectral floor: the Welch
    spectrum's largest bin within ± ``tolerance`` of ``n·f0`` (at least ± 2 bins, the Hann main lobe) over the
    median of the bins within ± f0/2 of ``n·f0`` outside that band (the floor between the neighbouring
    harmonics). Segments of ``nperseg`` samples (default: the power of two giving bins ≤ f0/8)."""
    x = np.asarray(x, float)
    if nperseg is None:
        nperseg = 1 << int(np.ceil(np.log2(8 * fs / f0)))
    if nperseg > x.size:
        raise ValueError(f"{x.size} samples are fewer than one {nperseg}-sample segment: resolve f0 = {f0:.4g} Hz "
                         "with a longer record")
    f, p = signal.welch(x, fs=fs, nperseg=nperseg, detrend="constant")
    df = f[1] - f[0]
    levels = {}
    for n in orders:
        centre = n * f0
        line = np.abs(f - centre) <= max(tolerance * centre, 2 * df)
        floor = (np.abs(f - centre) <= f0 / 2) & ~line
        if centre + f0 / 2 > f[-1] or floor.sum() < 4:
            raise ValueError(f"harmonic {n} of {f0:.4g} Hz: too few bins of floor beside it ({floor.sum()}; bins "
                             f"{df:.3g} Hz, Nyquist {f[-1]:.4g} Hz)")
        levels[int(n)] = float(10 * np.log10(p[line].max() / np.median(p[floor])))
    return levels
