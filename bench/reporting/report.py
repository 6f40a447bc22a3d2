"""Outputs of a run: raw codes (NPZ, CSV on request), physical units, a JSON record, plots, a short report."""

from __future__ import annotations

import json
import math
from dataclasses import asdict
from pathlib import Path

import numpy as np

from bench.verification import analysis
from bench.running.runner import Recording
from emulator import conversions as conv
from emulator.stimuli import SPHERES, SphereDrop

SPHERE_NAME = {m: n for n, (m, _) in SPHERES.items()}


def _first_stimulus_s(rec: Recording) -> float:
    starts = [s.start_s for s in rec.scene.stimuli]
    return min(starts) if starts else rec.simulated_s


def resting_stats(rec: Recording, channel: str) -> tuple[float, float]:
    """(baseline, σ) of a channel from its samples before the first stimulus (at most 1 s, at least 50 ms).

    Falls back to the median and a MAD-based σ of the whole trace when there is no quiet lead-in.
    """
    r = rec.channels[channel]
    x = r.codes.astype(float)[r.status == 0]
    t = r.times[r.status == 0]
    if x.size == 0:
        return math.nan, math.nan
    quiet_end = min(_first_stimulus_s(rec) - 0.02, 1.0)
    sel = t < quiet_end
    if quiet_end >= 0.05 and np.count_nonzero(sel) >= 5:
        return float(np.mean(x[sel])), float(np.std(x[sel]))
    med = float(np.median(x))
    return med, float(1.4826 * np.median(np.abs(x - med)))


def physical_units(rec: Recording) -> dict[str, np.ndarray]:
    """Published conversions, with offsets taken from the resting lead-in as a host would."""
    out = {}
    if "PAC" in rec.channels:
        base, _ = resting_stats(rec, "PAC")
        out["PAC_Pa"] = conv.pac_to_pa(rec.channels["PAC"].codes, base)
    if "PDC" in rec.channels:
        base, _ = resting_stats(rec, "PDC")
        out["PDC_kPa"] = conv.pdc_to_kpa(rec.channels["PDC"].codes, base)
        out["PDC_force_N"] = conv.pdc_to_force_n(rec.channels["PDC"].codes, base)
    if "TDC" in rec.channels:
        out["TDC_C"] = conv.tdc_to_celsius(rec.channels["TDC"].codes)
        if "TAC" in rec.channels:
            tdc = np.interp(rec.channels["TAC"].times, rec.channels["TDC"].times,
                            rec.channels["TDC"].codes.astype(float))
            base, _ = resting_stats(rec, "TAC")
            out["TAC_C_per_s"] = conv.tac_to_celsius_per_s(rec.channels["TAC"].codes, tdc, base)
    for name, r in rec.channels.items():
        if name.startswith("E"):
            out[f"{name}_ohm"] = conv.impedance_ohm(r.codes)
    return out


def impact_results(rec: Recording) -> dict:
    """The dissertation's impact detection applied to every sphere drop of the scene."""
    if "PAC" not in rec.channels:
        return {"error": "impact detection needs PAC in the host sequence"}
    pac = rec.channels["PAC"]
    base, sigma = resting_stats(rec, "PAC")
    x = pac.codes.astype(float)
    rule = analysis.DetectionRule()
    per_sphere: dict[str, dict] = {}
    for s in rec.scene.stimuli:
        if not isinstance(s, SphereDrop) or s.time_s + rule.window_s > rec.simulated_s:
            continue
        name = SPHERE_NAME.get(s.mass_kg, f"{s.mass_kg * 1e6:.3f} mg sphere")
        hit = analysis.detected_in_window(x, pac.times, s.time_s, base, sigma, rule)
        d = per_sphere.setdefault(name, {"mass_mg": s.mass_kg * 1e6, "energy_uJ": s.energy_J * 1e6,
                                         "drops": 0, "detected": 0})
        d["drops"] += 1
        d["detected"] += int(hit)
    for d in per_sphere.values():
        d["detection_rate"] = d["detected"] / d["drops"]
    return {"rule": asdict(rule), "baseline_code": base, "resting_sigma_bits": sigma, "spheres": per_sphere}


def _stimulus_record(s) -> dict:
    d = {"kind": type(s).__name__}
    d.update({k: v for k, v in vars(s).items()})
    return d


def build_record(rec: Recording, outputs: list[str]) -> dict:
    sc = rec.scene
    stats = {}
    for name, r in rec.channels.items():
        ok = r.status == 0
        x = r.codes[ok].astype(float)
        stats[name] = {
            "samples": int(r.codes.size), "bad_samples": int(np.count_nonzero(~ok)),
            "rate_Hz": float(r.codes.size / rec.simulated_s) if rec.simulated_s else 0.0,
            "mean_code": float(x.mean()) if x.size else None, "std_code": float(x.std()) if x.size else None,
            "min_code": int(x.min()) if x.size else None, "max_code": int(x.max()) if x.size else None,
        }
    record = {
        "status": "failed" if rec.error else "ok",
        "error": rec.error,
        "scene": {"name": sc.name, "source": sc.source, "description": sc.description, "seed": sc.seed,
                  "fidelity": sc.fidelity, "duration_s": sc.duration_s},
        "host": {"sequence": sc.sequence, "slot_rate_Hz": sc.slot_rate_Hz, "spi_clock_Hz": sc.spi_clock_Hz},
        "noise": asdict(sc.noise),
        "sensor_parameters": asdict(sc.params),
        "stimuli": [_stimulus_record(s) for s in sc.stimuli],
        "simulated_s": rec.simulated_s,
        "wall_s": rec.wall_s,
        "realtime_factor": rec.realtime_factor,
        "effects": rec.effects,
        "channels": stats,
        "outputs": outputs,
    }
    if "PAC" in rec.channels:
        base, sigma = resting_stats(rec, "PAC")
        record["pac_resting"] = {"baseline_code": base, "sigma_bits": sigma}
    if sc.impact_detection:
        record["impact_detection"] = impact_results(rec)
    return record


def write_outputs(rec: Recording, out_dir: Path, csv: bool = False, plots: bool = True) -> dict:
    """Write everything about ``rec`` into ``out_dir``; returns the JSON record."""
    out_dir.mkdir(parents=True, exist_ok=True)
    outputs = []
    arrays = {}
    for name, r in rec.channels.items():
        arrays[f"{name}_t"], arrays[f"{name}_code"], arrays[f"{name}_status"] = r.times, r.codes, r.status
    phys = physical_units(rec)
    arrays.update(phys)
    np.savez_compressed(out_dir / "codes.npz", scene_toml=np.array(rec.scene.text), **arrays)
    outputs.append("codes.npz")
    if csv:
        _write_csv(rec, phys, out_dir / "samples.csv")
        outputs.append("samples.csv")
    if plots and rec.simulated_s > 0:
        from bench.reporting import plots as plotting

        outputs += plotting.scene_plots(rec, phys, out_dir)
    outputs += ["record.json", "report.md"]
    record = build_record(rec, outputs)
    (out_dir / "record.json").write_text(json.dumps(record, indent=2, default=_json_default))
    (out_dir / "report.md").write_text(markdown_report(record))
    return record


def _json_default(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)


def _write_csv(rec: Recording, phys: dict, path: Path) -> None:
    unit_of = {"PAC": ("PAC_Pa", "Pa"), "PDC": ("PDC_kPa", "kPa"), "TDC": ("TDC_C", "degC")}
    rows = []
    for name, r in rec.channels.items():
        key, unit = unit_of.get(name, (f"{name}_ohm", "ohm"))
        value = phys.get(key, np.full(r.codes.size, np.nan))
        rows.append(np.rec.fromarrays([r.times, np.full(r.codes.size, name), r.codes, r.status, value,
                                       np.full(r.codes.size, unit)]))
    allrows = np.concatenate(rows) if rows else []
    order = np.argsort(allrows["f0"], kind="stable") if len(allrows) else []
    with path.open("w") as f:
        f.write("time_s,channel,code,status,value,unit\n")
        for row in (allrows[i] for i in order):
            f.write(f"{row[0]:.7f},{row[1]},{row[2]},{row[3]},{row[4]:.6g},{row[5]}\n")


def markdown_report(record: dict) -> str:
    sc = record["scene"]
    lines = [f"# Scene report: {sc['name']}", ""]
    if sc["description"]:
        lines += [sc["description"], ""]
    lines += [f"- status: **{record['status']}**" + (f" — {record['error']}" if record["error"] else ""),
              f"- simulated {record['simulated_s']:.2f} s in {record['wall_s']:.2f} s wall "
              f"({record['realtime_factor']:.0f}× real time), fidelity `{sc['fidelity']}`, seed {sc['seed']}", ""]
    if "pac_resting" in record:
        lines += [f"PAC at rest: baseline {record['pac_resting']['baseline_code']:.1f}, "
                  f"σ = {record['pac_resting']['sigma_bits']:.2f} bits RMS (published 1.4 ± 0.1)", ""]
    if "impact_detection" in record and "spheres" in record["impact_detection"]:
        lines += ["## Impact detection (more than 3 PAC samples beyond 4σ within 100 ms)", "",
                  "| sphere | energy (µJ) | drops | detected | rate |", "|---|---|---|---|---|"]
        for name, d in record["impact_detection"]["spheres"].items():
            lines.append(f"| {name} | {d['energy_uJ']:.3f} | {d['drops']} | {d['detected']} | "
                         f"{100 * d['detection_rate']:.0f} % |")
        lines.append("")
    lines += ["## Channels", "", "| channel | samples | rate (Hz) | mean | std | min | max | bad |",
              "|---|---|---|---|---|---|---|---|"]
    for name, s in record["channels"].items():
        if s["mean_code"] is None:
            lines.append(f"| {name} | {s['samples']} | | | | | | {s['bad_samples']} |")
        else:
            lines.append(f"| {name} | {s['samples']} | {s['rate_Hz']:.0f} | {s['mean_code']:.1f} | "
                         f"{s['std_code']:.2f} | {s['min_code']} | {s['max_code']} | {s['bad_samples']} |")
    lines += ["", "## Effects that ran", "", "| effect | what it models | ms per simulated s |", "|---|---|---|"]
    for e in record["effects"]:
        lines.append(f"| {e['name']} | {e['description']} | {1e3 * e['seconds_per_simulated_s']:.3f} |")
    lines += ["", "Outputs: " + ", ".join(f"`{o}`" for o in record["outputs"]), ""]
    return "\n".join(lines)

