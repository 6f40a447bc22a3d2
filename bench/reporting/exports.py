"""Exports written from ``samples.h5`` after a run: ``codes.npz`` and ``samples.csv``.

Both are made only for runs up to :data:`EXPORT_MAX_S` simulated seconds unless forced (``run --npz``).  They are
written one array (NPZ) or one time block (CSV) at a time, so even a forced export of a long run needs memory for
one channel, not for the run; ``checkpoint()`` is called between arrays and blocks (it raises to stop early).
Physical units use the published conversions with offsets taken from the resting lead-in, as a host would.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from bench.reporting import store
from emulator import conversions as conv

#: Longest run (simulated s) whose samples are exported to codes.npz / samples.csv without ``--npz``.
EXPORT_MAX_S = 600.0
CSV_UNIT = {"PAC": ("PAC_Pa", "Pa"), "PDC": ("PDC_kPa", "kPa"), "TDC": ("TDC_C", "degC"),
            "TAC": ("TAC_C_per_s", "degC/s")}


def _interp(t: np.ndarray, tp: np.ndarray, xp: np.ndarray) -> np.ndarray:
    """``xp`` (codes) at instants ``t``, linear between samples; NaN when there is no sample at all."""
    if tp.size == 0:
        return np.full(t.size, np.nan)
    return np.interp(t, tp, np.asarray(xp, float))


def physical(name: str, codes: np.ndarray, baselines: dict, tac_tdc: np.ndarray | None = None,
             status: np.ndarray | None = None) -> dict:
    """Physical-unit arrays of one channel's codes: PAC_Pa; PDC_kPa, PDC_force_N; TDC_C; TAC_C_per_s (needs the
    TDC code at each TAC instant); E<n>_ohm.  A sample the host rejected (``status`` ≠ 0: a parity error or an
    error word) is no measurement: its value is NaN (an error word had read as, e.g., 5540.8 ohm)."""
    out = _physical(name, codes, baselines, tac_tdc)
    if status is not None and np.any(status):
        bad = np.asarray(status) != 0
        out = {k: np.where(bad, np.nan, np.asarray(v, float)) for k, v in out.items()}
    return out


def _good(r):
    """Instants and codes of a channel's samples the host accepted (status 0)."""
    ok = np.asarray(r.status) == 0
    return r.times[ok], r.codes[ok]


def _physical(name: str, codes: np.ndarray, baselines: dict, tac_tdc: np.ndarray | None = None) -> dict:
    if name == "PAC":
        return {"PAC_Pa": conv.pac_to_pa(codes, baselines["PAC"])}
    if name == "PDC":
        return {"PDC_kPa": conv.pdc_to_kpa(codes, baselines["PDC"]),
                "PDC_force_N": conv.pdc_to_force_n(codes, baselines["PDC"])}
    if name == "TDC":
        return {"TDC_C": conv.tdc_to_celsius(codes)}
    if name == "TAC":
        return {} if tac_tdc is None else {"TAC_C_per_s": conv.tac_to_celsius_per_s(codes, tac_tdc,
                                                                                     baselines["TAC"])}
    if name.startswith("E"):
        return {f"{name}_ohm": conv.impedance_ohm(codes)}
    return {}


def _npz_entry(zf: zipfile.ZipFile, key: str, array: np.ndarray) -> None:
    with zf.open(key + ".npy", "w", force_zip64=True) as fh:  # as np.savez_compressed writes each array
        np.lib.format.write_array(fh, np.asanyarray(array), allow_pickle=False)


def export_npz(h5: Path, dest: Path, baselines: dict, checkpoint=lambda: None) -> None:
    """``codes.npz`` (as ``np.savez_compressed`` would write it) from ``samples.h5``: ``scene_toml``, then per
    channel ``<CH>_t``, ``<CH>_code``, ``<CH>_status``, then the physical units."""
    names = store.channel_names(h5)
    scene_toml = store.read_attrs(h5).get("scene_toml", "")
    with zipfile.ZipFile(dest, mode="w", compression=zipfile.ZIP_DEFLATED, allowZip64=True) as zf:
        _npz_entry(zf, "scene_toml", np.array(scene_toml))
        for name in names:
            checkpoint()
            r = store.read_channel(h5, name)
            for key, a in (("t", r.times), ("code", r.codes), ("status", r.status)):
                _npz_entry(zf, f"{name}_{key}", a)
            del r
        for name in [n for n in ("PAC", "PDC", "TDC", "TAC") if n in names] + [n for n in names if n[0] == "E"]:
            checkpoint()
            r = store.read_channel(h5, name)
            tdc = None
            if name == "TAC":
                if "TDC" not in names:
                    continue
                d = store.read_channel(h5, "TDC")
                tdc = _interp(r.times, *_good(d))
                del d
            for key, a in physical(name, r.codes, baselines, tdc, r.status).items():
                _npz_entry(zf, key, a)


def export_csv(h5: Path, dest: Path, baselines: dict, checkpoint=lambda: None, block_s: float = 60.0) -> None:
    """``samples.csv`` in long format (time_s, channel, code, status, value, unit), rows in time order, written
    one time block at a time."""
    names = store.channel_names(h5)
    with dest.open("w", encoding="utf-8") as f:
        f.write("time_s,channel,code,status,value,unit\n")
        tdc_prev, tdc_seen = None, 0
        for block in store.iter_time_blocks(h5, names, block_s):
            checkpoint()
            cols = []
            for name, r in block.items():
                if r.times.size == 0:
                    continue
                key, unit = CSV_UNIT.get(name, (f"{name}_ohm", "ohm"))
                tdc = None
                if name == "TAC" and "TDC" in block:
                    d = block["TDC"]
                    dt, dc = _good(d)  # TDC's accepted samples only: an error word is no temperature
                    # TDC around the block: the last sample before it, the block's, and the first after it
                    t_ref = np.concatenate([tdc_prev[0], dt]) if tdc_prev is not None else dt
                    c_ref = np.concatenate([tdc_prev[1], dc.astype(float)]) if tdc_prev is not None \
                        else dc.astype(float)
                    at = tdc_seen + d.times.size
                    while True:  # the first accepted TDC sample after the block (if any)
                        nxt = store.read_channel(h5, "TDC", at, at + 64)
                        nt, nc = _good(nxt)
                        if nt.size or nxt.times.size < 64:
                            break
                        at += 64
                    t_ref, c_ref = np.append(t_ref, nt[:1]), np.append(c_ref, nc[:1].astype(float))
                    tdc = _interp(r.times, t_ref, c_ref)
                value = physical(name, r.codes, baselines, tdc, r.status).get(key)
                if value is None:
                    value = np.full(r.codes.size, np.nan)
                cols.append((r.times, np.full(r.codes.size, name, dtype=object), r.codes, r.status, value,
                             np.full(r.codes.size, unit, dtype=object)))
            if "TDC" in block and block["TDC"].times.size:
                d = block["TDC"]
                dt, dc = _good(d)
                if dt.size:
                    tdc_prev = (dt[-1:], dc[-1:].astype(float))
                tdc_seen += d.times.size
            if not cols:
                continue
            t, ch, code, st, val, unit = (np.concatenate(x) for x in zip(*cols))
            order = np.argsort(t, kind="stable")
            lines = [f"{a:.7f},{b},{c},{d},{e:.6g},{u}\n" for a, b, c, d, e, u in
                     zip(t[order].tolist(), ch[order].tolist(), code[order].tolist(), st[order].tolist(),
                         val[order].tolist(), unit[order].tolist())]
            f.write("".join(lines))

