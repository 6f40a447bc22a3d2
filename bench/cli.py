"""biotac-bench: run scenes against the emulated BioTac, check the published figures, measure costs."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SCENES_DIR = REPO / "fixtures" / "scenes"

MAIN_HELP = """\
An emulated BioTac fingertip — pressure (PDC, PAC), temperature (TDC, TAC) and 19 impedance electrodes at
sample level — behind its SPI protocol (software model or Verilog RTL), driven by scene files.

typical session:
  biotac-bench scenes                                  # what ships
  biotac-bench run fixtures/scenes/sphere_drops.toml   # run one: codes.npz, record.json, report.md, plots
  biotac-bench claims                                  # check every published figure (PASS/FAIL table)
  biotac-bench noise-budget                            # where the 1.4 bits of PAC noise come from
  biotac-bench benchmark                               # what each fidelity profile costs and how wrong it is

Every subcommand has its own --help.
"""

RUN_HELP = """\
Runs a scene file through sensor -> SPI peripheral -> host sampler and writes, into --out:
  codes.npz     raw 12-bit codes per channel (<CH>_t, <CH>_code, <CH>_status) and physical units
                (PAC_Pa, PDC_kPa, PDC_force_N) using the published conversions
  samples.csv   the same in long format (with --csv)
  record.json   everything about the run: scene, parameters, effects that ran and their cost, results
  report.md     a short human-readable report
  traces.png, spectrogram.png

scene file (TOML):
  [scene]    name, duration_s, seed (0), fidelity ("fast" | "default" | "reference"), description
  [sensor]   any sensor parameter by name, e.g. inflation_volume_mL = 0.6  (see `biotac-bench params`)
  [host]     sequence = "default" (44-slot frame) or ["PAC", "PDC"]; slot_rate_Hz (4400); spi_clock_Hz (4.4e6);
             spi = "software" (the Python model) | "rtl" (the Verilog twin, run by the C++ Verilator harness)
  [noise]    johnson, amplifier, mains_hum, adc, spi_coupling = true | false
  [analysis] impact_detection = true   (applies D ch. 5's rule to every sphere drop)
  [[stimulus]] one table per stimulus, by kind:
     tap          at_s (s or list), peak_N, duration_s (0.03)
     press        start_s, force_N, ramp_s (0.5), hold_s (1.0)
     sphere_drop  at_s, sphere ("0.45 mm solder ball", ...) or mass_mg, height_m (0.07)
     vibration    start_s, duration_s, amplitude_um, frequency_Hz  | f_start_Hz + f_stop_Hz (log sweep), fade_s
     pressure     start_s, duration_s, offset_kPa, amplitude_Pa, frequency_Hz  (calibrator on the liquid)
     touch        start_s, force_N, ramp_s, hold_s; where: electrode ("E17") or x_mm + angle_deg;
                  indenter_radius_mm (3), tangential_N, shear_angle_deg; material ("aluminum", "glass",
                  "wood", "polystyrene foam", ...) and object_temperature_C for thermal contact
     power_on     at_s   (heaters start from ambient)        ambient_step  at_s, temperature_C
     heater_failure  at_s
  [faults]   electrode_open = [3], electrode_short = [5], mux_stuck = 7, thermistor = "open" | "short",
             heater_failed = true

The file is validated before anything runs; every problem is listed with its field, value and allowed range.
A run that fails part-way still writes what it recorded (record.json says "failed" and why); exit status 1.
"""


def _cmd_run(a) -> int:
    from bench.report import write_outputs
    from bench.runner import run_scene
    from bench.scene import load_scene

    scene = load_scene(a.scene)
    if a.fidelity:
        scene.fidelity = a.fidelity
    if a.seed is not None:
        scene.seed = a.seed
    if a.spi:
        scene.spi = a.spi
    out = Path(a.out) if a.out else Path("out") / scene.name
    rec = run_scene(scene, progress=not a.quiet)
    record = write_outputs(rec, out, csv=a.csv, plots=not a.no_plots)
    if not a.quiet:
        print((out / "report.md").read_text())
    print(f"wrote {out}/ ({', '.join(record['outputs'])})")
    if rec.error:
        print(f"error: the run stopped at {rec.simulated_s:.3f} s: {rec.error}", file=sys.stderr)
        return 1
    return 0


def _cmd_validate(a) -> int:
    from bench.scene import SceneError, load_scene

    bad = 0
    for f in a.scenes:
        try:
            sc = load_scene(f)
            print(f"{f}: ok ({sc.name}, {sc.duration_s} s, {len(sc.stimuli)} stimuli, fidelity {sc.fidelity})")
        except SceneError as e:
            print(e, file=sys.stderr)
            bad += 1
    return 1 if bad else 0


def _cmd_scenes(a) -> int:
    from bench.scene import load_scene

    for f in sorted(SCENES_DIR.glob("*.toml")):
        sc = load_scene(f)
        print(f"{f.relative_to(REPO)}\n    {sc.description or sc.name} ({sc.duration_s:g} s)")
    return 0


def _cmd_profiles(a) -> int:
    from emulator.fidelity import PROFILES

    for p in PROFILES.values():
        print(f"{p.name:10s} {p.description}")
    return 0


def _cmd_params(a) -> int:
    from emulator.params import PARAMETER_FIELDS, SensorParams

    d = SensorParams()
    for name, f in PARAMETER_FIELDS.items():
        m = f.metadata
        print(f"{name:38s} {getattr(d, name)!r:>24} {m['unit']:10s} [{m['range'][0]}, {m['range'][1]}] "
              f"({m['source']}) {m['doc']}")
    return 0


def _cmd_noise_budget(a) -> int:
    from emulator.noise_budget import budget, format_budget

    lines = budget()
    if a.json:
        print(json.dumps([vars(x) for x in lines], indent=2))
    else:
        print(format_budget(lines))
    return 0


def _cmd_claims(a) -> int:
    from bench.claims import CLAIM_GROUPS, Bench, format_table, run_claims

    groups = a.only or list(CLAIM_GROUPS)
    bench = Bench(fidelity=a.fidelity, seed=a.seed, quick=a.quick)
    claims = run_claims(bench, groups, progress=None if a.json else lambda g: print(f"… {g}", file=sys.stderr))
    if a.json:
        print(json.dumps([c.as_dict() for c in claims], indent=2, default=float))
    else:
        print(format_table(claims))
    if a.plots:
        from bench.plots import sensitivity_plot

        out = sensitivity_plot(claims, Path(a.plots))
        print(f"wrote {out}", file=sys.stderr)
    return 0 if all(c.passed for c in claims) else 1


def _cmd_rtl(a) -> int:
    from emulator.rtl import build

    if a.action == "lint":
        r = build.lint(REPO / "out" / "rtl_lint")
        print((r.stdout + r.stderr).strip() or "lint clean: verilator --lint-only -Wall")
        return r.returncode
    if a.action == "vectors":
        from emulator.rtl.runner import Rtl
        from emulator.spi import vectors as V

        if not a.files:
            raise ValueError("give one or more vector files, e.g. fixtures/spi_vectors/properties.json")
        rtl = Rtl(REPO / "out" / ("rtl_build_waves" if a.waves else "rtl_build"), waves=a.waves)
        if a.waves and rtl.wave_format != "fst":
            print("note: FST needs the lz4 headers (Debian: apt-get install liblz4-dev); writing VCD instead",
                  file=sys.stderr)
        rtl.build()
        results = rtl.run_vectors([Path(f).resolve() for f in a.files])
        bad = 0
        for f in a.files:
            vec, res = V.load(f), results[str(Path(f).resolve())]
            diff = sum(d["miso"] != m for d, m in zip(vec["transfers"], res["miso"]))
            bad += diff + len(res["mismatched_requests"])
            print(f"{f}: {len(vec['transfers'])} transfers, {diff} differ from the reference"
                  + (f", {len(res['mismatched_requests'])} ADC requests differ" if res["mismatched_requests"] else ""))
        if a.waves:
            print("waveforms: " + ", ".join(str(p) for p in rtl.wave_files()))
        return 1 if bad else 0
    from emulator.rtl.harness import Harness

    res = Harness().stream_frames(a.seconds)
    print(f"streamed {a.seconds:g} s of the default frame through the RTL (C++ harness): "
          f"{a.seconds / res['wall_s']:.1f}× real time")
    return 0


def _cmd_bridge(a) -> int:
    import time

    from bench.bridge import FirmwareBench
    from bench.scene import load_scene

    stimuli = load_scene(a.scene).stimuli if a.scene else ()
    with FirmwareBench(a.sensors, stimuli=stimuli, seed=a.seed, realtime=not a.fast, speed=a.speed, spi=a.spi) as fb:
        print(f"bridge firmware running with {a.sensors} emulated sensor(s); serial port: {fb.port}", flush=True)
        print("open it with any serial program (raw, no flow control); Ctrl-C to stop", flush=True)
        deadline = None if a.seconds is None else time.monotonic() + a.seconds
        try:
            while deadline is None or time.monotonic() < deadline:
                time.sleep(0.2)
        except KeyboardInterrupt:
            pass
        print(f"stopped at virtual time {fb.virtual_time:.2f} s")
    return 0


def _cmd_record(a) -> int:
    import numpy as np
    from tqdm import tqdm

    from bench.driver import CMD_START, BridgeDriver

    drv = BridgeDriver(a.port, baudrate=a.baud)
    drv.start()
    if drv.wait_for(CMD_START, timeout_s=5) is None:
        raise OSError(f"{a.port}: no answer to START within 5 s (is the bridge running?)")
    frames = []
    n = int(a.seconds * 100)
    with tqdm(total=n, unit="frame", disable=a.quiet) as bar:
        for f in drv.frames(max_frames=n, timeout_s=5):
            frames.append(f)
            bar.update(1)
    drv.stop()
    drv.close()
    if not frames:
        raise OSError(f"{a.port}: no frames arrived")
    seq = np.array([f.seq for f in frames])
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(out, seq=seq, mask=np.array([f.sensor_mask for f in frames]),
                        channels=np.stack([f.channels for f in frames]), codes=np.stack([f.codes for f in frames]),
                        status=np.stack([f.status for f in frames]))
    if a.csv:
        with open(out.with_suffix(".csv"), "w") as fh:
            fh.write("seq,slot,channel,sensor,code,status\n")
            for f in frames:
                for k, ch in enumerate(f.channels):
                    for j, n_s in enumerate(f.sensors):
                        fh.write(f"{f.seq},{k},{ch},{n_s},{f.codes[k, j]},{f.status[k, j]}\n")
    st = drv.parser.stats
    print(f"wrote {out}: {len(frames)} frames; CRC errors {st.crc_errors}, dropped frames {st.dropped_frames}, "
          f"bytes skipped {st.bytes_skipped}")
    return 0


def _cmd_campaign(a) -> int:
    from bench import campaign

    faults = list(campaign.FAULTS) if a.faults == "all" else a.faults.split(",")
    scenes = list(campaign.SCENES) if a.scenes == "all" else a.scenes.split(",")
    for name, known in ((faults, campaign.FAULTS), (scenes, campaign.SCENES)):
        bad = [x for x in name if x not in known]
        if bad:
            raise ValueError(f"unknown: {', '.join(bad)}; known: {', '.join(known)}")
    results = campaign.run_campaign(faults, scenes, range(a.seeds),
                                    progress=lambda m: print(f"… {m}", file=sys.stderr))
    campaign.write_junit(results, Path(a.junit))
    print(campaign.summary(results))
    print(f"JUnit XML: {a.junit}")
    return 0 if all(r["passed"] for r in results) else 1


def _cmd_benchmark(a) -> int:
    from bench.benchmark import main as bench_main

    return bench_main(a)


def build_parser() -> argparse.ArgumentParser:
    fmt = argparse.RawDescriptionHelpFormatter
    p = argparse.ArgumentParser(prog="biotac-bench", description=MAIN_HELP, formatter_class=fmt)
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)

    r = sub.add_parser("run", help="run a scene file and write codes, record, report and plots",
                       description=RUN_HELP, formatter_class=fmt)
    r.add_argument("scene", help="scene file (TOML), e.g. fixtures/scenes/sphere_drops.toml")
    r.add_argument("--out", help="output folder (default: out/<scene name>)")
    r.add_argument("--csv", action="store_true", help="also write samples.csv")
    r.add_argument("--fidelity", choices=["fast", "default", "reference"], help="override the scene's profile")
    r.add_argument("--seed", type=int, help="override the scene's seed")
    r.add_argument("--spi", choices=["software", "rtl"],
                   help="the sensor's SPI side: the software model (default) or the RTL via the C++ harness")
    r.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    r.add_argument("--quiet", action="store_true", help="no progress bar, no report on the terminal")
    r.set_defaults(func=_cmd_run)

    v = sub.add_parser("validate", help="check scene files without running them")
    v.add_argument("scenes", nargs="+")
    v.set_defaults(func=_cmd_validate)

    sub.add_parser("scenes", help="list the shipped scenes").set_defaults(func=_cmd_scenes)
    sub.add_parser("profiles", help="list the fidelity profiles").set_defaults(func=_cmd_profiles)
    sub.add_parser("params", help="list every sensor parameter with unit, range and source").set_defaults(
        func=_cmd_params)

    nb = sub.add_parser("noise-budget", help="the PAC noise budget, source by source")
    nb.add_argument("--json", action="store_true")
    nb.set_defaults(func=_cmd_noise_budget)

    c = sub.add_parser("claims", help="measure every published figure on the emulator; exit 1 if any fails",
                       description="Runs each claim (SENSOR.md figure) on the emulator's output and prints "
                                   "claim, expected, measured, accepted range and PASS/FAIL.", formatter_class=fmt)
    c.add_argument("--json", action="store_true", help="print the results as JSON")
    c.add_argument("--only", action="append", choices=["noise", "scales", "force", "impact", "detection",
                                                       "false-detection", "vibration", "thermal", "electrodes"],
                   help="run one group")
    c.add_argument("--fidelity", default="default", choices=["fast", "default", "reference"])
    c.add_argument("--seed", type=int, default=2012)
    c.add_argument("--quick", action="store_true", help="fewer drops and a shorter rest run (a look, not proof)")
    c.add_argument("--plots", metavar="DIR", help="write the frequency-sensitivity plot into DIR")
    c.set_defaults(func=_cmd_claims)

    rt = sub.add_parser("rtl", help="the Verilog twin: lint, replay vector files (FST waves on request), stream",
                        description="lint: verilator --lint-only -Wall on the RTL. vectors FILE...: replay protocol "
                                    "vector files (fixtures/spi_vectors/*.json) on the RTL under cocotb and compare "
                                    "with the reference; --waves writes an FST waveform. stream: play the default "
                                    "frame through the C++ harness.", formatter_class=fmt)
    rt.add_argument("action", choices=["lint", "vectors", "stream"])
    rt.add_argument("files", nargs="*", help="vector files (for 'vectors')")
    rt.add_argument("--waves", action="store_true", help="dump an FST waveform of the simulation")
    rt.add_argument("--seconds", type=float, default=1.0, help="simulated seconds (for 'stream')")
    rt.set_defaults(func=_cmd_rtl)

    br = sub.add_parser("bridge", help="run the bridge firmware against emulated sensors on a serial port (pty)",
                        description="Compiles and runs the reference bridge firmware (firmware_tests/firmware) "
                                    "against emulated sensors in virtual time and exposes its UART as a pty that "
                                    "any program can open as a serial port. Real-time paced unless --fast.",
                        formatter_class=fmt)
    br.add_argument("--sensors", type=int, default=1, choices=range(1, 6))
    br.add_argument("--scene", help="scene file whose stimuli the first sensor feels")
    br.add_argument("--seed", type=int, default=1)
    br.add_argument("--seconds", type=float, help="stop after this many wall-clock seconds")
    br.add_argument("--speed", type=float, default=1.0, help="virtual seconds per wall second when paced")
    br.add_argument("--fast", action="store_true", help="run as fast as possible instead of real time")
    br.add_argument("--spi", choices=["software", "rtl"], default="software",
                    help="the sensors' SPI side: the software model, or the Verilog RTL in the C++ harness")
    br.set_defaults(func=_cmd_bridge)

    rc = sub.add_parser("record", help="record a bridge's serial stream to NPZ (and CSV)",
                        description="Reads the bridge firmware's frames from a serial port (a device, a pty, or a "
                                    "pyserial URL such as socket://host:port) and writes codes, status and "
                                    "sequence numbers to NPZ; reports CRC errors and dropped frames.",
                        formatter_class=fmt)
    rc.add_argument("port")
    rc.add_argument("--seconds", type=float, default=1.0)
    rc.add_argument("--out", default="out/recording.npz")
    rc.add_argument("--csv", action="store_true")
    rc.add_argument("--baud", type=int, default=3_000_000)
    rc.add_argument("--quiet", action="store_true")
    rc.set_defaults(func=_cmd_record)

    cp = sub.add_parser("campaign", help="fault campaign: fault × scene × seed through firmware and driver",
                        description="Runs every chosen fault in every chosen scene for each seed through the "
                                    "bridge firmware, a pty and the host driver; prints a summary and writes "
                                    "JUnit XML. Exit status 1 if any case fails.", formatter_class=fmt)
    cp.add_argument("--faults", default="all", help="comma-separated fault names, or all")
    cp.add_argument("--scenes", default="all", help="comma-separated scene names, or all")
    cp.add_argument("--seeds", type=int, default=1)
    cp.add_argument("--junit", default="out/campaign.xml")
    cp.set_defaults(func=_cmd_campaign)

    b = sub.add_parser("benchmark", help="error vs the reference profile and cost per simulated second",
                       description="For every fidelity profile and shipped scene: PAC RMS error (bits) and "
                                   "spectral error (dB) against the reference profile, and wall time per "
                                   "simulated second; then throughput, memory and demand-driven savings.",
                       formatter_class=fmt)
    b.add_argument("--json", action="store_true", help="print the results as JSON")
    b.add_argument("--seconds", type=float, default=60.0, help="simulated seconds for the throughput runs")
    b.add_argument("--hour", action="store_true", help="stream a full simulated hour for the memory check")
    b.add_argument("--no-rtl", action="store_true", help="skip the RTL measurements (no Verilator build)")
    b.set_defaults(func=_cmd_benchmark)
    return p


def main(argv=None) -> int:
    from bench.scene import SceneError
    from emulator.adc import NumericalError

    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except SceneError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except (ValueError, NumericalError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
