"""Outputs of a run: samples.h5 (every sample), exports (codes.npz, samples.csv), plots, a JSON record, a report.

:func:`write_outputs` writes them into a locked out folder (:mod:`bench.reporting.outdir`), each file under a
temporary name renamed into place, in this order: exports, plots, then ``samples.h5`` (its ``status`` attribute
set to the record's), ``report.md``, and ``record.json`` last — so a ``record.json`` present means every file it
lists is complete and belongs to the same run.  Figures in the record come from the run's streaming summary
(:class:`bench.running.aggregate.RunSummary`), never from all samples in memory.
"""

from __future__ import annotations

import contextlib
import json
import os
from dataclasses import asdict
from pathlib import Path

import numpy as np

from bench.errors import OutputNotWritten
from bench.reporting import exports, store
from bench.reporting.outdir import OutFolder
from bench.running.aggregate import IMPACT_WINDOW_S, RunSummary
from bench.running.runner import Recording
from bench.verification import analysis
from emulator.stimuli import SPHERES, SphereDrop

SPHERE_NAME = {m: n for n, (m, _) in SPHERES.items()}


def _summary(rec: Recording) -> RunSummary:
    """The recording's streaming summary (built from in-memory channels for a hand-made recording)."""
    if rec.summary is None:
        s = RunSummary(rec.scene, list(rec.channels))
        s.add_parts({n: (r.times, r.codes, r.status) for n, r in rec.channels.items()})
        s.finish()
        rec.summary = s
    return rec.summary


def resting_stats(rec: Recording, channel: str) -> tuple[float, float]:
    """(baseline, σ) of a channel from its samples before the first stimulus (at most 1 s, at least 50 ms).

    Falls back to the median and a MAD-based σ of the whole trace when there is no quiet lead-in.
    """
    return _summary(rec).resting_stats(channel, rec.simulated_s)


def baselines(rec: Recording) -> dict[str, float]:
    """Resting offsets used by the physical conversions (PAC, PDC, TAC)."""
    names = rec.channel_names or list(rec.channels)
    return {n: resting_stats(rec, n)[0] for n in ("PAC", "PDC", "TAC") if n in names}


def impact_results(rec: Recording) -> dict:
    """The dissertation's impact detection applied to every sphere drop of the scene."""
    names = rec.channel_names or list(rec.channels)
    if "PAC" not in names:
        return {"error": "impact detection needs PAC in the host sequence"}
    summary = _summary(rec)
    base, sigma = resting_stats(rec, "PAC")
    rule = analysis.DetectionRule()
    assert rule.window_s <= IMPACT_WINDOW_S, "the summary keeps shorter windows than the rule reads"
    per_sphere: dict[str, dict] = {}
    drops = [s for s in rec.scene.stimuli if isinstance(s, SphereDrop)]
    for i, s in enumerate(drops):
        if s.time_s + rule.window_s > rec.simulated_s:
            continue
        name = SPHERE_NAME.get(s.mass_kg, f"{s.mass_kg * 1e6:.3f} mg sphere")
        t, x = summary.impact_window(i)
        hit = analysis.detected_in_window(x, t, s.time_s, base, sigma, rule)
        d = per_sphere.setdefault(name, {"mass_mg": s.mass_kg * 1e6, "energy_uJ": s.energy_J * 1e6,
                                         "drops": 0, "detected": 0})
        d["drops"] += 1
        d["detected"] += int(hit)
    for d in per_sphere.values():
        d["detection_rate"] = d["detected"] / d["drops"]
    return {"rule": asdict(rule), "baseline_code": base, "resting_sigma_bits": sigma, "spheres": per_sphere}


def _stimulus_record(s) -> dict:
    from emulator.skin import Skin
    from emulator.texture import Texture

    d = {"kind": type(s).__name__}
    for k, v in vars(s).items():
        if isinstance(v, Texture):
            v = {"number": v.number, "name": v.name}
        elif isinstance(v, Skin):
            v = v.state()
        d[k] = v
    return d


def sensor_serial(spec, k: int) -> str:
    """The serial number a sensor (``spec``: a :class:`~bench.scenes.scene.SensorSpec`, ``scene.sensor_spec(k)``)
    answers as sensor ``k`` of a bus (its serial property, what a host reads): its unit's — a BioTac SP's in the
    "BTSP…" form (:func:`emulator.spi.model.variant_serial`) — or, for the nominal unit and sensors the scene does
    not describe (no serial of their own, as :func:`bench.running.runner.build_sensor` builds them), sensor ``k``'s
    default (:func:`emulator.spi.model.default_serial`)."""
    from emulator.spi.model import default_serial, variant_serial

    if spec.unit == "nominal" or not spec.serial:
        return default_serial(k, spec.variant)
    return variant_serial(spec.serial, spec.variant)


def sensor_identity(spec, k: int) -> dict:
    """Who sensor ``k`` (``spec``: its :class:`~bench.scenes.scene.SensorSpec`) is, for its record: ``unit`` (the unit
    whose parameters it has) and ``serial`` (:func:`sensor_serial`); a sensor the scene does not describe — sensor
    1's twin: its unit's parameters, but no serial of its own, so it answers its port's default — also has
    ``twin_of: 1``, so that "unit 17" beside a serial that is not unit 17's is not taken for unit 17 itself."""
    who = {"unit": spec.unit, "serial": sensor_serial(spec, k)}
    return {**who, "twin_of": 1} if not spec.serial else who


def identity_words(who: dict, quote: str = "") -> str:
    """A :func:`sensor_identity` in words: "unit 17, serial BTU0000000000017", or for a twin "sensor 1's twin (unit
    17's parameters), serial BT0101EMU0000003 (its port's default)"; the serial between ``quote``s (Markdown's
    backtick in report.md)."""
    serial = f"{quote}{who['serial']}{quote}"
    if who.get("twin_of"):
        return f"sensor {who['twin_of']}'s twin (unit {who['unit']}'s parameters), serial {serial} (its port's default)"
    return f"unit {who['unit']}, serial {serial}"


def build_record(rec: Recording, outputs: list[str], skipped: dict | None = None,
                 interrupted_by: str | None = None, sensor_index: int = 1) -> dict:
    """The JSON record of ``rec``; ``sensor_index``: which sensor of the scene ``rec`` is (sensors 2..N are run as
    one-sensor scenes, :meth:`~bench.scenes.scene.Scene.for_sensor`)."""
    sc = rec.scene
    spec = sc.sensor_spec(1)
    summary = _summary(rec)
    stats = {name: cs.stats(rec.simulated_s) for name, cs in summary.channels.items()}
    record = {
        "status": rec.status,
        "error": rec.error,
        # the whole scene: its fields as run (command-line overrides applied and named), and the file's own text
        "scene": {"name": sc.name, "source": sc.source, "description": sc.description, "seed": sc.seed,
                  "fidelity": sc.fidelity, "duration_s": sc.duration_s,
                  "overrides": dict(getattr(sc, "overrides", {}) or {}), "text": sc.text,
                  # the texture library the slides came from (path, SHA-256 of the file, shipped or one's own)
                  "library": getattr(sc, "library", None)},
        "host": {"sequence": sc.sequence, "slot_rate_Hz": sc.slot_rate_Hz, "spi_clock_Hz": sc.spi_clock_Hz,
                 "spi": sc.spi},
        "faults": dict(sc.faults),
        # the sensor: the serial is the one it answers as sensor sensor_index of a bus (bridge, Cheetah adapter)
        "sensor": {"index": sensor_index, "variant": spec.variant, **sensor_identity(spec, sensor_index)},
        "analysis": {"impact_detection": sc.impact_detection},
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
    if interrupted_by:
        record["interrupted_by"] = interrupted_by
    if skipped:
        record["skipped_outputs"] = skipped
    if "PAC" in summary.channels:
        base, sigma = resting_stats(rec, "PAC")
        record["pac_resting"] = {"baseline_code": base, "sigma_bits": sigma}
    if sc.impact_detection and any(isinstance(s, SphereDrop) for s in sc.stimuli):  # (a finger with drops to judge)
        record["impact_detection"] = impact_results(rec)
    if getattr(rec, "slides", None) or getattr(sc, "skin_before", None):
        record["sliding"] = {"skin_before": sc.skin_before, "skin_after": sc.skin_after,
                             "trials": getattr(rec, "slides", [])}
    return record


class _NoGuard:
    """Stands in for a signal guard when outputs are written from Python: never asks to stop."""

    signum = None
    signal_name = None

    def checkpoint(self):
        pass


def write_outputs(rec: Recording, out_dir, csv: bool = False, plots: bool = True, *, npz: bool | None = None,
                  samples_tmp: Path | None = None, force: bool = False, guard=None,
                  compression: str = "gzip", sensors: dict[int, dict] | None = None, sensor_index: int = 1) -> dict:
    """Write everything about ``rec`` into ``out_dir`` (a path, checked and locked here, or an open
    :class:`~bench.reporting.outdir.OutFolder`); returns the JSON record.

    ``samples_tmp``: the run's closed ``samples.h5`` under its temporary name (from a streaming run); without it,
    ``samples.h5`` is written from the recording's in-memory channels.  ``npz``: export codes.npz (and samples.csv
    when ``csv``) whatever the run's length (``True``), never (``False``), or for runs up to
    :data:`~bench.reporting.exports.EXPORT_MAX_S` (``None``).  ``guard``: a signal guard whose ``checkpoint()``
    raises (:class:`~bench.running.signals.StopRequested`, with the signal's name) to stop exports and plots
    early — :class:`~bench.running.signals.StopSignals` does so only for a signal arriving after its
    ``begin_writing()``; the record is still written, with status ``"interrupted"`` if the guard saw any signal.
    ``sensors``: a several-sensor run's records of sensors 2..N (already written into ``sensor<k>/``), listed in
    this record under ``"sensors"`` (status, error, outputs, the serial each answers); one that failed makes this
    record failed too.  ``sensor_index``: which sensor of the scene ``rec`` is (for its serial: :func:`sensor_serial`).
    """
    from bench.running.signals import StopRequested

    guard = guard or _NoGuard()
    own = not isinstance(out_dir, OutFolder)
    folder = OutFolder.open(out_dir, force=force) if own else out_dir
    outputs: list[str] = []
    skipped: dict[str, str] = {}
    problems: list[str] = []
    stopped: str | None = None  # the signal that stopped exports and plots

    def step(name: str, fn):
        nonlocal stopped
        if stopped:
            skipped[name] = f"not written: {stopped} arrived while the outputs were being written"
            return
        try:
            guard.checkpoint()
            with folder.atomic(name) as tmp:
                fn(tmp)
            outputs.append(name)
        except StopRequested as stop:
            stopped = stop.args[0] if stop.args else "a signal"
            skipped[name] = f"not written: {stopped} arrived while the outputs were being written"
        except Exception as e:
            problems.append(f"writing {name}: {type(e).__name__}: {e}")

    try:
        h5 = samples_tmp
        if h5 is None and rec.channels:
            h5 = folder.temp_path("samples.h5")
            try:
                store.write_recording(h5, rec, compression)
            except Exception as e:
                problems.append(f"writing samples.h5: {type(e).__name__}: {e}")
                os.unlink(h5)
                h5 = None
        base = baselines(rec)
        export = npz if npz is not None else rec.simulated_s <= exports.EXPORT_MAX_S
        wanted = ["codes.npz"] + (["samples.csv"] if csv else [])
        if h5 is None:
            for name in wanted:
                skipped[name] = "not written: there is no samples.h5 to export from"
        elif not export:
            why = ("not written: exports are off (--npz not given)" if npz is False else
                   f"not written: the run is longer than {exports.EXPORT_MAX_S:g} simulated s; samples.h5 holds "
                   f"every sample, or run again with --npz to force the export")
            for name in wanted:
                skipped[name] = why
        else:
            step("codes.npz", lambda tmp: exports.export_npz(h5, tmp, base, guard.checkpoint))
            if csv:
                step("samples.csv", lambda tmp: exports.export_csv(h5, tmp, base, guard.checkpoint))
        if plots and rec.simulated_s > 0:
            from bench.reporting import plots as plotting

            for name, draw in plotting.scene_plots(rec, base):
                step(name, draw)

        # commit: final status into samples.h5, then report.md, then record.json (no checkpoints from here on)
        if guard.signum is not None and rec.status == "ok":
            rec.status = "interrupted"
        if problems:
            if rec.status != "failed":
                rec.status = "failed"
            rec.error = "; ".join(([rec.error] if rec.error else []) + problems)
        interrupted_by = guard.signal_name if rec.status == "interrupted" else None
        planned = (["samples.h5"] if h5 is not None else []) + outputs + ["report.md", "record.json"]
        record = _safe_record(rec, planned, skipped, interrupted_by, sensor_index)
        if sensors:
            record["sensors"] = {f"sensor{k}": {**{key: r.get(key) for key in ("status", "error", "outputs")},
                                                **sensor_identity(rec.scene.sensor_spec(k), k)}
                                 for k, r in sorted(sensors.items())}
            for k, r in sorted(sensors.items()):
                if r.get("status") == "failed" and record["status"] != "failed":
                    _fail(record, f"sensor {k}: {r.get('error')}")
        text = markdown_report(record)
        if h5 is not None:
            try:
                store.set_status(h5, record["status"], rec.simulated_s, record["error"],
                                 interrupted_by=interrupted_by or "")
                folder.commit(h5, "samples.h5")
            except Exception as e:
                _fail(record, f"writing samples.h5: {type(e).__name__}: {e}", "samples.h5")
                text = markdown_report(record)
        try:
            folder.write_text("report.md", text)
        except Exception as e:
            _fail(record, f"writing report.md: {type(e).__name__}: {e}", "report.md")
            if "samples.h5" in record["outputs"]:  # keep samples.h5's status equal to the record's
                with contextlib.suppress(Exception):
                    store.set_status(folder.path / "samples.h5", record["status"], rec.simulated_s,
                                     record["error"])
        try:
            folder.write_text("record.json", json.dumps(record, indent=2, default=_json_default))
        except OSError as e:
            raise _record_not_written(folder, record, rec, e) from None
        return record
    finally:
        folder.remove_temps()
        if own:
            folder.close()


def _record_not_written(folder: OutFolder, record: dict, rec: Recording, e: OSError) -> OutputNotWritten:
    """record.json could not be written (the last file: a full disk, say): the files already in place are marked
    failed where that still works, and the error says that the folder is incomplete without its record — and the
    run's own error, which the record would have held (where samples that did not fit were saved, say)."""
    earlier = record.get("error")
    _fail(record, f"writing record.json: {e.strerror or e}", "record.json")
    with contextlib.suppress(Exception):
        store.set_status(folder.path / "samples.h5", record["status"], rec.simulated_s, record["error"])
    with contextlib.suppress(Exception):
        folder.write_text("report.md", markdown_report(record))
    return OutputNotWritten(f"{folder.path}/record.json could not be written ({e.strerror or e}): the run's other "
                            f"files there are incomplete without it (status \"failed\" where it could still be "
                            f"marked); make room and run again with --force"
                            + (f"; the run's error: {earlier}" if earlier else ""))


def _fail(record: dict, problem: str, missing: str | None = None) -> None:
    record["status"] = "failed"
    record["error"] = "; ".join(([record["error"]] if record.get("error") else []) + [problem])
    if missing in record["outputs"]:
        record["outputs"].remove(missing)


def _safe_record(rec: Recording, outputs: list[str], skipped: dict, interrupted_by: str | None,
                 sensor_index: int = 1) -> dict:
    """:func:`build_record`, or — if building it fails — a minimal record saying so (a record is always written)."""
    try:
        return build_record(rec, outputs, skipped, interrupted_by, sensor_index)
    except Exception as e:
        sc = rec.scene
        record = {"status": rec.status, "error": rec.error,
                  "scene": {"name": sc.name, "source": sc.source, "description": sc.description, "seed": sc.seed,
                            "fidelity": sc.fidelity, "duration_s": sc.duration_s},
                  "simulated_s": rec.simulated_s, "wall_s": rec.wall_s, "realtime_factor": rec.realtime_factor,
                  "effects": [], "channels": {}, "outputs": outputs, "skipped_outputs": skipped}
        _fail(record, f"building the record: {type(e).__name__}: {e}")
        return record


def _json_default(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)


def _or_dash(x, fmt: str) -> str:
    """``x`` in ``fmt``, or "—" for a value that is undefined (None: a sliding trial's property; record.json says
    why)."""
    return "—" if x is None else format(x, fmt)


def realtime_said(factor: float) -> str:
    """A real-time factor (simulated s per wall s) as a report says it: whole numbers from 10×, two significant
    digits below (0.44×, 3.2×: a slow run is not rounded to "0×")."""
    return f"{factor:.0f}×" if factor >= 10 else f"{factor:.2g}×"


def markdown_report(record: dict) -> str:
    sc = record["scene"]
    lines = [f"# Scene report: {sc['name']}", ""]
    if sc["description"]:
        lines += [sc["description"], ""]
    status = record["status"] + (f" by {record['interrupted_by']}" if record.get("interrupted_by") else "")
    speed = record["realtime_factor"]
    spi = {"rtl": "the Verilog RTL (C++ Verilator harness)", "software": "the software model"}.get(
        record.get("host", {}).get("spi"), "not recorded")  # (a record that could not be built holds no host)
    lines += [f"- status: **{status}**" + (f" — {record['error']}" if record["error"] else ""),
              f"- simulated {record['simulated_s']:.2f} s of {sc['duration_s']:g} s in {record['wall_s']:.2f} s wall "
              + f"({realtime_said(speed)} real time)",
              f"- fidelity `{sc['fidelity']}`, seed {sc['seed']}, SPI side: {spi}"]
    if "sensor" in record:
        who = record["sensor"]
        lines.append(f"- sensor {who['index']}: {who['variant']}, {identity_words(who, '`')}")
    if sc.get("library"):
        lib = sc["library"]
        lines.append(f"- texture library: `{lib['path']}` ({'the shipped one' if lib['shipped'] else 'the scene’s own'}"
                     f", SHA-256 `{lib['sha256'][:16]}…`)")
    if record.get("faults"):
        lines.append("- faults: " + ", ".join(f"`{k} = {v}`" for k, v in record["faults"].items()))
    lines.append("")
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
    sliding = record.get("sliding")
    if sliding and sliding["trials"]:
        lines += ["## Sliding trials (traction, roughness, fineness as D ch. 6 defines them)", "",
                  "| trial | texture | force (N) | velocity (cm/s) | ridge height (µm) | true normal force (N) | "
                  "traction (A) | roughness | fineness |", "|---|---|---|---|---|---|---|---|---|"]
        for r in sliding["trials"]:
            lines.append(f"| {r['trial']} | T{r['texture']} {r['texture_name']} | {r['force_N']:g} | "
                         f"{100 * r['velocity_m_per_s']:g} | {1e6 * (r['ridge_height_m'] or 0):.1f} | "
                         f"{r['true_normal_N']:.3f} | {r['traction']:.3f} | {_or_dash(r['roughness'], '.2f')} | "
                         f"{_or_dash(r['fineness'], '.2f')} |")
        b, a = sliding["skin_before"], sliding["skin_after"]
        lines += ["", f"Skin before: serial {b['serial']}, ridge height {1e6 * b['ridge_height_m']:.1f} µm; after: "
                      f"serial {a['serial']}, ridge height {1e6 * a['ridge_height_m']:.1f} µm "
                      f"({a['trials']} trial{'' if a['trials'] == 1 else 's'} on it, {a['sliding_distance_m']:.2f} m slid).", ""]
    lines += ["## Channels", "", "Statistics of the 12-bit ADC codes (0–4095) the host read. *At rails*: good samples "
              "reading 0 or 4095, where the signal reached the ADC's range or went beyond it (clipped); *bad*: words the "
              "host rejected (parity error or an error word), left out of the statistics.", "",
              "| channel | samples | rate (Hz) | mean | std | min | max | at rails | bad |",
              "|---|---|---|---|---|---|---|---|---|"]
    for name, s in record["channels"].items():
        if s["mean_code"] is None:
            lines.append(f"| {name} | {s['samples']} | | | | | | | {s['bad_samples']} |")
        else:
            lines.append(f"| {name} | {s['samples']} | {s['rate_Hz']:.0f} | {s['mean_code']:.1f} | "
                         f"{s['std_code']:.2f} | {s['min_code']} | {s['max_code']} | {s.get('rail_samples', 0)} | "
                         f"{s['bad_samples']} |")
    clipped = {n: s["rail_samples"] for n, s in record["channels"].items() if s.get("rail_samples")}
    if clipped:
        lines += ["", "**Clipped:** " + ", ".join(f"{n} reached the ADC's rails in {k} sample{'s' if k > 1 else ''}"
                                                  for n, k in clipped.items())
                  + " — codes there are the rail, not the signal."]
    lines += ["", "## Effects that ran", "", "| effect | what it models | ms per simulated s |", "|---|---|---|"]
    for e in record["effects"]:
        lines.append(f"| {e['name']} | {e['description']} | {1e3 * e['seconds_per_simulated_s']:.3f} |")
    lines += ["", "Outputs: " + ", ".join(f"`{o}`" for o in record["outputs"]), ""]
    for folder, r in record.get("sensors", {}).items():
        lines.append(f"- `{folder}/`: {r['status']}" + (f", serial `{r['serial']}`" if r.get("serial") else "")
                     + (f" — {r['error']}" if r.get("error") else ""))
    if record.get("sensors"):
        lines.append("")
    for name, why in record.get("skipped_outputs", {}).items():
        lines.append(f"- `{name}` {why}")
    if record.get("skipped_outputs"):
        lines.append("")
    return "\n".join(lines)
