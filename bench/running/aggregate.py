"""What a run keeps while its samples stream past: statistics and plot data of bounded size.

A run of ten hours must not hold ten hours of samples, yet its record needs channel statistics, the resting
baseline and noise of each channel, the impact detection per sphere drop, and its plots need the traces and the
PAC spectrogram.  :class:`RunSummary` collects all of that chunk by chunk, in memory that does not grow with the
run's duration:

* per channel, a histogram of the 12-bit codes of good samples (4096 counters): count, mean, standard
  deviation, minimum, maximum and the exact median / MAD fall-back of the resting statistics; the same over the
  first 5 % of the scene (the electrodes' resting values for the electrode map);
* the good samples of the first second (the resting lead-in the record's baselines come from);
* a min/max/mean envelope over :data:`ENVELOPE_BINS` equal time bins of the scene (one bin is at most a pixel
  column of the traces plot);
* for PAC, the spectrogram (80 ms windows) computed as the samples arrive, averaged over consecutive windows so
  that at most :data:`SPECTROGRAM_COLUMNS` columns are kept, and the samples inside each sphere drop's detection
  window.

For runs short enough that the spectrogram needs no averaging the figures equal those computed from the whole
arrays (the spectrogram column for column, the statistics to rounding).
"""

from __future__ import annotations

import math

import numpy as np

ENVELOPE_BINS = 1000  # about one per pixel column of the traces plot (11 in at 110 dpi, less margins)
SPECTROGRAM_COLUMNS = 1000
LEAD_IN_S = 1.0
IMPACT_WINDOW_S = 0.1  # the window of D ch. 5's detection rule (analysis.DetectionRule.window_s)
CODES = 4096


def _hist_order_stat(hist: np.ndarray, k: int) -> int:
    """The k-th smallest value (0-based) of the multiset whose histogram is ``hist``."""
    return int(np.searchsorted(np.cumsum(hist), k, side="right"))


def hist_median(hist: np.ndarray) -> float:
    """``np.median`` of the values a histogram counts (exact: integer values)."""
    n = int(hist.sum())
    if n == 0:
        return math.nan
    lo, hi = _hist_order_stat(hist, (n - 1) // 2), _hist_order_stat(hist, n // 2)
    return (lo + hi) / 2.0


def hist_median_pair(hist: np.ndarray) -> tuple[int, int]:
    """The two middle values (equal for an odd count) of the multiset a histogram counts."""
    n = int(hist.sum())
    return _hist_order_stat(hist, (n - 1) // 2), _hist_order_stat(hist, n // 2)


def hist_mad_sigma(hist: np.ndarray, med: float) -> float:
    """1.4826 · median(|x − med|) of the values a histogram counts (exact)."""
    values = np.flatnonzero(hist)
    if values.size == 0:
        return math.nan
    dev = np.abs(values - med)
    order = np.argsort(dev, kind="stable")
    dev_sorted, counts = dev[order], hist[values][order]
    n = int(counts.sum())
    c = np.cumsum(counts)
    lo = dev_sorted[int(np.searchsorted(c, (n - 1) // 2, side="right"))]
    hi = dev_sorted[int(np.searchsorted(c, n // 2, side="right"))]
    return float(1.4826 * (lo + hi) / 2.0)


class ChannelSummary:
    """One channel's view of a :class:`RunSummary`: its rows of the summary's counters."""

    def __init__(self, owner: "RunSummary", row: int, name: str):
        self._o, self.row, self.name = owner, row, name
        self._lead_t: list[np.ndarray] = []
        self._lead_x: list[np.ndarray] = []

    @property
    def samples(self) -> int:
        return int(self._o.samples[self.row])

    @property
    def bad(self) -> int:
        return int(self._o.bad[self.row])

    @property
    def hist(self) -> np.ndarray:
        """Counts of each code 0..4095 over the good samples."""
        return self._o.hist[self.row]

    @property
    def early_hist(self) -> np.ndarray:
        """Counts of each code over the good samples of the first 5 % of the scene (resting values)."""
        return self._o.early_hist[self.row]

    @property
    def good(self) -> int:
        return int(self.hist.sum())

    def stats(self, simulated_s: float) -> dict:
        n = self.good
        hist = self.hist
        values = np.arange(hist.size, dtype=np.int64)
        if n:
            s1 = int((hist * values).sum())
            s2 = int((hist * values * values).sum())
            var = max(0.0, (n * s2 - s1 * s1) / (n * n))
            nz = np.flatnonzero(hist)
        return {"samples": self.samples, "bad_samples": self.bad,
                # good samples at the ADC's rails (0 or 4095): the signal went there or beyond, clipped
                "rail_samples": int(hist[0] + hist[-1]),
                "rate_Hz": float(self.samples / simulated_s) if simulated_s else 0.0,
                "mean_code": s1 / n if n else None, "std_code": float(math.sqrt(var)) if n else None,
                "min_code": int(nz[0]) if n else None, "max_code": int(nz[-1]) if n else None}

    def lead_in(self) -> tuple[np.ndarray, np.ndarray]:
        """Good samples of the first :data:`LEAD_IN_S` seconds: (instants, codes as float)."""
        if not self._lead_t:
            return np.zeros(0), np.zeros(0)
        return np.concatenate(self._lead_t), np.concatenate(self._lead_x).astype(float)

    def envelope(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Bins that hold good samples: (centre instants s, lowest code, highest code, mean code)."""
        o, r = self._o, self.row
        nz = np.flatnonzero(o.env_n[r])
        width = o.duration_s / o.bins
        return ((nz + 0.5) * width, o.env_lo[r, nz].astype(float), o.env_hi[r, nz].astype(float),
                o.env_sum[r, nz] / o.env_n[r, nz])


class SpectrogramAccumulator:
    """The spectrogram of a uniformly sampled stream (scipy's ``spectrogram``, 80 ms windows, half overlap),
    computed as samples arrive; consecutive windows are averaged so that at most ``max_columns`` are kept."""

    def __init__(self, duration_s: float, max_columns: int = SPECTROGRAM_COLUMNS, window_s: float = 0.08):
        self.duration_s, self.max_columns, self.window_s = float(duration_s), int(max_columns), window_s
        self.fs: float | None = None
        self.samples = 0
        self._t_head: list[float] = []
        self.t0: float | None = None
        self._buf = np.zeros(0)
        self._segments = 0  # windows computed so far
        self._group_sum = None
        self._group_t = 0.0
        self._group_n = 0
        self.columns: list[np.ndarray] = []
        self.column_t: list[float] = []
        self.freqs: np.ndarray | None = None

    def _start(self):
        self.fs = 1.0 / float(np.median(np.diff(self._t_head)))
        self.nper = max(32, int(round(self.window_s * self.fs)))
        self.noverlap = self.nper // 2
        self.step = self.nper - self.noverlap
        expected = max(1, (int(self.duration_s * self.fs) - self.nper) // self.step + 1)
        self.group = max(1, math.ceil(expected / self.max_columns))
        from scipy.signal import get_window

        self._win = get_window(("tukey", 0.25), self.nper)
        self._scale = 1.0 / (self.fs * float((self._win * self._win).sum()))
        self.freqs = np.fft.rfftfreq(self.nper, 1.0 / self.fs)

    def add(self, t: np.ndarray, x: np.ndarray) -> None:
        if t.size == 0:
            return
        if self.t0 is None:
            self.t0 = float(t[0])
        self.samples += int(t.size)
        self._buf = np.concatenate([self._buf, np.asarray(x, float)])
        if self.fs is None:
            self._t_head.extend(t[: 64 - len(self._t_head)].tolist())
            if len(self._t_head) < 64:
                return
            self._start()
        self._process()

    def _psd(self, segs: np.ndarray) -> np.ndarray:
        """PSD (density, one-sided) of each row of ``segs``, as ``scipy.signal.spectrogram`` computes it with its
        defaults (Tukey(0.25) window, constant detrend)."""
        x = (segs - segs.mean(axis=1, keepdims=True)) * self._win
        p = np.abs(np.fft.rfft(x, axis=1)) ** 2 * self._scale
        if self.nper % 2:
            p[:, 1:] *= 2
        else:
            p[:, 1:-1] *= 2
        return p.T

    def _process(self, final: bool = False):
        if self.fs is None:
            if not final or len(self._t_head) < 2:
                return
            self._start()
        n = self._buf.size
        if n < self.nper:
            return
        k = (n - self.nper) // self.step + 1
        segs = np.lib.stride_tricks.sliding_window_view(self._buf, self.nper)[::self.step][:k]
        sxx = self._psd(segs)
        times = self.t0 + (self.nper / 2 + (self._segments + np.arange(k)) * self.step) / self.fs
        self._segments += k
        self._buf = self._buf[k * self.step:].copy()
        if self.group == 1:
            self.columns.extend(sxx.T)
            self.column_t.extend(times.tolist())
            return
        for j in range(k):
            if self._group_sum is None:
                self._group_sum, self._group_t, self._group_n = sxx[:, j].copy(), 0.0, 0
            else:
                self._group_sum += sxx[:, j]
            self._group_t += times[j]
            self._group_n += 1
            if self._group_n == self.group:
                self._emit()

    def _emit(self):
        self.columns.append(self._group_sum / self._group_n)
        self.column_t.append(self._group_t / self._group_n)
        self._group_sum, self._group_n = None, 0

    def finish(self):
        self._process(final=True)
        if self._group_sum is not None and self._group_n:
            self._emit()

    def result(self):
        """(frequencies Hz, column instants s, PSD frequencies × columns) in squared input units per Hz."""
        if not self.columns:
            return None
        return self.freqs, np.asarray(self.column_t), np.stack(self.columns, axis=1)


class RunSummary:
    """Everything the record, the report and the plots need, gathered while the samples stream past.

    The counters are arrays with one row per channel, updated for a whole chunk at once (a chunk arrives sorted
    by channel, in time order within each channel — see ``bench.running.runner.split_by_channel``)."""

    def __init__(self, scene, channel_names, bins: int = ENVELOPE_BINS,
                 spectrogram_columns: int = SPECTROGRAM_COLUMNS, impact_window_s: float = IMPACT_WINDOW_S):
        from emulator.channels import ALL_CHANNEL_INDEX as CHANNEL_INDEX  # E1..E24: an SP's E20..E24 too
        from emulator.stimuli import SphereDrop

        self.duration_s = float(scene.duration_s)
        self.bins = int(bins)
        names = list(channel_names)
        k = len(names)
        self.row_of_index = np.full(max(CHANNEL_INDEX.values()) + 1, -1, np.int64)
        for r, n in enumerate(names):
            self.row_of_index[CHANNEL_INDEX[n]] = r
        self.samples = np.zeros(k, np.int64)
        self.bad = np.zeros(k, np.int64)
        self.hist = np.zeros((k, CODES), np.int64)
        self.early_hist = np.zeros((k, CODES), np.int64)
        self.early_end_s = 0.05 * self.duration_s
        self.env_lo = np.full((k, self.bins), np.iinfo(np.int32).max, np.int32)
        self.env_hi = np.full((k, self.bins), -1, np.int32)
        self.env_n = np.zeros((k, self.bins), np.int64)
        self.env_sum = np.zeros((k, self.bins), np.float64)
        self.channels = {n: ChannelSummary(self, r, n) for r, n in enumerate(names)}
        starts = [s.start_s for s in scene.stimuli]
        self.first_stimulus_s = min(starts) if starts else None
        self.spectrogram = SpectrogramAccumulator(self.duration_s, spectrogram_columns) \
            if "PAC" in self.channels else None
        self.impact_windows: list[tuple[float, float]] = []
        if "PAC" in self.channels and scene.impact_detection:
            self.impact_windows = [(s.time_s, s.time_s + impact_window_s)
                                   for s in scene.stimuli if isinstance(s, SphereDrop)]
        self._window_t: dict[int, list[np.ndarray]] = {}
        self._window_x: dict[int, list[np.ndarray]] = {}

    def add(self, chunk) -> None:
        """``chunk``: a :class:`~bench.running.runner.Chunk` (arrays sorted by channel, plus per-channel views)."""
        t, code, status = chunk.times, chunk.codes, chunk.status
        if t.size == 0:
            return
        k = len(self.channels)
        row = self.row_of_index[chunk.channels]
        self.samples += np.bincount(row, minlength=k)
        ok = status == 0
        if not ok.all():
            self.bad += np.bincount(row[~ok], minlength=k)
            t, code, row = t[ok], code[ok], row[ok]
            if t.size == 0:
                return
        code = code.astype(np.int64)
        key = row * CODES + code
        self.hist += np.bincount(key, minlength=k * CODES).reshape(k, CODES)
        if t.min() < self.early_end_s:
            m = t < self.early_end_s
            self.early_hist += np.bincount(key[m], minlength=k * CODES).reshape(k, CODES)
        if t.min() < LEAD_IN_S:
            for name, (tc, xc, sc) in chunk.parts.items():
                m = (tc < LEAD_IN_S) & (sc == 0)
                if m.any():
                    cs = self.channels[name]
                    cs._lead_t.append(tc[m].copy())
                    cs._lead_x.append(xc[m].copy())
        # envelope: bin keys are non-decreasing (channel-major, time order within a channel)
        b = np.minimum((t * (self.bins / self.duration_s)).astype(np.int64), self.bins - 1)
        ekey = row * self.bins + b
        starts = np.concatenate([[0], np.flatnonzero(np.diff(ekey)) + 1])
        u = ekey[starts]
        lo, hi = self.env_lo.reshape(-1), self.env_hi.reshape(-1)
        lo[u] = np.minimum(lo[u], np.minimum.reduceat(code, starts))
        hi[u] = np.maximum(hi[u], np.maximum.reduceat(code, starts))
        self.env_n.reshape(-1)[u] += np.diff(np.concatenate([starts, [code.size]]))
        self.env_sum.reshape(-1)[u] += np.add.reduceat(code, starts)
        if "PAC" in chunk.parts:
            tp, xp, _ = chunk.parts["PAC"]
            if self.spectrogram is not None:
                self.spectrogram.add(tp, xp)
            if self.impact_windows and tp.size:
                for i, (a, e) in enumerate(self.impact_windows):
                    if e <= tp[0] or a > tp[-1]:
                        continue
                    m = (tp >= a) & (tp < e)
                    if m.any():
                        self._window_t.setdefault(i, []).append(tp[m].copy())
                        self._window_x.setdefault(i, []).append(xp[m].copy())

    def add_parts(self, parts: dict) -> None:
        """Add samples given as channel name → (instants, codes, status) (e.g. a recording held in memory)."""
        from bench.running.runner import make_chunk

        self.add(make_chunk(parts))

    def finish(self) -> None:
        if self.spectrogram is not None:
            self.spectrogram.finish()

    def impact_window(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """PAC samples (every status, as the detection rule reads them) inside sphere drop ``i``'s window."""
        if i not in self._window_t:
            return np.zeros(0), np.zeros(0)
        return np.concatenate(self._window_t[i]), np.concatenate(self._window_x[i]).astype(float)

    def resting_stats(self, channel: str, simulated_s: float) -> tuple[float, float]:
        """(baseline, σ) of a channel from its good samples before the first stimulus (at most 1 s, at least
        50 ms); falls back to the median and a MAD-based σ of the whole trace when there is no quiet lead-in."""
        cs = self.channels[channel]
        if cs.good == 0:
            return math.nan, math.nan
        first = self.first_stimulus_s if self.first_stimulus_s is not None else simulated_s
        quiet_end = min(first - 0.02, LEAD_IN_S)
        t, x = cs.lead_in()
        sel = t < quiet_end
        if quiet_end >= 0.05 and np.count_nonzero(sel) >= 5:
            return float(np.mean(x[sel])), float(np.std(x[sel]))
        med = hist_median(cs.hist)
        return med, hist_mad_sigma(cs.hist, med)
