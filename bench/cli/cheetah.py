"""The emulated Cheetah adapter: ``biotac-bench cheetah serve [SCENE] --sensors N``."""

from __future__ import annotations

import argparse
import shlex
import sys

from bench.cli.args import any_seed, number, sigterm_raises, stimuli_count, whole
from bench.running.signals import signals_deferred
from bench.tomlfile import spelled

#: Sensors served without a scene (``--sensors`` not given); with one, the scene's count.
DEFAULT_SENSORS = 3


def _cmd_serve(a) -> int:
    import time

    from bench.hosts.cheetah_server import CheetahBench

    kw = {}
    n_sensors = DEFAULT_SENSORS if a.sensors is None else a.sensors
    what = f"{n_sensors} emulated sensor(s) at rest"
    if a.scene:
        from bench.hosts.scene_sensors import sensors_from_scene
        from bench.scenes.scene import load_scene

        scene = load_scene(a.scene)
        n_sensors = scene.n_sensors if a.sensors is None else a.sensors
        kw["sensors"] = sensors_from_scene(scene, n_sensors, seed=a.seed)
        kw["spi"] = scene.spi  # the sensors' SPI side the adapter clocks (as biotac_cheetah(scene=...) takes it)
        what = (f"{n_sensors} emulated sensor(s) built from scene '{scene.name}' ("
                + "; ".join(f"sensor {k} feels {stimuli_count(len(scene.sensor_spec(k).stimuli))}"
                            for k in range(1, scene.n_sensors + 1)) + ")")
        if scene.sequence != "default" or scene.slot_rate_Hz != 4400.0:
            print("note: the scene's [host] sequence and slot rate are not used: your program is the host and "
                  "chooses what to sample and when", file=sys.stderr)
    else:
        kw["seed"] = 0 if a.seed is None else a.seed
        what += f" (seed {kw['seed']}: sensor k draws {kw['seed']} + k - 1)"
    with sigterm_raises():
        cb = CheetahBench(n_sensors, request_wait_s=a.request_wait, **kw).start()
        try:
            print(f"export BIOTAC_CHEETAH_SOCKET={shlex.quote(cb.socket_path)}", flush=True)
            side = (f", their SPI side the Verilog RTL (the scene says host.spi = {spelled(cb.spi)})"
                    if cb.spi == "rtl" else "")
            print(f"emulated Cheetah adapter (port 0) with {what}{side}\n"
                  f"run your Cheetah program with that variable set and this cheetah.so beside it (or in its working "
                  f"folder): {cb.library}\nCtrl-C or SIGTERM to stop", file=sys.stderr, flush=True)
            deadline = None if a.seconds is None else time.monotonic() + a.seconds
            while deadline is None or time.monotonic() < deadline:
                time.sleep(0.2)
        except KeyboardInterrupt:
            pass
        finally:
            with signals_deferred():
                cb.stop()
    print(f"stopped: {cb.batches} batches served, {cb.t:.3f} s of the host's virtual time"
          + (f"; {len(cb.client_errors)} client connection(s) ended for malformed requests" if cb.client_errors
             else ""), file=sys.stderr)
    for why in cb.client_errors[:5]:
        print(f"  {why}", file=sys.stderr)
    if cb.stop_problem:  # a program's request was cut short by the stop (over the RTL, its harness ended under it)
        print(f"  {cb.stop_problem}", file=sys.stderr)
    return 0


def add_commands(sub, fmt=argparse.RawDescriptionHelpFormatter) -> None:
    from bench.cli.scenes import scene_argument

    ch = sub.add_parser("cheetah", help="the emulated Cheetah SPI adapter for unmodified Cheetah-based programs",
                        description="Emulated BioTac sensors behind a Cheetah-compatible adapter: programs written "
                                    "against Total Phase's Cheetah API load the bench's cheetah.so and talk to "
                                    "the emulated sensors over SPI, in virtual time.\n\n"
                                    "  biotac-bench cheetah serve --sensors 3            # 3 sensors at rest\n"
                                    "  biotac-bench cheetah serve taps --seconds 60      # built from a scene\n\n"
                                    "biotac-bench cheetah serve --help says how to point your program at it.",
                        formatter_class=fmt)
    chsub = ch.add_subparsers(dest="cheetah_command", metavar="ACTION", required=True)
    sv = chsub.add_parser(
        "serve", help="serve an emulated adapter until stopped",
        description="Serves one emulated Cheetah adapter (port 0) with --sensors emulated sensors on a Unix socket in "
                    "a private folder, and prints the line to export:\n\n"
                    "  export BIOTAC_CHEETAH_SOCKET=...\n\n"
                    "then serves until Ctrl-C or SIGTERM (or --seconds), and stops cleanly whatever clients did. "
                    "With SCENE sensor k is the scene's sensor k (unit, parameters, its faults, noise, fidelity, seed; "
                    "the stimuli addressed to it, in the adapter's virtual time). One program at a time may open "
                    "the adapter, as with the real device.\n\n"
                    "  biotac-bench cheetah serve taps --sensors 1   # prints: export BIOTAC_CHEETAH_SOCKET=...\n"
                    "  # then, in another shell: paste that line and run your program with the printed cheetah.so "
                    "beside it",
        formatter_class=fmt)
    sv.add_argument("scene", nargs="?", type=scene_argument,
                    help="scene file, or a shipped scene's name, the sensors are built from (default: none, the "
                         "sensors at rest)")
    sv.add_argument("--sensors", type=whole(1, 5), default=None,
                    help=f"emulated sensors, 1 to 5 (default: the scene's count with SCENE, else {DEFAULT_SENSORS}; "
                         f"with SCENE at least its count)")
    sv.add_argument("--seed", type=any_seed,
                    help="seed (default: the scene's, else 0); sensor k draws its noise from seed + k - 1, "
                         "with a scene or without (as every route numbers sensors)")
    sv.add_argument("--seconds", type=number(0, lo_open=True), help="stop after this many wall-clock seconds (s; default: "
                                                                        "serve until Ctrl-C or SIGTERM)")
    sv.add_argument("--request-wait", type=number(0, 3600, lo_open=True), default=None, metavar="SECONDS",
                    help="at Ctrl-C or SIGTERM, how long to wait for a program's request still being clocked before "
                         "ending it (wall s; over the RTL its harness is ended under it; default: 5)")
    sv.set_defaults(func=_cmd_serve)
