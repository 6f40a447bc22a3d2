"""Analog prototypes discretized stage by stage and run as second-order sections.

Every filter in the emulator is designed as analog zeros/poles/gain (rad/s),
discretized by one of the methods below, and run with ``scipy.signal.sosfilt``
carrying its state ``zi`` between blocks, so output never depends on block size.
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit
from scipy import signal

try:  # the C routine behind scipy.signal.lfilter (scipy is pinned; see lfilter below)
    from scipy.signal._sigtools import _linear_filter
except ImportError:  # pragma: no cover - another scipy layout: the public function does the same
    _linear_filter = None

DISCRETIZATIONS = ("bilinear", "prewarped", "matched")


#: Roots above this fraction of the sample rate cannot be prewarped (tan diverges at Nyquist).
PREWARP_LIMIT = 0.49


def _prewarp(roots: np.ndarray, fs: float) -> np.ndarray:
    """Move each analog root so that its natural frequency survives the bilinear map exactly.

    Roots at or above ``PREWARP_LIMIT``·fs have no in-band image; they are left for the plain
    bilinear map, which still places them stably (their effect is confined to the top of the band).
    """
    roots = np.asarray(roots, complex)
    mag = np.abs(roots)
    out = roots.copy()
    ok = (mag > 0) & (mag < 2 * np.pi * PREWARP_LIMIT * fs)
    out[ok] = roots[ok] / mag[ok] * (2.0 * fs * np.tan(mag[ok] / (2.0 * fs)))
    return out


def discretize(z, p, k, fs: float, method: str, gain_at_hz: float = 0.0) -> np.ndarray:
    """Discrete SOS for the analog filter (z, p, k) in rad/s at sample rate ``fs`` (Hz), read-only: designs are
    remembered, so sensors built one after another (a rig's trials) design each filter once."""
    key = (tuple(np.atleast_1d(np.asarray(z, complex)).tolist()), tuple(np.atleast_1d(np.asarray(p, complex)).tolist()),
           float(k), float(fs), method, float(gain_at_hz))
    return _discretize_cached(*key)


@functools.lru_cache(maxsize=256)
def _discretize_cached(z: tuple, p: tuple, k: float, fs: float, method: str, gain_at_hz: float) -> np.ndarray:
    sos = _design(np.array(z, complex), np.array(p, complex), k, fs, method, gain_at_hz)
    sos.setflags(write=False)
    return sos


def _design(z, p, k, fs: float, method: str, gain_at_hz: float) -> np.ndarray:
    """Discrete SOS for the analog filter (z, p, k) in rad/s at sample rate ``fs`` (Hz).

    ``bilinear``: plain Tustin transform (corners near Nyquist are warped down).
    ``prewarped``: every pole and zero is prewarped before Tustin, so each corner lands where it should.
    ``matched``: matched-z (s = r -> z = exp(r/fs)); zeros at infinity go to z = -1.
    The gain is then matched to the analog response at ``gain_at_hz``.
    """
    z = np.atleast_1d(np.asarray(z, complex))
    p = np.atleast_1d(np.asarray(p, complex))
    if method == "bilinear":
        zd, pd, kd = signal.bilinear_zpk(z, p, k, fs)
    elif method == "prewarped":
        zd, pd, kd = signal.bilinear_zpk(_prewarp(z, fs), _prewarp(p, fs), k, fs)
    elif method == "matched":
        zd = np.concatenate([np.exp(z / fs), -np.ones(len(p) - len(z))])
        pd = np.exp(p / fs)
        kd = 1.0
    else:
        raise ValueError(f"unknown discretization {method!r}; choose one of {DISCRETIZATIONS}")
    w_analog = 2 * np.pi * gain_at_hz
    _, h_analog = signal.freqs_zpk(z, p, k, worN=[w_analog])
    _, h_digital = signal.freqz_zpk(zd, pd, kd, worN=[gain_at_hz], fs=fs)
    kd = kd * np.abs(h_analog[0]) / np.abs(h_digital[0])
    return signal.zpk2sos(zd, pd, kd)


@njit(cache=True, nogil=True)
def _df2t(b, a, x, z):  # pragma: no cover - compiled (coverage does not see inside)
    """One section of 2 or 3 taps (a[0] = 1) in lfilter's direct form II transposed, operation for operation as its
    C loop does them (y = z0 + b0·x; z0 = (z1 + x·b1) − y·a1; z1 = x·b2 − y·a2), so the same bits; ``z`` is
    updated in place.  Compiled: a tight loop keeps the state in registers (2.5 ns a sample against 6-7)."""
    n = x.size
    y = np.empty(n)
    if b.size == 3:
        z0, z1 = z[0], z[1]
        b0, b1, b2, a1, a2 = b[0], b[1], b[2], a[1], a[2]
        for i in range(n):
            xi = x[i]
            yi = z0 + b0 * xi
            z0 = z1 + xi * b1 - yi * a1
            z1 = xi * b2 - yi * a2
            y[i] = yi
        z[0], z[1] = z0, z1
    else:
        z0 = z[0]
        b0, b1, a1 = b[0], b[1], a[1]
        for i in range(n):
            xi = x[i]
            yi = z0 + b0 * xi
            z0 = xi * b1 - yi * a1
            y[i] = yi
        z[0] = z0
    return y


@njit(cache=True, nogil=True)
def _df2t_rows(b, a, x, z):  # pragma: no cover - compiled (coverage does not see inside)
    """:func:`_df2t` down each column of ``x`` (samples along axis 0), the columns' states in ``z`` (taps − 1,
    columns), updated in place: the same operations per column as lfilter along axis 0. Written out row by row
    rather than calling :func:`_df2t` per column: 1500 × 19 samples take 19 µs so, ~95 µs through per-column
    calls (strided or transposed), measured."""
    n, m = x.shape
    y = np.empty((n, m))
    if b.size == 3:
        b0, b1, b2, a1, a2 = b[0], b[1], b[2], a[1], a[2]
        for i in range(n):
            for j in range(m):
                xi = x[i, j]
                yi = z[0, j] + b0 * xi
                z[0, j] = z[1, j] + xi * b1 - yi * a1
                z[1, j] = xi * b2 - yi * a2
                y[i, j] = yi
    else:
        b0, b1, a1 = b[0], b[1], a[1]
        for i in range(n):
            for j in range(m):
                xi = x[i, j]
                yi = z[0, j] + b0 * xi
                z[0, j] = xi * b1 - yi * a1
                y[i, j] = yi
    return y


def lfilter(b: np.ndarray, a: np.ndarray, x: np.ndarray, zi: np.ndarray, axis: int = -1):
    """``scipy.signal.lfilter(b, a, x, axis, zi)`` -> (y, zf) for float64 ``b``, ``a`` (a[0] = 1) and ``zi`` of the
    exact state shape, the same arithmetic so the same bits: a 1-D signal through 2 or 3 taps (b as long as a) in
    the compiled loop :func:`_df2t`, anything else through lfilter's C routine called without the public function's
    array-API checks (~20 µs a call, which a 1 s batch of a few thousand samples feels); a 2-D signal filtered
    along axis 0 (the electrodes' columns) through :func:`_df2t_rows` (1500 × 19 samples: 19 µs against 150)."""
    x = np.asarray(x, dtype=float)
    if x.ndim == 1 and 2 <= len(b) == len(a) <= 3 and a[0] == 1.0:
        z = np.array(zi, dtype=float)  # a copy: the caller's state is left as it was
        return _df2t(np.asarray(b, float), np.asarray(a, float), np.ascontiguousarray(x), z), z
    columns = x.ndim == 2 and axis == 0 and np.shape(zi) == (len(b) - 1, x.shape[1])
    if columns and 2 <= len(b) == len(a) <= 3 and a[0] == 1.0:
        z = np.array(zi, dtype=float)  # columns filtered along axis 0, as lfilter does them
        return _df2t_rows(np.asarray(b, float), np.asarray(a, float), np.ascontiguousarray(x), z), z
    if _linear_filter is None:  # pragma: no cover
        return signal.lfilter(b, a, x, axis=axis, zi=zi)
    return _linear_filter(b, a, x, axis, zi)


class SosFilter:
    """A second-order-section filter that carries its state between blocks.

    A filter of a single section runs through :func:`lfilter` on that biquad (the same arithmetic,
    a cheaper call), as a 2-tap filter when the section is first-order (b2 = a2 = 0: the third tap's
    state stays 0 and only adds zeros, so the output is the same to the last bit, for 15 % less time);
    several sections run through ``sosfilt``.
    """

    def __init__(self, sos: np.ndarray):
        self.sos = np.asarray(sos, float)
        self.zi = np.zeros((self.sos.shape[0], 2))
        if self.sos.shape[0] == 1:  # lfilter's b and a (2 taps when b2 = a2 = 0)
            self._taps = 2 if self.sos[0, 2] == 0.0 and self.sos[0, 5] == 0.0 else 3
            self._b, self._a = self.sos[0, :self._taps].copy(), self.sos[0, 3:3 + self._taps].copy()

    def settle(self, x0: float) -> None:
        """Set the state to the steady state for a constant input ``x0`` (no start-up transient)."""
        self.zi = sosfilt_zi(self.sos) * x0

    def __call__(self, x: np.ndarray) -> np.ndarray:
        if self.sos.shape[0] == 1:
            y, zi = lfilter(self._b, self._a, x, self.zi[0, :self._taps - 1])
            self.zi = np.zeros((1, 2))
            self.zi[0, :self._taps - 1] = zi
            return y
        y, self.zi = signal.sosfilt(self.sos, x, zi=self.zi)
        return y


def sosfilt_zi(sos: np.ndarray) -> np.ndarray:
    """``scipy.signal.sosfilt_zi(sos)`` (a new array), remembered per coefficient set: every sensor built with the
    same parameters settles the same filters (a rig builds one per trial)."""
    sos = np.ascontiguousarray(sos, dtype=float)
    return _sosfilt_zi(sos.shape, sos.tobytes()).copy()


@functools.lru_cache(maxsize=256)
def _sosfilt_zi(shape: tuple, coefficients: bytes) -> np.ndarray:
    return signal.sosfilt_zi(np.frombuffer(coefficients).reshape(shape))


def lowpass_butter2(f_hz: float):
    """Analog 2nd-order Butterworth low-pass, unit DC gain: (z, p, k) in rad/s (new arrays; the design is
    remembered)."""
    z, p, k = _butter2(float(f_hz))
    return z.copy(), p.copy(), k


@functools.lru_cache(maxsize=64)
def _butter2(f_hz: float):
    return signal.butter(2, 2 * np.pi * f_hz, analog=True, output="zpk")


def highpass_1st(f_hz: float):
    """Analog 1st-order high-pass, unit high-frequency gain."""
    return np.array([0.0]), np.array([-2 * np.pi * f_hz]), 1.0


def resonance(f_hz: float, decay_s: float, zero_hz: float | None = None):
    """Analog 2nd-order resonance with natural frequency ``f_hz`` and envelope decay ``decay_s``.

    Unit DC gain; with ``zero_hz`` a real zero (1 + s/ω_z) is added.
    """
    w0 = 2 * np.pi * f_hz
    sigma = 1.0 / decay_s  # envelope e^(-t/decay) => Re(p) = -1/decay
    wd = np.sqrt(max(w0**2 - sigma**2, 1e-12))
    p = np.array([-sigma + 1j * wd, -sigma - 1j * wd])
    k = w0**2
    if zero_hz is None:
        return np.array([]), p, k
    wz = 2 * np.pi * zero_hz
    return np.array([-wz]), p, k / wz
