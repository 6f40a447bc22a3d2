"""What accuracy costs in time: fidelity profiles measured against the reference profile.

For every profile and shipped scene:
  * RMS error (bits) of each kind of channel the scene reads (PAC, PDC, TDC, TAC, electrodes): the noise-free
    analog value at every conversion the scene's host makes (every sensor), against the reference profile's, over
    the whole scene (:func:`profile_errors`; committed in fixtures/fidelity/errors.json, which a test recomputes);
  * spectral error (dB): mean |ΔPSD| over 20–1000 Hz of the PAC codes (all noise on, through SPI)
    against the reference profile; the row "reference (other seed)" shows the statistical floor of
    this estimate (two noise realisations of the same model);
  * cost: wall time per simulated second of the full run through SPI.
Then throughput of the full 44-slot frame, the demand-driven saving of reading only PAC, the cost of each of
issue 10's effects (:func:`effect_costs`: the full frame with and without it), and the peak memory of streaming
one simulated hour (in a subprocess, so the number is the stream's own).
"""

from __future__ import annotations

import copy
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from bench.errors import escaped
from bench.verification import analysis
from bench.running.runner import build_sensor, run_scene
from bench.running.sampler import Sampler
from bench.paths import FIXTURES, REPO, SCENES_DIR
from bench.scenes.scene import load_scene
from emulator.channels import DEFAULT_FRAME_NAMES, DEFAULT_VARIANT, ELECTRODE_FIRST, PAC, PDC, TAC, TDC
from emulator.conversions import ADC_LSB_V
from emulator.fidelity import PROFILES
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.spi.peripheral import SoftwarePeripheral



#: the kinds of channel whose error :func:`profile_errors` measures, each over every conversion of that kind
ERROR_KINDS = ("PAC", "PDC", "TDC", "TAC", "electrodes")
#: each of :data:`ERROR_KINDS` as a column of the printed tables (the fidelity table, the sliding one)
ERROR_KIND_COLUMNS = {"PAC": "PAC", "PDC": "PDC", "TDC": "TDC", "TAC": "TAC", "electrodes": "E"}


def _conversions(scene) -> tuple[np.ndarray, np.ndarray]:
    """The instants (s) and channel indices of every conversion the host of ``scene`` (one sensor) makes, in order."""
    sampler = Sampler(None, scene.sequence, scene.slot_rate_Hz, scene.spi_clock_Hz)
    _, t_sampled, channel = sampler.slots(np.arange(int(round(scene.duration_s * scene.slot_rate_Hz))))
    return t_sampled, channel


def _kind_masks(channels: np.ndarray) -> dict[str, np.ndarray]:
    """For each of :data:`ERROR_KINDS` that ``channels`` holds: where it sits (a boolean mask)."""
    masks = {"PAC": channels == PAC, "PDC": channels == PDC, "TDC": channels == TDC, "TAC": channels == TAC,
             "electrodes": channels >= ELECTRODE_FIRST}
    return {kind: masks[kind] for kind in ERROR_KINDS if masks[kind].any()}


def _noise_free_bits(scene, fidelity: str, times: np.ndarray, channels: np.ndarray) -> np.ndarray:
    """The noise-free analog value (ADC LSB, before quantization) of every conversion of one-sensor ``scene`` at
    ``fidelity``, asked for as its host asks: a second of conversions at a time, in the frame's order (the electrode
    multiplexer remembers the order)."""
    scene.fidelity, scene.noise = fidelity, NoiseSources.none()
    sensor = build_sensor(scene)
    out = np.empty(times.size)
    step = max(1, int(round(scene.slot_rate_Hz)))
    for i in range(0, times.size, step):
        out[i:i + step] = sensor.analog(channels[i:i + step], times[i:i + step])
    return out / ADC_LSB_V


def profile_errors(scene, profiles=tuple(PROFILES)) -> dict[str, dict[str, float]]:
    """Each profile's deterministic error against ``reference`` on ``scene`` (a scene file's path, or a
    :class:`~bench.scenes.scene.Scene`, which is left as it is: each profile measures a copy): {profile: {kind: RMS
    error in bits}}, for every kind of :data:`ERROR_KINDS` the scene's host reads, over every conversion of that
    kind of every sensor of the scene (noise off; the analog value before quantization, in ADC LSB)."""
    def fresh():
        """A new copy of the scene (measuring one sets its fidelity and noise)."""
        return load_scene(scene) if isinstance(scene, (str, Path)) else copy.deepcopy(scene)

    diffs: dict[str, dict[str, list]] = {name: {} for name in profiles}
    for k in range(1, fresh().n_sensors + 1):
        times, channels = _conversions(fresh().for_sensor(k))
        masks = _kind_masks(channels)
        ref = _noise_free_bits(fresh().for_sensor(k), "reference", times, channels)
        for name in profiles:
            d = (np.zeros(ref.size) if name == "reference"
                 else _noise_free_bits(fresh().for_sensor(k), name, times, channels) - ref)
            for kind, sel in masks.items():
                diffs[name].setdefault(kind, []).append(d[sel])
    return {name: {kind: float(np.sqrt(np.mean(np.concatenate(parts) ** 2))) for kind, parts in per.items()}
            for name, per in diffs.items()}


def _noisy_run(scene, fidelity: str, seed: int):
    scene.fidelity, scene.noise, scene.seed = fidelity, NoiseSources(), seed
    rec = run_scene(scene, progress=False)
    pac = rec.channels["PAC"].codes.astype(float) if "PAC" in rec.channels else None
    return pac, rec.wall_s / rec.simulated_s


def _spectral_error_dB(x: np.ndarray, ref: np.ndarray, fs: float) -> float:
    f, a = analysis.welch_db(x - x.mean(), fs)
    _, b = analysis.welch_db(ref - ref.mean(), fs)
    band = (f >= 20) & (f <= 1000)
    return float(np.mean(np.abs(a[band] - b[band])))


def fidelity_table(progress=print, scenes=None) -> list[dict]:
    """One row per scene (``scenes``: scene files; default every shipped scene) and profile: ``error_bits``
    (:func:`profile_errors`: each channel kind's noise-free RMS error against ``reference``, bits; PAC's also as
    ``pac_rms_error_bits``), the spectral error of PAC (dB; None if the scene reads no PAC) and the measured wall
    time per simulated second of the full noisy run through SPI; then a "reference (other seed)" row: the spectral
    estimate's own floor."""
    rows = []
    for path in (sorted(SCENES_DIR.glob("*.toml")) if scenes is None else scenes):
        base = load_scene(path)
        progress(f"… {base.name}: noise-free errors")
        errors = profile_errors(path)
        spectral = "PAC" in base.channels
        times, channels = _conversions(base)
        pac_rate = np.count_nonzero(channels == PAC) / base.duration_s
        ref_noisy, ref_cost = _noisy_run(load_scene(path), "reference", base.seed)
        for name in PROFILES:
            progress(f"… {base.name} / {name}")
            if name == "reference":
                spec, cost = 0.0 if spectral else None, ref_cost
            else:
                noisy, cost = _noisy_run(load_scene(path), name, base.seed)
                spec = _spectral_error_dB(noisy, ref_noisy, pac_rate) if spectral else None
            rows.append({"scene": base.name, "profile": name, "error_bits": errors[name],
                         "pac_rms_error_bits": errors[name].get("PAC"), "spectral_error_dB": spec,
                         "wall_ms_per_sim_s": 1e3 * cost, "realtime_factor": 1.0 / cost})
        other, _ = _noisy_run(load_scene(path), "reference", base.seed + 1)
        rows.append({"scene": base.name, "profile": "reference (other seed)", "error_bits": None,
                     "pac_rms_error_bits": None,
                     "spectral_error_dB": _spectral_error_dB(other, ref_noisy, pac_rate) if spectral else None,
                     "wall_ms_per_sim_s": None, "realtime_factor": None})
    return rows


def stream_realtime_factor(fidelity: str, channels, sequence, slot_rate_Hz: float, seconds: float,
                           stimuli=(), repeats: int = 3, params: SensorParams | None = None,
                           noise: NoiseSources = NoiseSources(), variant: str = DEFAULT_VARIANT) -> dict:
    """Throughput of streaming ``seconds`` of samples through SPI, in 1 s host batches: the fastest of ``repeats``
    runs, each with a fresh sensor (another process on the machine only ever slows a run down, so the fastest run is
    the code's own speed; every run's factor is kept), with that run's process CPU time beside its wall time.
    ``params`` (default nominal), ``noise`` and ``variant`` build the sensor; ``markers`` in the result says what that
    sensor ran (:func:`effect_markers`)."""
    runs = []
    for _ in range(max(1, int(repeats))):
        sensor = Sensor(params, list(stimuli), channels, fidelity, seed=1, noise=noise, variant=variant)
        sampler = Sampler(SoftwarePeripheral(sensor), sequence, slot_rate_Hz)
        per_batch = int(slot_rate_Hz)
        t0, c0 = time.perf_counter(), time.process_time()
        for _ in range(int(seconds)):
            sampler.read(per_batch)
        runs.append((time.perf_counter() - t0, time.process_time() - c0, sensor))
    wall, cpu, sensor = min(runs, key=lambda r: r[0])
    report = sensor.effects_report()
    slow = {"thermal_network", "thermal_steady_state", "electrodes"}
    modality_ms = {"pressure path (grid effects)": 1e3 * sum(e["seconds"] for e in report if e["name"] not in slow)}
    for e in report:
        if e["name"] in slow:
            modality_ms[e["name"].replace("_", " ")] = 1e3 * e["seconds"]
    modality_ms["SPI, ADC and host (the rest)"] = 1e3 * wall - sum(modality_ms.values())
    slots = sampler.sequence.size
    return {"fidelity": fidelity, "sequence": f"default {slots}-slot frame" if sequence == "default" else sequence,
            "slot_rate_Hz": slot_rate_Hz, "frame_slots": slots,
            "simulated_s": seconds, "wall_s": wall, "realtime_factor": seconds / wall,
            "cpu_realtime_factor": seconds / max(cpu, 1e-9), "runs": [seconds / r[0] for r in runs],
            "effects": [e["name"] for e in report], "markers": effect_markers(sensor),
            "grid_ms_per_simulated_s": {e["name"]: 1e3 * e["seconds"] / seconds for e in report},
            "ms_per_simulated_s": {k: v / seconds for k, v in modality_ms.items()}}


def effect_markers(sensor: Sensor) -> dict:
    """What ``sensor`` runs of issue 10's effects, read from the sensor itself: the skin's creep ratio
    (instantaneous/relaxed pressure of its force coupling; 1 = elastic skin; None: no force path), the ADC's
    per-conversion noise terms (input V, reference relative RMS, PAC path V), the mains-hum components (Hz; empty:
    hum off), the unit's electrode-gap spread (mm) and seed (0 mm: the nominal unit's equal gaps), the variant and
    its electrode count."""
    coupling = next((e for e in sensor.graph.effects if e.name == "force_coupling"), None)
    hum = next((e for e in sensor.graph.effects if e.name == "mains_hum"), None)
    p = sensor.params
    return {"skin_creep_ratio": None if coupling is None else float(coupling.creep.ratio),
            "adc_noise": {"input_V": sensor.adc.noise_V, "reference_relative": sensor.adc.reference_rel,
                          "pac_path_V": sensor.adc.pac_V},
            "mains_hum_Hz": [] if hum is None else [float(f) for f, _, _ in hum.components],
            "electrode_gap": {"spread_mm": float(p.electrode_gap_spread_mm), "seed": int(p.electrode_gap_seed)},
            "variant": sensor.variant.name, "electrodes": sensor.variant.n_electrodes}


def _runs(r: dict) -> str:
    """"best of 3 runs: 1012, 987, 1120×; CPU 1130×" for a :func:`stream_realtime_factor` result."""
    return (f"best of {len(r['runs'])} runs: {', '.join(f'{x:.0f}' for x in r['runs'])}×; "
            f"that run's CPU time {r['cpu_realtime_factor']:.0f}×")


#: the drawn unit of the per-effect table (any seed: a unit's spreads change values, not the work done)
EFFECT_UNIT_SEED = 17
#: the full frame's target (issue 10, Performance: the default full frame stays ≥ 1000× real time)
FULL_FRAME_TARGET_X = 1000.0


def _repeated_presses(seconds: float) -> list:
    """The presses-grid scene's twelve 1 N touches (PDC and the touched electrodes creep under each), repeated every
    scene duration (19.5 s) so that they cover ``seconds``."""
    import dataclasses

    scene = load_scene(SCENES_DIR / "presses_grid.toml")
    repeats = max(1, int(np.ceil(seconds / scene.duration_s)))
    return [dataclasses.replace(s, start=s.start + k * scene.duration_s)
            for k in range(repeats) for s in scene.stimuli]


def _effect_configs(seconds: float) -> dict[str, dict]:
    """The sensors the per-effect table streams, by name: keyword arguments of :func:`stream_realtime_factor`."""
    from emulator.channels import variant
    from emulator.units import unit

    nominal = SensorParams()
    presses = _repeated_presses(seconds)
    return {
        "rest": {},
        "presses": {"stimuli": presses},
        "presses, elastic skin": {"stimuli": presses, "params": nominal.replace(skin_relaxed_modulus_fraction=1.0)},
        "rest, one ADC noise": {"params": nominal.replace(adc_reference_noise_ppm=0.0, pac_path_noise_rms_bits=0.0)},
        "rest, hum fundamental only": {"params": nominal.replace(mains_harmonic2_ratio=0.0, mains_harmonic3_ratio=0.0)},
        "rest, hum off": {"noise": NoiseSources(mains_hum=False)},
        f"rest, unit {EFFECT_UNIT_SEED}": {"params": unit(EFFECT_UNIT_SEED).params},
        "rest, BioTac SP": {"variant": "biotac-sp", "channels": variant("biotac-sp").frame_names},
    }


#: (effect, configuration with it, configuration without it, the :func:`effect_markers` key that tells them apart)
EFFECT_ROWS = (
    ("viscoelastic skin (E∞/E0 0.6) vs elastic (1.0)", "presses", "presses, elastic skin", "skin_creep_ratio"),
    ("per-channel ADC noise vs one ADC noise", "rest", "rest, one ADC noise", "adc_noise"),
    ("mains hum + 2nd, 3rd harmonic vs fundamental", "rest", "rest, hum fundamental only", "mains_hum_Hz"),
    ("mains hum + harmonics vs hum off", "rest", "rest, hum off", "mains_hum_Hz"),
    (f"drawn unit (seed {EFFECT_UNIT_SEED}) vs nominal unit", f"rest, unit {EFFECT_UNIT_SEED}", "rest", "electrode_gap"),
    ("BioTac SP (54 slots) vs BioTac (44 slots)", "rest, BioTac SP", "rest", "variant"),
)


def _ms_per_simulated_s(realtime_factor: float) -> float:
    """Wall time (ms) per simulated second of a run at ``realtime_factor``× real time."""
    return 1e3 / realtime_factor


def _run_spread_ms(r: dict) -> float:
    """How far the second-fastest run of a :func:`stream_realtime_factor` result lies behind the fastest, in ms per
    simulated s: the timing's own scatter (0 with a single run)."""
    fastest = sorted(r["runs"], reverse=True)
    return _ms_per_simulated_s(fastest[1]) - _ms_per_simulated_s(fastest[0]) if len(fastest) > 1 else 0.0


def creep_filter_ms_per_simulated_s(seconds: float, fidelity: str = "default", repeats: int = 3) -> float:
    """Wall time (ms per simulated s) of the skin's creep filter alone (the nominal standard linear solid) on the
    grid of ``fidelity`` in the sensor's 2 s blocks: the fastest of ``repeats`` runs.  PDC's force path runs it once;
    each touching contact runs one more at the electrode rate."""
    from emulator.fidelity import profile
    from emulator.mechanics import skin_fluid
    from emulator.viscoelastic import Creep

    sf, fs = skin_fluid(SensorParams()), profile(fidelity).grid_Hz
    block = np.linspace(0.0, 1.0, int(round(2.0 * fs)))  # a force ramp (N): the filter's work does not depend on it
    blocks = max(1, int(np.ceil(seconds / 2.0)))
    best = np.inf
    for _ in range(max(1, int(repeats))):
        creep = Creep.standard_linear_solid(sf.creep_time_s, sf.creep_ratio)
        t0 = time.perf_counter()
        for _ in range(blocks):
            creep.step(block, fs)
        best = min(best, time.perf_counter() - t0)
    return 1e3 * best / (2.0 * blocks)


#: the per-effect table measures every configuration in turn this many times and keeps each one's fastest result:
#: the machine's speed drifts within a minute, and alternating spreads that drift over all of them alike (the first
#: round also compiles what a configuration needs for the first time)
EFFECT_ROUNDS = 5


def effect_costs(seconds: float = 60.0, repeats: int = 3, rounds: int = EFFECT_ROUNDS, say=lambda m: None) -> dict:
    """Issue 10's per-effect cost table: the default full frame through SPI (default profile, 4.4 kHz slots) with and
    without each new effect, each the fastest of ``repeats`` runs of ``seconds`` simulated s
    (:func:`stream_realtime_factor`), in ``rounds`` alternating rounds (the fastest round kept).  The skin's creep
    runs under repeated 1 N touches, the rest at rest.  Per row: both factors, the difference in ms per simulated s
    (with − without), the larger run scatter of the two, and both sensors' markers (:func:`effect_markers`) showing
    the effect ran in one and not the other."""
    t0 = time.perf_counter()
    configs, options_by_name = {}, _effect_configs(seconds)
    for k in range(max(1, int(rounds))):
        for name, options in options_by_name.items():
            say(f"… effect costs, round {k + 1}: {name}")
            options = {"channels": DEFAULT_FRAME_NAMES, **options}
            r = stream_realtime_factor("default", options.pop("channels"), "default", 4400.0, seconds,
                                       repeats=repeats, **options)
            if name not in configs or r["realtime_factor"] > configs[name]["realtime_factor"]:
                configs[name] = r
    rows = []
    for effect, with_name, without_name, marker in EFFECT_ROWS:
        w, wo = configs[with_name], configs[without_name]
        rows.append({"effect": effect, "with": with_name, "without": without_name,
                     "with_realtime_factor": w["realtime_factor"], "without_realtime_factor": wo["realtime_factor"],
                     "delta_ms_per_simulated_s": _ms_per_simulated_s(w["realtime_factor"])
                     - _ms_per_simulated_s(wo["realtime_factor"]),
                     "scatter_ms_per_simulated_s": max(_run_spread_ms(w), _run_spread_ms(wo)),
                     "marker": marker, "marker_with": w["markers"][marker], "marker_without": wo["markers"][marker]})
    per_slot = {name: {"us_per_slot": 1e6 / (configs[name]["realtime_factor"] * configs[name]["slot_rate_Hz"]),
                       "frame_slots": configs[name]["frame_slots"]} for name in ("rest", "rest, BioTac SP")}
    for v in per_slot.values():
        v["us_per_frame"] = v["us_per_slot"] * v["frame_slots"]
    rest = configs["rest"]["realtime_factor"]
    return {"simulated_s": seconds, "repeats": repeats, "rounds": rounds, "configs": configs, "rows": rows, "per_slot": per_slot,
            "creep_filter_ms_per_simulated_s": creep_filter_ms_per_simulated_s(seconds),
            "full_frame": {"realtime_factor": rest, "target": FULL_FRAME_TARGET_X, "met": rest >= FULL_FRAME_TARGET_X},
            "wall_s": time.perf_counter() - t0}


def effect_cost_lines(e: dict) -> list[str]:
    """The per-effect cost table of an :func:`effect_costs` result, as printed lines."""
    rest = e["configs"]["rest"]
    lines = [f"Cost of each realism effect (units, noise sources, local electrodes, creep, Hertz impacts, variants): "
             f"default full frame through SPI, default profile, 4.4 kHz slots; best of {e['rounds']} rounds × "
             f"{e['repeats']} runs of {e['simulated_s']:g} simulated s each",
             f"  {'effect':48s} {'stimulus':9s} {'with ×':>8s} {'without ×':>10s} {'Δ ms / sim s':>13s} "
             f"{'scatter':>8s}"]
    for r in e["rows"]:
        lines.append(f"  {r['effect']:48s} {r['with'].split(',')[0]:9s} {r['with_realtime_factor']:8.0f} "
                     f"{r['without_realtime_factor']:10.0f} {r['delta_ms_per_simulated_s']:+13.3f} "
                     f"{r['scatter_ms_per_simulated_s']:8.3f}")
    sp, bt = e["per_slot"]["rest, BioTac SP"], e["per_slot"]["rest"]
    full = e["full_frame"]
    lines += ["  (scatter: the larger of the two configurations' gaps between their fastest and second-fastest run, ms "
              "per simulated s; a Δ within it is no measurable cost)",
              f"  BioTac SP: {sp['us_per_slot']:.3f} µs per slot, {sp['us_per_frame']:.1f} µs per {sp['frame_slots']}-slot "
              f"frame; BioTac: {bt['us_per_slot']:.3f} µs per slot, {bt['us_per_frame']:.1f} µs per "
              f"{bt['frame_slots']}-slot frame",
              f"  the skin's creep filter alone: {e['creep_filter_ms_per_simulated_s']:.3f} ms per simulated s on the "
              f"grid (PDC's force path; one more per touching contact at the electrode rate); an elastic skin runs the "
              f"same filter with a zero weight (the code has no switch that skips it)",
              f"  default full frame at rest, every effect on: {full['realtime_factor']:.0f}× real time ({_runs(rest)}); "
              f"target ≥ {full['target']:.0f}×: {'met' if full['met'] else 'NOT met'}"]
    return lines


def _own_peak_MB() -> float:
    """This process's peak resident memory since its exec (VmHWM), MB. ``ru_maxrss`` would also count the pages a
    child forked from the (large) benchmark process started with."""
    with open("/proc/self/status") as f:
        return float(next(line.split()[1] for line in f if line.startswith("VmHWM:"))) / 1024.0


def stream_hour_child(seconds: float) -> None:
    """Entry point of the memory subprocess: stream, keep running statistics only, print JSON."""
    sensor = Sensor(None, [], DEFAULT_FRAME_NAMES, "default", seed=1)
    sampler = Sampler(SoftwarePeripheral(sensor), "default", 4400.0)
    n = 0
    total = 0.0
    t0 = time.perf_counter()
    for _ in range(int(seconds)):
        s = sampler.read(4400)
        pac = s.codes[s.channels == PAC]
        n += pac.size
        total += float(pac.sum())
    wall = time.perf_counter() - t0
    peak_MB = _own_peak_MB()
    print(json.dumps({"simulated_s": seconds, "wall_s": wall, "realtime_factor": seconds / wall,
                      "peak_rss_MB": peak_MB, "pac_mean": total / n}))


def stream_hour(seconds: float = 3600.0) -> dict:
    code = f"from bench.verification.benchmark import stream_hour_child; stream_hour_child({seconds!r})"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=REPO)
    return json.loads(out.stdout.strip().splitlines()[-1])


#: runs ``biotac-bench <args>`` and writes the process's peak resident memory (kB, VmHWM) to the file in argv[1]
_RUN_AND_REPORT_HWM = """
import atexit, runpy, sys
report = sys.argv[1]
def _hwm():
    with open('/proc/self/status') as f:
        kb = next(line.split()[1] for line in f if line.startswith('VmHWM:'))
    with open(report, 'w') as out:
        out.write(kb)
atexit.register(_hwm)
sys.argv = ['biotac-bench'] + sys.argv[2:]
runpy.run_module('bench.cli', run_name='__main__', alter_sys=True)
"""


def run_memory(short_s: float = 60.0, long_s: float = 36000.0, say=print) -> dict:
    """Peak RSS of ``biotac-bench run`` (full 44-slot frame at rest, samples.h5 and plots) for ``short_s`` and
    ``long_s`` simulated seconds, each in its own child process (``os.wait4`` returns that child's own peak).

    Target: the long run at the short run's peak within 20 %, both at most 300 MB.
    """
    import tempfile
    from pathlib import Path

    runs = {}
    with tempfile.TemporaryDirectory(prefix="biotac-run-memory-") as tmp:
        for seconds in (short_s, long_s):
            scene = Path(tmp) / f"rest_{seconds:g}s.toml"
            scene.write_text(f'[scene]\nname = "rest-memory"\nduration_s = {float(seconds)!r}\nseed = 1\n'
                             f'[host]\nsequence = "default"\n')
            out, log = Path(tmp) / f"out_{seconds:g}s", Path(tmp) / f"log_{seconds:g}s.txt"
            t0 = time.perf_counter()
            hwm = Path(tmp) / f"hwm_{seconds:g}s.txt"
            with log.open("w") as err:
                # the child reports its own high-water mark (VmHWM of its image after exec): the rusage of a
                # child forked from this (large) benchmark process counts the parent's pages it started with
                p = subprocess.Popen([sys.executable, "-c", _RUN_AND_REPORT_HWM, str(hwm), "run", str(scene),
                                      "--out", str(out), "--quiet"], cwd=REPO, stdout=subprocess.DEVNULL, stderr=err)
                p.wait()
            if p.returncode != 0:
                raise RuntimeError(f"run of {seconds:g} s failed ({p.returncode}): {log.read_text()[-2000:]}")
            runs[seconds] = {"simulated_s": seconds, "wall_s": time.perf_counter() - t0,
                             "peak_rss_MB": float(hwm.read_text()) / 1024.0,
                             "outputs": sorted(f.name for f in out.iterdir() if not f.name.startswith("."))}
    short, long_ = runs[short_s], runs[long_s]
    res = {"short": short, "long": long_, "ratio": long_["peak_rss_MB"] / short["peak_rss_MB"],
           "target_MB": 300.0, "target_ratio": 1.2}
    res["met"] = max(short["peak_rss_MB"], long_["peak_rss_MB"]) <= 300.0 and abs(res["ratio"] - 1.0) <= 0.2
    if say:
        say(f"`run` with samples.h5 and plots, full 44-slot frame at rest: {short_s:g} s peak RSS "
            f"{short['peak_rss_MB']:.0f} MB ({short['wall_s']:.1f} s wall), {long_s:g} s peak RSS "
            f"{long_['peak_rss_MB']:.0f} MB ({long_['wall_s']:.1f} s wall); ratio {res['ratio']:.2f} "
            f"(target ≤ 300 MB, equal within 20 %: {'met' if res['met'] else 'NOT met'})")
    return res


def spi_paths(rtl: bool = True, say=lambda m: None) -> dict:
    """Throughput of each implementation of the sensor's SPI side on the default frame (1 sensor)."""
    from emulator.spi.model import SELECT_CODE, Bus, SensorPort, Transfer
    from emulator.spi import protocol as proto

    out = {}
    say("… SPI: software model")
    r = stream_realtime_factor("default", DEFAULT_FRAME_NAMES, "default", 4400.0, 20.0)
    out["software_vectorized"] = {"realtime_factor": r["realtime_factor"],
                                  "transactions_per_s": 4400.0 * r["realtime_factor"], "includes_physics": True}
    sensor = Sensor(None, [], DEFAULT_FRAME_NAMES, "default", seed=1)
    bus = Bus({1: SensorPort(sensor)})
    seq = Sampler(None).sequence
    n = 4400
    t0 = time.perf_counter()
    for k in range(n):
        t = k / 4400.0
        bus.transfer(Transfer(t, SELECT_CODE[1], int(proto.sample_command(int(seq[k % 44]))) << 8, 16))
        bus.transfer(Transfer(t + 16.5 / 4.4e6 + 50e-6, SELECT_CODE[1], 0, 16))
    wall = time.perf_counter() - t0
    out["software_transfer_level"] = {"realtime_factor": 1.0 / wall, "transactions_per_s": n / wall,
                                      "includes_physics": True}
    if rtl:
        from emulator.rtl.harness import Harness
        from emulator.rtl.runner import Rtl

        say("… SPI: RTL under cocotb")
        cocotb_rtl = Rtl()
        cocotb_rtl.build()
        c = cocotb_rtl.stream_frames(1.0)
        out["rtl_cocotb"] = {"realtime_factor": c["simulated_s"] / c["wall_s"],
                             "transactions_per_s": c["slots"] / c["wall_s"], "includes_physics": True}
        say("… SPI: RTL through the C++ harness")
        h = Harness()
        h.build()
        res = h.stream_frames(20.0)
        out["rtl_cpp_harness"] = {"realtime_factor": res["simulated_s"] / res["wall_s"],
                                  "transactions_per_s": 4400.0 * res["simulated_s"] / res["wall_s"],
                                  "includes_physics": False, "evals": res["evals"]}
    return out


def firmware_paths(say=lambda m: None) -> dict:
    """Bridge firmware co-simulated in virtual time, and the driver keeping up through a pty."""
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.cosim import CoSim, VirtualBoard, default_sensors
    from bench.hosts.driver import CMD_START, BridgeDriver, FrameParser, encode

    out = {}
    for n in (1, 3):
        say(f"… firmware co-simulation, {n} sensor(s)")
        parser = FrameParser()
        board = VirtualBoard(default_sensors(n), uart_out=lambda b: parser.feed(b))
        sim = CoSim(board)
        board.send_to_firmware(encode(CMD_START))
        t0 = time.perf_counter()
        sim.run(10.0)
        wall = time.perf_counter() - t0
        out[f"cosim_{n}_sensors"] = {"realtime_factor": 10.0 / wall, "frames": parser.stats.frames}
    say("… driver at 10x real-time pacing, 3 sensors")
    with FirmwareBench(3, realtime=True, speed=10.0) as fb:
        drv = BridgeDriver(fb.port)
        drv.start()
        drv.wait_for(CMD_START)
        t0 = time.perf_counter()
        frames = list(drv.frames(max_frames=1000, timeout_s=10))
        wall = time.perf_counter() - t0
        drv.close()
    st = drv.parser.stats
    out["driver_3_sensors_10x"] = {"frames": len(frames), "wall_s": wall, "frames_per_s": len(frames) / wall,
                                   "dropped": st.dropped_frames, "crc_errors": st.crc_errors}
    say("… Cheetah-compatible library with the example client")
    import subprocess

    from bench.hosts.cheetah_server import CheetahBench, build_client

    with CheetahBench(3) as cb:
        exe = build_client(cb.library)
        t0 = time.perf_counter()
        subprocess.run([str(exe), "200"], capture_output=True, env=cb.env, check=True, timeout=600)
        wall = time.perf_counter() - t0
        out["cheetah_3_sensors"] = {"simulated_s": cb.t, "wall_s": wall, "realtime_factor": cb.t / wall}
    return out


def _channel_codes(rec):
    """(sensor number, channel name, codes) for every channel of every sensor of ``rec``, sensor 1 first."""
    for number, r in [(1, rec)] + sorted(rec.sensors.items()):
        for name in r.channels:
            yield number, name, np.ascontiguousarray(r.channels[name].codes)


def scene_code_fingerprints(scenes_dir=SCENES_DIR, profiles=("fast", "default", "reference"),
                            seed_offsets=(0, 1, 5, 11), reference_cap_s: float = 30.0, say=print) -> dict[str, str]:
    """A fingerprint (sha256 of every channel's codes, every sensor) per shipped scene × profile × seed (the scene's
    own plus ``seed_offsets``), the reference profile over its first ``reference_cap_s`` s: two trees' fingerprints
    compared show whether a change (a faster path) left every code as it was."""
    import hashlib

    out = {}
    for path in sorted(scenes_dir.glob("*.toml")):
        for fidelity in profiles:
            for offset in seed_offsets:
                scene = load_scene(path)
                scene.fidelity, scene.seed = fidelity, scene.seed + offset
                if fidelity == "reference":
                    scene.duration_s = min(scene.duration_s, reference_cap_s)
                rec = run_scene(scene, progress=False, keep_samples=True)
                h = hashlib.sha256()
                for _, name, codes in _channel_codes(rec):
                    h.update(name.encode())
                    h.update(codes.tobytes())
                key = f"{path.stem}/{fidelity}/seed+{offset}"
                out[key] = f"{h.hexdigest()[:16]} {rec.status}"
                say(f"{key:44s} {out[key]}")
    return out


#: the committed codes of the shipped scenes that do not slide (issue 8: adding sliding leaves them bit for bit);
#: bench/tests/test_scene_fingerprints.py recomputes them
SCENE_FINGERPRINT_FIXTURE = FIXTURES / "fingerprints" / "scenes_default.json"
SCENE_FINGERPRINT_COMMAND = ".venv/bin/python -m bench.verification.benchmark --write-fixture"


def scene_slides(scene) -> bool:
    """Whether any sensor of ``scene`` has a slide or a skin replacement (the sliding path: texture, friction,
    skin wear)."""
    from bench.scenes.scene import SkinReplacement
    from emulator.sliding import Slide

    return any(isinstance(s, (Slide, SkinReplacement))
               for k in range(1, scene.n_sensors + 1) for s in scene.sensor_spec(k).stimuli)


def channel_fingerprints(scene) -> dict:
    """Run ``scene`` as it is (profile, seed) and fingerprint each channel: {"status": run status, "channels":
    {"sensor<k>/<channel>": {"codes": how many, "sha256": first 16 hex digits of the codes as little-endian
    int32}}}."""
    import hashlib

    rec = run_scene(scene, progress=False, keep_samples=True)
    channels = {}
    for number, name, codes in _channel_codes(rec):
        if codes.size == 0 and rec.status == "ok":
            raise ValueError(f"scene {scene.name}: sensor {number} channel {name} kept no codes to fingerprint")
        as_int32 = np.asarray(codes, dtype="<i4")
        channels[f"sensor{number}/{name}"] = {"codes": int(codes.size),
                                             "sha256": hashlib.sha256(as_int32.tobytes()).hexdigest()[:16]}
    return {"status": rec.status, "channels": channels}


def non_sliding_scene_fingerprints(scenes_dir=SCENES_DIR, fidelity: str = "default") -> dict[str, dict]:
    """:func:`channel_fingerprints` of every shipped scene that does not slide, at ``fidelity`` and the scene's own
    seed, by scene file stem (about 3 s at the default profile)."""
    out = {}
    for path in sorted(scenes_dir.glob("*.toml")):
        scene = load_scene(path)
        if not scene_slides(scene):
            scene.fidelity = fidelity
            out[path.stem] = channel_fingerprints(scene)
    return out


def fingerprint_environment() -> dict:
    """The versions and machine the codes were computed with (a mismatch elsewhere may be floating point)."""
    import platform

    import numba
    import scipy

    return {"python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
            "numba": numba.__version__, "machine": platform.machine()}


def write_json(path: Path, doc) -> None:
    """Write ``doc`` to ``path`` as indented JSON (UTF-8), its folder made if need be, whole or not at all
    (:func:`bench.atomic.atomic_write`): a write that fails or is stopped (a full disk, Ctrl-C) leaves an earlier
    file there as it was and no temporary file.  Raises :class:`OSError` naming ``path``."""
    from bench.atomic import atomic_write

    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path) as tmp:
        tmp.write_text(json.dumps(doc, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")


def write_scene_fingerprint_fixture(path=None) -> dict:
    """Recompute the non-sliding scenes' fingerprints and write them to ``path`` (default
    :data:`SCENE_FINGERPRINT_FIXTURE`; do it only for an intended change of their codes, and say why in the
    commit)."""
    path = SCENE_FINGERPRINT_FIXTURE if path is None else path
    doc = {"about": "Codes of the shipped scenes that do not slide (fixtures/scenes/*.toml without a slide or skin "
                    "replacement on any sensor), default profile, each scene's own seed: per channel the number of "
                    "codes and the first 16 hex digits of the sha256 of the codes as little-endian int32. "
                    "bench/tests/test_scene_fingerprints.py recomputes them: any change of these codes fails there "
                    "(issue 8 item 8: sliding leaves scenes without sliding unchanged bit for bit).",
           "regenerate": f"only for an intended change of these codes, said in the commit message: "
                         f"{SCENE_FINGERPRINT_COMMAND}",
           "profile": "default",
           "made_with": fingerprint_environment(),
           "scenes": non_sliding_scene_fingerprints()}
    write_json(path, doc)
    return doc


#: each profile's noise-free error against ``reference`` on every shipped scene (:func:`profile_errors`): the errors
#: the project states; bench/tests/test_fidelity_errors.py recomputes them
FIDELITY_ERROR_FIXTURE = FIXTURES / "fidelity" / "errors.json"
FIDELITY_ERROR_COMMAND = ".venv/bin/python -m bench.verification.benchmark --write-fidelity-errors"


def source_revision(repo: Path = REPO) -> dict:
    """Where in the project's history a measurement was made: the commit the working tree of ``repo`` is at
    (``commit``: 40 hex digits, None outside a git checkout) and the tracked files it had changed on top of that
    commit (``uncommitted``: relative paths, sorted; the measured fixture itself is left out)."""
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=repo, capture_output=True, text=True, check=True)
        diff = subprocess.run(["git", "diff", "--name-only", "--no-renames", "-z", "HEAD"], cwd=repo,
                              capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        return {"commit": None, "uncommitted": []}
    fixture = str(FIDELITY_ERROR_FIXTURE.relative_to(REPO))
    changed = sorted({name for name in diff.stdout.split("\0") if name} - {fixture})
    return {"commit": head.stdout.strip(), "uncommitted": changed}


def write_fidelity_error_fixture(path=None, say=print, remake=None) -> dict:
    """Recompute :func:`profile_errors` for every shipped scene, or only for the scenes named in ``remake`` (their
    file names without ``.toml``), and write them to ``path`` (default :data:`FIDELITY_ERROR_FIXTURE`; only for an
    intended change of a profile's error, said in the commit).  Each scene's entry in ``made`` says what it was
    measured with: the date (UTC), :func:`source_revision` and :func:`fingerprint_environment`; a partial remake
    keeps the other scenes' errors and their ``made`` entries as they were.  Raises :class:`ValueError` (one line,
    nothing written) for a name that is not a shipped scene, or a partial remake of a file without per-scene
    ``made`` entries."""
    path = FIDELITY_ERROR_FIXTURE if path is None else Path(path)
    shipped = sorted(p.stem for p in SCENES_DIR.glob("*.toml"))
    if remake is None:
        scenes, made, names = {}, {}, shipped
    else:
        unknown = sorted(set(remake) - set(shipped))
        if unknown:
            raise ValueError(f"fidelity errors: no shipped scene named {', '.join(map(repr, unknown))} "
                             f"(fixtures/scenes/*.toml: {', '.join(shipped)})")
        try:
            old = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as e:
            raise ValueError(f"fidelity errors: cannot read {escaped(str(path))} to remake part of it: "
                             f"{escaped(str(e))}") from None
        if not isinstance(old, dict) or not isinstance(old.get("scenes"), dict):
            raise ValueError(f"fidelity errors: {escaped(str(path))} has no 'scenes' table to remake part of")
        scenes, made, names = old["scenes"], old.get("made", {}), sorted(set(remake))
        missing = sorted(set(scenes) - set(made))
        if missing:
            raise ValueError(f"fidelity errors: {escaped(str(path))} says nothing of how {', '.join(missing)} "
                             f"were measured (no per-scene 'made' entry): remake it whole, without naming scenes")
    stamp = {"date": time.strftime("%Y-%m-%d", time.gmtime()), **source_revision(),
             "environment": fingerprint_environment()}
    for name in names:
        t0 = time.perf_counter()
        scenes[name] = profile_errors(SCENES_DIR / f"{name}.toml")
        made[name] = stamp
        say(f"{name}: {time.perf_counter() - t0:.1f} s")
    doc = {"about": "Each fidelity profile's error against the reference profile on every shipped scene "
                    "(fixtures/scenes/*.toml, every sensor): per kind of channel the scene's host reads, the RMS over "
                    "all its conversions of the noise-free analog value's difference, in ADC LSB (bits). "
                    "bench/tests/test_fidelity_errors.py recomputes them: a change of any profile's error fails "
                    "there until this file (and the README's table) says the new error. 'made' says, per scene, "
                    "when, at which commit (and with which tracked files changed on top of it) and with what "
                    "software its errors were last measured.",
           "regenerate": f"only for an intended change of these errors, said in the commit message: "
                         f"{FIDELITY_ERROR_COMMAND} (every scene), or with --remake SCENE (repeatable) for the "
                         f"scenes whose errors the change moved",
           "kinds": list(ERROR_KINDS),
           "made": {name: made[name] for name in sorted(made)},
           "scenes": {name: scenes[name] for name in sorted(scenes)}}
    write_json(path, doc)
    return doc


def _fingerprints_main(argv) -> int:
    """``python -m bench.verification.benchmark OUT.json [OLD.json]`` (and ``--write-fixture``,
    ``--write-fidelity-errors``): :func:`bench.cli.fingerprints.main`, which holds the lock beside OUT.json (the
    command-line layer: verification sits below the output folders' code in bench/reporting)."""
    from bench.cli.fingerprints import main as fingerprints_main

    return fingerprints_main(argv)


def fidelity_lines(rows: list[dict]) -> list[str]:
    """The fidelity table of :func:`fidelity_table` as text: per scene and profile each channel kind's noise-free RMS
    error (bits; — where the scene reads no such channel), PAC's spectral error (dB) and the cost."""
    kinds = ERROR_KIND_COLUMNS
    lines = ["Fidelity profiles: error against the reference profile (noise-free RMS, bits, per channel kind), and cost",
             f"{'scene':22s} {'profile':24s} " + " ".join(f"{k:>9s}" for k in kinds.values())
             + f" {'PAC spectral (dB)':>18s} {'ms / sim s':>11s} {'× real time':>12s}"]
    for r in rows:
        err = r.get("error_bits") or {}
        lines.append(f"{r['scene']:22s} {r['profile']:24s} " + " ".join(_fmt(err.get(k), "9.4f") for k in kinds)
                     + f" {_fmt(r['spectral_error_dB'], '18.3f')} {_fmt(r['wall_ms_per_sim_s'], '11.2f')} "
                     f"{_fmt(r['realtime_factor'], '12.0f')}")
    return lines


def _fmt(v, spec):
    width = int("".join(ch for ch in spec.split(".")[0] if ch.isdigit()) or 0)
    return f"{'—':>{width}s}" if v is None else format(v, spec)


def main(args) -> int:
    say = (lambda m: print(m, file=sys.stderr)) if not args.json else (lambda m: None)
    if getattr(args, "textures", False):
        from bench.verification.benchmark_textures import report, results

        measured = results(say)
        if args.json:  # --json had been ignored here: the table came out where JSON was asked for
            from bench.cli.args import strict_json

            print(strict_json(measured, indent=2))
        else:
            print(report(measured=measured))
        return 0
    if getattr(args, "effects", False):
        costs = effect_costs(args.seconds, say=say)
        if args.json:
            from bench.cli.args import strict_json

            print(strict_json({"effect_costs": costs}, indent=2))
        else:
            print("\n".join(effect_cost_lines(costs)))
        return 0
    result = {"fidelity": fidelity_table(say)}
    sec = args.seconds
    say("… throughput")
    result["throughput"] = [stream_realtime_factor(p, DEFAULT_FRAME_NAMES, "default", 4400.0, sec)
                            for p in ("fast", "default", "reference")]
    drops = load_scene(SCENES_DIR / "sphere_drops.toml").stimuli
    full = stream_realtime_factor("default", DEFAULT_FRAME_NAMES, "default", 4400.0, 30.0, drops)
    pac_only = stream_realtime_factor("default", ["PAC"], ["PAC"], 2200.0, 30.0, drops)
    pdc_only = stream_realtime_factor("default", ["PDC"], ["PDC"], 100.0, 30.0, drops)
    result["demand"] = {"full_frame": full, "pac_only": pac_only, "pdc_only": pdc_only,
                        "pac_only_speedup": pac_only["realtime_factor"] / full["realtime_factor"]}
    say("… modalities")
    touches = load_scene(SCENES_DIR / "thermal_contacts.toml").stimuli
    result["modalities"] = stream_realtime_factor("default", DEFAULT_FRAME_NAMES, "default", 4400.0, 100.0, touches)
    result["effect_costs"] = effect_costs(sec, say=say)
    say("… memory (streaming)")
    result["memory"] = stream_hour(3600.0 if args.hour else 600.0)
    result["spi"] = spi_paths(rtl=not args.no_rtl, say=say)
    result["firmware"] = firmware_paths(say=say)
    if args.json:
        from bench.cli.args import strict_json

        print(strict_json(result, indent=2))
        return 0
    print("\n".join(fidelity_lines(result["fidelity"])))
    print("\nFull 44-slot frame at rest, through SPI:")
    for r in result["throughput"]:
        print(f"  {r['fidelity']:10s} {r['realtime_factor']:8.0f}× real time "
              f"({3600 / r['realtime_factor']:.1f} s per simulated hour; {_runs(r)})")
        if r["fidelity"] == "default":
            print("    cost (ms per simulated s): " + ", ".join(
                f"{k} {v:.3f}" for k, v in {**r["grid_ms_per_simulated_s"], **r["ms_per_simulated_s"]}.items()))
    d = result["demand"]
    print("\nDemand-driven (sphere-drop stimuli, default profile):")
    for key in ("full_frame", "pac_only", "pdc_only"):
        r = d[key]
        print(f"  {key:10s} {r['realtime_factor']:8.0f}× real time, effects: {', '.join(r['effects'])}")
    print(f"  reading only PAC is {d['pac_only_speedup']:.2f}× faster than the full frame")
    m = result["modalities"]
    print(f"\nFull frame with the thermal network and electrodes active (thermal-contacts scene, default profile): "
          f"{m['realtime_factor']:.0f}× real time ({_runs(m)}); cost per modality (ms per simulated s):")
    for name, ms in m["ms_per_simulated_s"].items():
        print(f"  {name:32s} {ms:7.3f}")
    print("  grid effects: " + ", ".join(f"{k} {v:.3f}" for k, v in m["grid_ms_per_simulated_s"].items()))
    ms = m["ms_per_simulated_s"]
    print(f"  saved when a scene needs neither: thermal network {ms.get('thermal network', 0):.3f} ms/s (steady-state "
          f"shortcut instead), electrodes {ms.get('electrodes', 0):.3f} ms/s (not built when no electrode is read; "
          f"resting values when nothing touches)")
    print()
    print("\n".join(effect_cost_lines(result["effect_costs"])))
    m = result["memory"]
    print(f"\nStreaming {m['simulated_s']:.0f} simulated s of the full frame: {m['realtime_factor']:.0f}× real time, "
          f"peak RSS {m['peak_rss_MB']:.0f} MB")
    run_memory(say=print)
    print("\nSPI implementations, default 44-slot frame at 4.4 kHz (one sample transaction = command + read):")
    names = {"software_vectorized": "software model (vectorized path)",
             "software_transfer_level": "software model (transfer-level path)",
             "rtl_cocotb": "RTL under cocotb + Verilator", "rtl_cpp_harness": "RTL through the C++ harness"}
    for key, r in result["spi"].items():
        print(f"  {names[key]:38s} {r['transactions_per_s']:12.0f} transactions/s  {r['realtime_factor']:9.2f}× real time"
              + ("" if r["includes_physics"] else "  (codes precomputed by the emulator)"))
    fw = result["firmware"]
    print("\nBridge firmware (C, native) with emulated sensors in virtual time, full 44-slot frame:")
    for n in (1, 3):
        print(f"  {n} sensor(s): {fw[f'cosim_{n}_sensors']['realtime_factor']:6.1f}× real time")
    d = fw["driver_3_sensors_10x"]
    print(f"  driver through a pty, 3 sensors, firmware paced at 10× real time: {d['frames']} frames in "
          f"{d['wall_s']:.2f} s ({d['frames_per_s']:.0f} frames/s), dropped {d['dropped']}, CRC errors {d['crc_errors']}")
    c = fw["cheetah_3_sensors"]
    print(f"  Cheetah-compatible library, example client streaming the default frame from 3 sensors: "
          f"{c['realtime_factor']:.1f}× real time")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(_fingerprints_main(sys.argv[1:]))
    except KeyboardInterrupt:  # (every file is written whole or not at all: none is half-written)
        print("interrupted (Ctrl-C): no file written; an earlier one is left as it was", file=sys.stderr)
        sys.exit(130)
