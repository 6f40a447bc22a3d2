"""Host-stack commands: the bridge firmware on a pty, recording a bridge's serial stream."""

from __future__ import annotations

import argparse
from pathlib import Path


def _cmd_bridge(a) -> int:
    import time

    from bench.hosts.bridge import FirmwareBench
    from bench.scenes.scene import load_scene

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

    from bench.hosts.driver import CMD_START, BridgeDriver

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


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
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
