"""``samples.h5``: every sample of a run, streamed to disk as the run goes (HDF5 through h5py).

Layout (readable from MATLAB ``h5read``, pandas/h5py, HDFView)::

    /                 attributes: format, scene_name, scene_toml (the scene file's text), scene_source, seed,
                      fidelity, spi, sequence (JSON), slot_rate_Hz, spi_clock_Hz, duration_s (planned),
                      status ("running" while written; then "ok" | "failed" | "interrupted"), simulated_s, error
    /<CH>/            one group per channel read (PAC, PDC, TAC, TDC, E1..E19); attributes: channel, rate_Hz
    /<CH>/t           float64, s: the instant each sample was taken (the sampling command's chip-select release)
    /<CH>/code        uint16: the 12-bit ADC code (0..4095)
    /<CH>/status      uint8: 0 ok, 1 parity error, 2 error word

Datasets are one-dimensional, chunked (:data:`H5_CHUNK` samples), resizable, compressed with gzip level 1 and
the shuffle filter by default (``compression="none"`` or ``"lzf"`` on request).  Samples are buffered and
appended in whole chunks once :data:`FLUSH_SAMPLES` are buffered, so memory stays flat whatever the run's length.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from bench.running.runner import ChannelRecord

FORMAT = "biotac-bench samples 1"
H5_CHUNK = 16384
FLUSH_SAMPLES = 1 << 17
COMPRESSIONS = ("gzip", "lzf", "none")
FIELDS = (("t", np.float64, "s", "instant the sample was taken (chip-select release of the sampling command)"),
          ("code", np.uint16, "ADC code", "12-bit ADC code, 0..4095"),
          ("status", np.uint8, "", "0 ok, 1 parity error, 2 error word"))


def _h5py():
    import h5py

    return h5py


class SampleStore:
    """Appends each chunk's samples to ``path`` (a temporary file the caller renames into place after
    :meth:`close`)."""

    def __init__(self, path: Path, scene, channel_names, compression: str = "gzip"):
        h5py = _h5py()
        if compression not in COMPRESSIONS:
            raise ValueError(f"compression = {compression!r}: one of {', '.join(COMPRESSIONS)}")
        self.path = Path(path)
        # HDF5 1.10 file format (readable by HDF5 >= 1.10: MATLAB R2021b+, HDFView 3, h5py, pandas): its chunk index
        # keeps the library's memory flat on long appends; whole chunks are written, so no chunk cache is needed
        self.f = h5py.File(self.path, "w", libver=("v110", "v110"), rdcc_nbytes=0)
        self.names = list(channel_names)
        a = self.f.attrs
        seq = scene.sequence if isinstance(scene.sequence, str) else list(scene.sequence)
        a.update({"format": FORMAT, "scene_name": scene.name, "scene_toml": scene.text or "",
                  "scene_source": str(scene.source), "seed": int(scene.seed), "fidelity": scene.fidelity,
                  "spi": scene.spi, "sequence": json.dumps(seq), "slot_rate_Hz": float(scene.slot_rate_Hz),
                  "spi_clock_Hz": float(scene.spi_clock_Hz), "duration_s": float(scene.duration_s),
                  "status": "running", "simulated_s": 0.0, "error": ""})
        kw = {} if compression == "none" else {"compression": compression, "shuffle": True}
        if compression == "gzip":
            kw["compression_opts"] = 1
        from emulator.channels import ALL_CHANNEL_INDEX as CHANNEL_INDEX
        from emulator.channels import parse_sequence

        seq_idx = parse_sequence(scene.sequence, scene.variant)  # "default": the sensor's variant's frame
        self._ds = {}
        for name in self.names:
            g = self.f.create_group(name)
            g.attrs["channel"] = name
            g.attrs["rate_Hz"] = float(np.count_nonzero(seq_idx == CHANNEL_INDEX[name]) * scene.slot_rate_Hz
                                       / len(seq_idx))
            dss = []
            for key, dtype, unit, doc in FIELDS:
                d = g.create_dataset(key, shape=(0,), maxshape=(None,), dtype=dtype, chunks=(H5_CHUNK,), **kw)
                d.attrs["units"], d.attrs["description"] = unit, doc
                dss.append(d)
            self._ds[name] = dss
        self._buf: dict[str, list] = {n: [] for n in self.names}
        self._pending = 0
        self.failed: str | None = None  # why a write failed (then the file is broken: salvage, then abort)

    def add(self, parts: dict) -> None:
        """``parts``: channel name → (instants, codes, status) of the next chunk."""
        for name, p in parts.items():
            self._buf[name].append(p)
            self._pending += p[0].size
        if self._pending >= FLUSH_SAMPLES:
            self.flush()

    def flush(self, everything: bool = False) -> None:
        """Append buffered samples: whole HDF5 chunks only (the rest stays buffered), or ``everything``.

        Writing whole chunks means no chunk is ever written twice and HDF5 needs no chunk cache, so the
        library's memory stays flat however long the run.  A channel's samples leave the buffer only once they
        are written (see :meth:`_append`)."""
        for name, lst in self._buf.items():
            if not lst:
                continue
            arrays = [np.concatenate(x) for x in zip(*lst)] if len(lst) > 1 else list(lst[0])
            lst[:] = [tuple(arrays)]
            n = arrays[0].size if everything else (arrays[0].size // H5_CHUNK) * H5_CHUNK
            if n == 0:
                continue
            self._append(name, [a[:n] for a in arrays])
            lst[:] = [tuple(a[n:].copy() for a in arrays)] if n < arrays[0].size else []
        self._pending = sum(p[0].size for lst in self._buf.values() for p in lst)

    def _append(self, name: str, arrays) -> None:
        """Append one channel's (instants, codes, status) to its datasets: all three, or — when a write fails (a
        full disk) — none, the datasets cut back to their length before it and :attr:`failed` set to the reason."""
        datasets = self._ds[name]
        k = datasets[0].shape[0]
        try:
            for d, a in zip(datasets, arrays):
                d.resize((k + a.size,))
                d[k:] = a
        except Exception as e:
            self.failed = os_reason(e)
            for d in datasets:
                with contextlib.suppress(Exception):
                    d.resize((k,))
            raise

    def salvage(self, until_s: float) -> dict[str, ChannelRecord]:
        """Every sample taken before ``until_s`` (s) that the store holds, written or still buffered, read back into
        memory: after a write failed, so that a fresh file can hold them once the broken one is gone."""
        kept = {}
        for name in self.names:
            parts = [tuple(d[:] for d in self._ds[name])] + self._buf[name]
            t, code, status = (np.concatenate(x) for x in zip(*parts))
            before = t < until_s
            kept[name] = ChannelRecord(t[before], code[before], status[before])
        return kept

    def close(self, status: str = "running", simulated_s: float = 0.0, error: str | None = None) -> None:
        """Write what is buffered, set the run's status attributes, flush and close the file.  A failure (a full
        disk: HDF5 writes its cached metadata only now) raises with :attr:`failed` set and the file left open, so
        that :meth:`salvage` can still read every sample back; :meth:`abort` closes it."""
        try:
            self.flush(everything=True)
            self.f.attrs.update({"status": status, "simulated_s": float(simulated_s), "error": error or ""})
            self.f.flush()
            self.f.close()
        except Exception as e:
            self.failed = self.failed or os_reason(e)
            raise

    def abort(self) -> None:
        try:
            self.f.close()
        except Exception:
            pass


def os_reason(e: BaseException) -> str:
    """An error in a few words: the system's text for an ``OSError``'s errno, or for the errno HDF5's own message
    names (it runs to several lines of buffer addresses and times, and reaches Python without an errno), else the
    message's first line, else (an empty message) the error's type: never empty, since a reason marks a failure."""
    if isinstance(e, OSError) and e.errno:
        return os.strerror(e.errno)
    named = re.search(r"\berrno = (\d+)", str(e))
    return os.strerror(int(named.group(1))) if named else str(e).split("\n", 1)[0] or type(e).__name__


def set_status(path: Path, status: str, simulated_s: float, error: str | None, **extra) -> None:
    """Set the run's final status attributes of a closed ``samples.h5``."""
    with _h5py().File(path, "r+") as f:
        f.attrs.update({"status": status, "simulated_s": float(simulated_s), "error": error or ""})
        for k, v in extra.items():
            f.attrs[k] = v


def write_recording(path: Path, rec, compression: str = "gzip") -> None:
    """A ``samples.h5`` from a recording whose samples are in memory."""
    store = SampleStore(path, rec.scene, list(rec.channels), compression)
    try:
        store.add({n: (r.times, r.codes, r.status) for n, r in rec.channels.items()})
        store.close(rec.status, rec.simulated_s, rec.error)
    except BaseException:
        store.abort()
        raise


def read_attrs(path: Path) -> dict:
    with _h5py().File(path, "r") as f:
        return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}


def channel_names(path: Path) -> list[str]:
    from emulator.channels import ALL_CHANNEL_INDEX as CHANNEL_INDEX

    with _h5py().File(path, "r") as f:
        return sorted(f.keys(), key=lambda n: CHANNEL_INDEX.get(n, 999))


def read_channel(path: Path, name: str, start: int = 0, stop: int | None = None) -> ChannelRecord:
    with _h5py().File(path, "r") as f:
        g = f[name]
        return ChannelRecord(g["t"][start:stop], g["code"][start:stop], g["status"][start:stop])


def read_channels(path: Path) -> dict[str, ChannelRecord]:
    """Every channel of a ``samples.h5``, in memory (for short runs)."""
    return {n: read_channel(path, n) for n in channel_names(path)}


class StoredChannels(Mapping):
    """``Recording.channels`` read back on demand from a ``samples.h5`` (one channel at a time)."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self._names = channel_names(self.path)

    def __getitem__(self, name: str) -> ChannelRecord:
        if name not in self._names:
            raise KeyError(name)
        return read_channel(self.path, name)

    def __iter__(self):
        return iter(self._names)

    def __len__(self):
        return len(self._names)


def iter_time_blocks(path: Path, names, block_s: float = 60.0):
    """Yield ``{channel: ChannelRecord}`` for consecutive time blocks [k·block_s, (k+1)·block_s), reading only one
    block at a time from ``samples.h5``."""
    h5py = _h5py()
    with h5py.File(path, "r") as f:
        total = {n: f[n]["t"].shape[0] for n in names}
        rate = {n: float(f[n].attrs.get("rate_Hz", 100.0)) for n in names}
        cur = {n: 0 for n in names}
        end = block_s
        while any(cur[n] < total[n] for n in names):
            block = {}
            for n in names:
                ds, i = f[n]["t"], cur[n]
                j, k = i, max(1024, int(rate[n] * block_s) + 2)
                while j < total[n]:
                    w = ds[j:j + k]
                    pos = int(np.searchsorted(w, end, side="left"))
                    j += pos
                    if pos < w.size:
                        break
                    k *= 2
                g = f[n]
                block[n] = ChannelRecord(g["t"][i:j], g["code"][i:j], g["status"][i:j])
                cur[n] = j
            yield block
            end += block_s


def file_size(path: Path) -> int:
    try:
        return os.path.getsize(path)
    except OSError:
        return 0
