"""The Verilog twin: lint, replay protocol vectors (optionally with waves), stream frames."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bench.paths import REPO


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


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
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
