"""Fault campaigns: every fault × scene × seed through firmware, serial link and driver, with verdicts.

Each fault states what a correct firmware and driver do; a run passes when the stream stays decodable,
nothing corrupted reaches the caller, the expected reaction is seen, a fault whose correct reaction shows the host
nothing left its trace on the bus (:data:`FAULT_TRACES`: it happened), with no fault the data read as each
sensor at rest before the scene's first stimulus (:data:`AT_REST`), and nothing hangs (every wait is bounded).
Results go to JUnit XML and a summary table.

The cases are independent tasks on the campaign engine (:mod:`bench.campaigns.engine`: a Dask LocalCluster or an
existing scheduler).  A task is a case's description — fault name, scene name (or a scene file's validated
scene: :mod:`bench.campaigns.scene_files`), seed (:class:`CaseTask`) — and a worker builds the case from the
registries below, so the verdicts are the same for any number of workers; each
case's wall time is measured where it runs.  The faults' and scenes' names, the faults' expected reactions and the
scenes' descriptions live in :mod:`bench.campaigns.case_names` (light: what the command line's help lists); the
registries here hold the heavy objects keyed by those names.  The bench and the driver are imported only where a
case runs.  The firmware is built once on the client before the tasks go out; a
worker on another machine builds its own (the build is atomic, also between threads: bench.hosts.native).  So are
the emulator's numba kernels compiled, for each scene (:func:`compile_kernels`): workers on this machine load them
from numba's cache on disk; one on another machine compiles its own in its first case of a scene.
"""

from __future__ import annotations

import re
import threading
import time
import xml.etree.ElementTree as ET
from contextlib import contextmanager, suppress
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bench.atomic import atomic_write
from bench.campaigns.case_names import CASE_FRAMES, FAULT_EXPECTED, SCENE_DESCRIPTIONS, check_bus
from bench.campaigns.drivers import (BENCH_DRIVER, HOST_LIMIT_PER_FRAME_S, HOST_LIMIT_S, DriverFailed, DriverFile,
                                     one_line, open_driver, uncounted_gaps)
from emulator.spi.model import Faults
from emulator.stimuli import SPHERES, SphereDrop, Tap, Touch

if TYPE_CHECKING:
    from bench.hosts.driver import BridgeDriver


@dataclass
class FaultCase:
    name: str
    expected: str
    bench_kw: dict
    schedule: list  # (seconds after streaming starts, action(board))
    check: object  # (frames, status, parser stats) -> problem string or None
    trace: object = None  # (board) -> problem string or None: the fault's own mark on the bus (that it happened)
    at_rest: bool = False  # the frames before the scene's first stimulus must read as each sensor at rest


def _mask_returns(frames, status, stats):
    masks = [f.sensor_mask for f in frames]
    if not (0b01 in masks and masks[-1] == 0b11):
        return f"sensor 2 was not lost and found again (masks seen: {sorted(set(masks))})"
    if status.losses < 1 or status.finds < 1:
        return "firmware counters show no loss/find"


def _flags_parity(frames, status, stats):
    if not any((f.status == 1).any() for f in frames) or status.parity_errors == 0:
        return "bad parity was not flagged"


def _drops_sensor(frames, status, stats):
    if frames[-1].sensor_mask != 0b01:
        return "the stuck sensor is still streamed"


#: when the brown-out resets sensor 1 after the frame it falls in starts (s): after the slot's sampling command
#: (3.75 µs), before its read (54 µs), so the pending result is lost
BROWNOUT_INTO_FRAME_S = 20e-6


def _survives_reset(frames, status, stats):
    bad = sum(int((f.status != 0).sum()) for f in frames)
    if bad == 0 or status.error_words == 0:
        return "no error word reached the host: the reset lost no pending result (did it happen?)"
    if bad > 2:
        return f"{bad} bad samples after a reset (at most two)"
    if frames[-1].sensor_mask != 0b01:
        return "the reset sensor was dropped"


def _resyncs(frames, status, stats):
    if stats.dropped_frames == 0 and stats.crc_errors == 0:
        return "corruption went unnoticed"


#: the fluid leak case's rate (mL/min): a punctured skin, which loses ~0.15 mL over a case's 150 frames
LEAK_CASE_ML_PER_MIN = 6.0
#: frames the leak case compares at each end of its run (medians: a tap or a drop in them moves nothing)
LEAK_CASE_FRAMES = 15


def _resting_pdc_falls_as_the_fluid_leaks(frames, status, stats):
    """The resting PDC the driver hands over falls as the pressure–volume curve predicts for the fluid lost
    between the run's first and last frames (each frame its slots / 4400 s; the leak runs from the sensor's
    power-on, the first frame within 0.1 s of it): the medians of the first and last :data:`LEAK_CASE_FRAMES` frames' PDC
    differ by the predicted drop within 15 % + 2 codes."""
    from bench.hosts.driver import SLOT_RATE_HZ
    from emulator.channels import PDC
    from emulator.mechanics import FluidLeak
    from emulator.params import SensorParams
    from emulator.units import derived

    p = SensorParams()
    good = [f for f in frames if f.ok[f.channels == PDC, 0].all()]
    if len(good) < 4 * LEAK_CASE_FRAMES:
        return f"only {len(good)} frames with a clean PDC"
    first, last = good[:LEAK_CASE_FRAMES], good[-LEAK_CASE_FRAMES:]
    pdc = [float(np.median(np.concatenate([f.codes[f.channels == PDC, 0] for f in part]))) for part in (first, last)]
    frame_s = len(frames[0].channels) / SLOT_RATE_HZ
    span_s = (np.median([f.seq for f in last]) - np.median([f.seq for f in first])) * frame_s
    leak = FluidLeak(LEAK_CASE_ML_PER_MIN)
    drops = [(p.resting_pressure_at(leak.volume_mL(p.inflation_volume_mL, t0))
              - p.resting_pressure_at(leak.volume_mL(p.inflation_volume_mL, t0 + span_s))) / derived(p)["PDC_Pa_per_bit"]
             for t0 in (0.0, 0.1)]
    drop = pdc[0] - pdc[1]
    if not min(drops) / 1.15 - 2 <= drop <= max(drops) * 1.15 + 2:
        return (f"resting PDC fell by {drop:.1f} codes over {span_s:.2f} s; the leak predicts "
                f"{min(drops):.1f} to {max(drops):.1f}")


#: how often the cs_glitch case toggles sensor 1's chip select with no clock edges (50 ms apart from 0.1 s)
CS_GLITCHES = 10


def _every_glitch_reached_sensor_1(board):
    """cs_glitch's trace: sensor 1's port, on either SPI bus, counted exactly :data:`CS_GLITCHES` chip-select
    windows with no clock edges (the firmware's own traffic makes none), so a glitch dropped on the way — or one
    sent to another sensor — fails the case, where the healthy link it leaves behind would pass it."""
    port = board.bus.ports.get(1)
    seen = 0 if port is None else port.empty_windows
    if seen != CS_GLITCHES:
        return (f"sensor 1 saw {seen} chip-select windows with no clock edges; the case glitches it "
                f"{CS_GLITCHES} times (a glitch went missing or astray)")


def _clean(frames, status, stats):
    flagged = sum(int((f.status != 0).sum()) for f in frames)
    if stats.crc_errors or stats.dropped_frames or flagged:
        return (f"errors on a healthy link ({stats.crc_errors} CRC errors, {stats.dropped_frames} dropped frames, "
                f"{flagged} flagged samples)")


def _healthy(frames, status, stats):
    """The healthy link's check (:func:`_clean`) and the firmware's own counters: no parity errors, error words,
    losses, finds or command errors, and every frame streams every sensor the case has (the first frame's)."""
    if problem := _clean(frames, status, stats):
        return problem
    counted = {name: getattr(status, name) for name in ("parity_errors", "error_words", "losses", "finds",
                                                       "command_errors") if getattr(status, name)}
    if counted:
        return f"the firmware flagged faults on a healthy link ({', '.join(f'{k} {v}' for k, v in counted.items())})"
    masks = sorted({f.sensor_mask for f in frames})
    if len(masks) > 1:
        return f"the sensors streamed changed on a healthy link (sensor masks seen: {masks})"


#: How far (in σ of each channel's noise at rest, from :func:`emulator.noise_budget.budget`) a code of a sensor at
#: rest may lie from its noise-free resting code, plus one code for quantization: 6σ, which Gaussian noise exceeds
#: about once in 5·10⁸ samples (a case reads ~7000 per sensor).
REST_BAND_SIGMAS = 6.0
#: Frames left out before a scene's first stimulus (a frame's instant is estimated from START, 10 ms each): margin
#: for the firmware's delay between START and its first frame.
REST_MARGIN_FRAMES = 2
#: Fewest frames the at-rest check needs before the first stimulus (else the case fails: it would check nothing).
REST_MIN_FRAMES = 10


def resting_volts_in_order(params, variant: str, order) -> dict[str, tuple[float, float]]:
    """Noise-free values (V) at the ADC input of each channel named in ``order`` of a sensor (``params``,
    ``variant``) at rest, read as frames sampling ``order`` over and over read them: channel name -> (lowest,
    highest) over the first frame and the next.  The multiplexer keeps a part of the electrode converted before
    (exp(−t_acq/τ): ``mux_acquisition_s``, ``mux_settling_s``): in the first frame the first electrode follows no
    other, in each later one the previous frame's last electrode — so it reads differently at rest in each, where
    :func:`emulator.noise_budget.resting_volts` gives only the first."""
    from emulator import channels as ch
    from emulator.sensor import NoiseSources, Sensor

    names = list(dict.fromkeys(order))
    s = Sensor(params, [], names, seed=0, noise=NoiseSources.none(), variant=variant)
    idx = np.array([ch.channel_index(n) for n in order] * 2)
    v = s.analog(idx, np.full(idx.size, 0.5))
    out: dict[str, tuple[float, float]] = {}
    for n, x in zip(order * 2, v):
        lo, hi = out.get(n, (x, x))
        out[n] = (min(lo, float(x)), max(hi, float(x)))
    return out


def resting_bands(sensor, order) -> dict[str, tuple[float, float]]:
    """Each channel's resting band of ``sensor`` (its unit's parameters and variant) in frames sampling the channels
    named in ``order``: channel name -> (lowest, highest) code, the noise-free resting codes
    (:func:`resting_volts_in_order`) widened by REST_BAND_SIGMAS × its noise at rest (codes) + 1 code each way."""
    from emulator import noise_budget as nb
    from emulator.conversions import ADC_LSB_V

    rest = resting_volts_in_order(sensor.params, sensor.variant, list(order))
    sigma = nb.channel_totals(nb.budget(sensor.params, sensor.variant))
    half = {name: REST_BAND_SIGMAS * sigma[name] + 1 for name in rest}
    return {name: (lo / ADC_LSB_V - half[name], hi / ADC_LSB_V + half[name]) for name, (lo, hi) in rest.items()}


def not_at_rest(frames, sensors: dict, stimuli, start_s: float) -> str | None:
    """Why the frames before the first of ``stimuli`` (all frames without any) do not read as ``sensors`` ({number:
    Sensor}) at rest, or None: every clean sample of each sensor within its :func:`resting_bands`.  Frame ``seq``
    is taken to start at ``start_s`` + seq × its duration (s from power-on; ``start_s``: when the firmware received
    START); frames within :data:`REST_MARGIN_FRAMES` of the first stimulus are left out."""
    from bench.hosts.driver import SLOT_RATE_HZ
    from emulator import channels as ch

    quiet_until = min((st.start_s for st in stimuli), default=np.inf)
    frame_s = len(frames[0].channels) / SLOT_RATE_HZ
    quiet = [f for f in frames if start_s + (f.seq + 1 + REST_MARGIN_FRAMES) * frame_s <= quiet_until]
    if len(quiet) < REST_MIN_FRAMES:
        return (f"only {len(quiet)} frames before the scene's first stimulus at {quiet_until:g} s (at least "
                f"{REST_MIN_FRAMES} needed to check the sensor at rest)")
    for n, sensor in sorted(sensors.items()):
        names = [ch.variant(sensor.variant).channel_name[int(c)] for c in quiet[0].channels]
        bands = resting_bands(sensor, names)
        for f in quiet:
            if n not in f.sensors:
                continue
            column = f.sensors.index(n)
            for slot, channel in enumerate(f.channels):
                name = ch.variant(sensor.variant).channel_name[int(channel)]
                lo, hi = bands[name]
                code = int(f.codes[slot, column])
                if f.status[slot, column] == 0 and not lo <= code <= hi:
                    return (f"sensor {n} at rest read {name} = {code} in frame {f.seq} (at about "
                            f"{start_s + f.seq * frame_s:.3f} s), outside its resting band {lo:.0f}..{hi:.0f} "
                            f"(resting code ± {REST_BAND_SIGMAS:g}σ of its noise + 1)")
    return None


#: How each fault of :data:`~bench.campaigns.case_names.FAULT_EXPECTED` is made and checked: name -> (bench
#: keywords, schedule, check).
FAULT_CASES = {
    "none": ({}, [], _healthy),
    "unplug_replug": ({"n_sensors": 2}, [(0.3, lambda b: b.unplug(2)), (0.8, lambda b: b.plug(2))], _mask_returns),
    "parity_errors": ({}, [(0.1, lambda b: setattr(b.bus.ports[1], "faults", Faults(bad_parity=True)))],
                      _flags_parity),
    "miso_stuck": ({"n_sensors": 2}, [(0.2, lambda b: setattr(b.bus.ports[2], "faults", Faults(miso_stuck=1)))],
                   _drops_sensor),
    "brownout_reset": ({}, [(0.3, lambda b: b.reset_at(1, b.t + BROWNOUT_INTO_FRAME_S))], _survives_reset),
    "cs_glitch": ({}, [(0.1 + 0.05 * k, lambda b: b.glitch(1)) for k in range(CS_GLITCHES)], _clean),
    "serial_corruption": ({"corrupt_rate": 5e-4}, [], _resyncs),
    "serial_loss": ({"drop_rate": 5e-4}, [], _resyncs),
    "fluid_leak": ({"sensor_faults": {"fluid_leak_mL_per_min": LEAK_CASE_ML_PER_MIN}}, [],
                   _resting_pdc_falls_as_the_fluid_leaks),
}

#: The traces of the faults whose correct reaction shows nothing to the host (name -> trace(board)): what the bus
#: recorded of the fault, so that a fault dropped on the way fails its case rather than passing as a healthy link.
FAULT_TRACES = {"cs_glitch": _every_glitch_reached_sensor_1}

#: The faults whose data must read, before the scene's first stimulus, as each sensor at rest (:func:`not_at_rest`):
#: with no fault a broken "healthy" path (codes shifted, channels swapped, a sensor's unit mixed up) fails the case.
AT_REST = {"none"}

#: The campaign's faults, in :data:`~bench.campaigns.case_names.FAULT_EXPECTED`'s order with its expected reactions.
FAULTS = {name: FaultCase(name, expected, *FAULT_CASES[name], FAULT_TRACES.get(name), name in AT_REST)
          for name, expected in FAULT_EXPECTED.items()}

#: Each scene of :data:`~bench.campaigns.case_names.SCENE_DESCRIPTIONS`: its stimuli for sensor 1, as described there.
SCENE_STIMULI = {
    "rest": [],
    "taps": [Tap(0.5, 0.5), Tap(1.0, 1.0)],
    "sphere_drops": [SphereDrop(0.4 + 0.3 * k, SPHERES["1 mm steel bearing"][0]) for k in range(4)],
    "press": [Touch(0.3, 1.0, 0.2, 0.6, electrode="E17")],
}

#: The campaign's scenes (name -> stimuli), in :data:`~bench.campaigns.case_names.SCENE_DESCRIPTIONS`' order.
SCENES = {name: SCENE_STIMULI[name] for name in SCENE_DESCRIPTIONS}


#: How often a case sends START or STATUS on a lossy line (a fault with ``corrupt_rate`` or ``drop_rate``) before
#: it gives up: there the reply itself may be corrupted or lose bytes — which of the firmware's bytes the line hits
#: depends on when the request arrives, i.e. on the host's timing (measured: 4 of 80 lossy cases lost their START
#: acknowledgement with both cores busy) — and a host on such a line asks again.  On a clean line one unanswered
#: request fails the case.
LOSSY_LINE_TRIES = 3


def _ask(drv: BridgeDriver, send, reply_type, tries: int):
    """``send()`` and the reply of type ``reply_type`` (a command type, or Status), up to ``tries`` times; None if
    none came.  Each try waits the driver's ``REPLY_HORIZON_S`` (s), after which the driver takes the earlier
    request as lost, so a late reply goes to the latest request."""
    from bench.hosts.driver import REPLY_HORIZON_S

    for _ in range(tries):
        send()
        reply = drv.wait_for(reply_type, timeout_s=REPLY_HORIZON_S)
        if reply is not None:
            return reply
    return None


def _schedule_after_start(board, schedule) -> list:
    """Schedule ``schedule``'s actions (virtual s after streaming starts, action) when the firmware receives the
    host's first bytes (its START), in the firmware's own thread: when the host reads the virtual time or when its
    request is taken moves nothing.  (Scheduled from the host, a host slowed by a busy machine placed the actions
    late, several at once: cs_glitch then failed with "errors on a healthy link".)  Returns a list that then holds
    that instant (virtual s from power-on)."""
    receive = board.send_to_firmware
    started = []

    def first_bytes(data: bytes) -> None:
        board.send_to_firmware = receive
        started.append(board.t)
        for dt, action in schedule:
            board.at(board.t + dt, action)
        receive(data)

    board.send_to_firmware = first_bytes
    return started


def run_case(fault: FaultCase, scene, seed: int, frames_wanted: int = CASE_FRAMES, spi: str = "software",
             firmware=None, driver: str = BENCH_DRIVER, host_limit_s: float | None = None,
             driver_file: DriverFile | None = None) -> dict:
    """One fault in one scene — a built-in scene's name, or a scene file
    (:class:`~bench.campaigns.scene_files.CampaignScene`: its sensor 1 and stimuli, and its own number of frames)
    — over the SPI bus ``spi`` ("software" or "rtl") with ``firmware`` (None: the reference one; else
    FirmwareBench's ``firmware=``: your C sources or library) and the host ``driver`` (``MODULE:CALLABLE`` or
    ``PATH.py:CALLABLE``: :mod:`bench.campaigns.drivers`; ``driver_file``: a ``PATH.py`` driver's text as the
    campaign's client read it, :func:`~bench.campaigns.drivers.driver_file`; None: read here): the verdict (``passed``, ``problem``; ``error`` when
    the driver raised or lacks part of its interface, so no verdict was reached), what was expected, the bus, and
    ``seconds`` (the case's wall time, s).  A crash or hang of the firmware or driver is this case's failure (or
    error), never an exception: a driver whose calls have not returned within ``host_limit_s`` wall seconds (None:
    :data:`HOST_LIMIT_S` + :data:`HOST_LIMIT_PER_FRAME_S` per frame the case reads) makes the case an error, and the
    case's port is closed under it."""
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.cosim import default_sensors
    from bench.hosts.driver import CMD_START, REPLY_HORIZON_S, Status
    from emulator.channels import PAC

    t0 = time.perf_counter()
    problem, error = None, False
    own = not isinstance(scene, str)  # a scene file's
    try:
        stimuli = scene.stimuli if own else SCENES[scene]
        kw = {"n_sensors": 1, **fault.bench_kw}
        if firmware is not None:
            kw["firmware"] = list(firmware) if isinstance(firmware, tuple) else firmware
        sensor_faults = kw.pop("sensor_faults", None)
        if own:  # the scene's sensor 1 (and its twin), with the fault's own sensor faults
            kw["sensors"] = scene.sensors(kw["n_sensors"], seed, sensor_faults)
            frames_wanted = scene.frames
        elif sensor_faults:  # the sensors the bench would build, with these faults of their own
            kw["sensors"] = default_sensors(kw["n_sensors"], stimuli, seed, faults=sensor_faults)
        fb = FirmwareBench(stimuli=stimuli, seed=seed, spi=spi, **kw)
        started = _schedule_after_start(fb.board, fault.schedule)
        with fb:
            drv = open_driver(driver, fb.port, driver_file)
            tries = LOSSY_LINE_TRIES if fb.corrupt_rate or fb.drop_rate else 1

            def session():
                try:
                    with _blamed_on(driver):
                        acknowledged = _ask(drv, drv.start, CMD_START, tries)
                    if acknowledged is None:
                        raise TimeoutError(f"no acknowledgement of START within {tries} × {REPLY_HORIZON_S:g} s")
                    with _blamed_on(driver):
                        frames = list(drv.frames(max_frames=frames_wanted, timeout_s=10))
                        status = _ask(drv, drv.request_status, Status, tries)
                        stats = drv.parser.stats
                except BaseException:  # the driver's port closed on every way out, not left to the garbage collector
                    with suppress(Exception):
                        drv.close()
                    raise
                with _blamed_on(driver):
                    drv.close()
                return frames, status, stats

            if host_limit_s is None:
                host_limit_s = HOST_LIMIT_S + HOST_LIMIT_PER_FRAME_S * frames_wanted
            frames, status, stats = _within(session, host_limit_s, driver)
        unapplied = len(fb.board.events) + len(fb.board.resets)  # the fault's actions the run never reached
        if fault.schedule and unapplied:
            problem = f"{unapplied} of the fault's scheduled actions never happened (the stream ended before them)"
        elif fault.trace is not None and (missing := fault.trace(fb.board)) is not None:
            problem = missing
        elif len(frames) < frames_wanted // 2:
            problem = f"only {len(frames)} frames arrived"
        elif status is None:
            problem = "no status reply"
        elif (lost := uncounted_gaps(frames, stats.dropped_frames)) is not None:
            problem = lost
        else:
            problem = fault.check(frames, status, stats)
            pac = np.concatenate([f.codes[f.channels == PAC, 0] for f in frames if (f.status == 0).all()]
                                 or [np.array([2048])])
            if problem is None and not (0 <= pac.min() and pac.max() <= 4095):
                problem = "out-of-range data reached the caller"
            if problem is None and fault.at_rest:
                problem = not_at_rest(frames, fb.board.sensors, stimuli, started[0])
    except DriverFailed as e:  # the driver raised or cannot be used: the case reached no verdict
        problem, error = one_line(e), True
    except Exception as e:  # a crash or hang of the firmware or driver is a failure of the case
        problem = f"{type(e).__name__}: {e}"
    return {"fault": fault.name, "scene": scene.label if own else scene, "seed": seed, "spi": spi,
            "firmware": firmware_name(firmware), "expected": fault.expected,
            "driver": driver, **({"scene_file": scene.path} if own else {}),
            "passed": problem is None, "problem": problem, **({"error": True} if error else {}),
            "seconds": time.perf_counter() - t0}


#: How long (wall s) a case waits for a timed-out driver's thread to end once :class:`DriverStopped` has been raised
#: in it (a driver spinning in Python ends at its next bytecode; one blocked in C only when the call returns)
DRIVER_STOP_S = 5.0


class DriverStopped(BaseException):
    """Raised asynchronously into a host driver's thread whose case timed out (:func:`_within`), so that a driver
    spinning in Python stops rather than keep a worker's core busy for the rest of the campaign.  A BaseException,
    as KeyboardInterrupt is: a driver's ``except Exception`` does not swallow it."""


def _raise_in(thread: threading.Thread, exc_type: type) -> bool:
    """Raise ``exc_type`` in ``thread`` at its next Python bytecode (CPython's ``PyThreadState_SetAsyncExc``);
    False if the thread had already ended.  A thread blocked in C (a read, a sleep) sees it only when the call
    returns."""
    import ctypes

    set_async = ctypes.pythonapi.PyThreadState_SetAsyncExc
    set_async.argtypes = (ctypes.c_ulong, ctypes.py_object)
    n = set_async(thread.ident, exc_type)
    if n > 1:  # (never, with a live thread's own id: undone, as CPython's documentation asks)
        set_async(thread.ident, None)
    return n == 1


def _landing() -> None:
    """Nothing: a Python call, at whose start an exception raised asynchronously into the calling thread lands."""


def _within(session, limit_s: float, driver: str):
    """``session()``'s return value, run in a thread of its own: what it raises is raised here; if it has not
    returned within ``limit_s`` wall seconds, :class:`DriverFailed` naming ``driver``.  The thread is then stopped:
    :class:`DriverStopped` is raised in it and it is given :data:`DRIVER_STOP_S` to end, so a driver spinning in
    Python (``while True: pass``) no longer holds a core and the interpreter's lock through the next cases; one
    blocked in C ends when the caller closes the port under it (the thread is a daemon: if it never does, it does
    not keep the process alive), and the error says it had not ended.  It is stopped only while still inside
    ``session()``: one whose calls returned as the limit ran out is left to end (its id, once it has, may be another
    thread's), and a stop raised as it leaves lands in its own code, never in threading's."""
    outcome: dict = {}
    gate = threading.Lock()  # held to leave session() and to stop the thread: never both at once

    def run():
        try:
            try:
                outcome["value"] = session()
            except BaseException as e:
                outcome["error"] = e
            with gate:
                outcome["over"] = True
            _landing()  # (a DriverStopped raised as the session ended lands by this call, not in threading's)
        except DriverStopped:
            pass

    thread = threading.Thread(target=run, name="host driver", daemon=True)
    thread.start()
    thread.join(limit_s)
    if thread.is_alive():
        with gate:  # only into a thread still inside the session (an ended thread's id may be another's by now)
            stopping = "over" not in outcome and _raise_in(thread, DriverStopped)
        thread.join(DRIVER_STOP_S)
        ended = ("its calls returned just after that" if not stopping else
                 "its thread was stopped" if not thread.is_alive() else
                 f"its thread had not ended {DRIVER_STOP_S:g} s after being stopped (blocked in C: it ends when its "
                 f"port is closed)")
        raise DriverFailed(f"driver {driver} had not returned within {limit_s:g} s (a case's calls to the driver are "
                           f"bounded: start, frames, request_status and wait_for must return); {ended}")
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]


@contextmanager
def _blamed_on(driver: str):
    """An exception the host ``driver``'s own methods raise inside this block becomes :class:`DriverFailed`
    naming the driver (the case is then an error, not a verdict on the firmware)."""
    try:
        yield
    except Exception as e:
        raise DriverFailed(f"driver {driver} raised {type(e).__name__}: {e}") from None


#: How long (wall s) :func:`compile_kernels`' bench waits for a host before dropping the bytes nobody reads.
COMPILE_RUN_HOST_GONE_S = 1e-3


def compile_kernels(scenes) -> None:
    """Run the reference firmware over sensor 1 of each of ``scenes`` (built-in names or scene files, as in
    :func:`campaign_tasks`) for a case's length, here, with no host and before any case's wall-clock waits start.
    The emulator's numba kernels (the sensor's, the SPI model's) compile on their first call, inside a case's first
    firmware step: measured in a fresh clone with a load of 11 on 2 cores, a sliding scene's first step took 24 s,
    so its first ``none`` case read no frame within the 10 s it waits ("only 0 frames arrived") and passed when run
    again.  Compiled here, they reach every worker on this machine from numba's cache on disk (that step then takes
    0.3 s).  No case's frames change: these benches and sensors are thrown away."""
    from bench.campaigns.scene_files import frame_s
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.cosim import default_sensors
    from bench.hosts.driver import CMD_START, encode

    seen = set()
    for scene in scenes:
        own = not isinstance(scene, str)
        if (scene.path if own else scene) in seen:
            continue
        seen.add(scene.path if own else scene)
        sensors = scene.sensors(1, 0) if own else default_sensors(1, SCENES[scene], 0)
        fb = FirmwareBench(sensors=sensors, host_gone_s=COMPILE_RUN_HOST_GONE_S)
        try:
            fb.board.send_to_firmware(encode(CMD_START))
            fb.sim.run((scene.frames if own else CASE_FRAMES) * frame_s())
        finally:
            fb.stop()


def firmware_name(firmware) -> str:
    """How a report names the firmware a case ran: "reference", or your sources' or library's paths."""
    if firmware is None:
        return "reference"
    return ", ".join(map(str, firmware)) if isinstance(firmware, (list, tuple)) else str(firmware)


@dataclass(frozen=True)
class CaseTask:
    """One case of a campaign as a task: names, a seed and the SPI bus (a fault's schedule holds functions, which do
    not travel to a worker; the worker looks the fault and a built-in scene up by name; a scene file travels as its
    validated scene, :class:`~bench.campaigns.scene_files.CampaignScene`, so every worker runs the same one)."""

    fault: str
    scene: object  # a built-in scene's name (str) or a CampaignScene
    seed: int
    spi: str = "software"
    firmware: tuple | str | None = None  # None: the reference firmware; your sources (a tuple) or library (a path)
    driver: str = BENCH_DRIVER  # the host driver: MODULE:CALLABLE or PATH.py:CALLABLE (bench.campaigns.drivers)
    driver_file: DriverFile | None = None  # a PATH.py driver's text, read on the client: the same on every worker


def run_case_task(task: CaseTask) -> dict:
    """The engine's task: :func:`run_case` for the named fault and scene (a plain dict; ``seconds`` is wall s)."""
    return run_case(FAULTS[task.fault], task.scene, task.seed, spi=task.spi, firmware=task.firmware,
                    driver=task.driver, driver_file=task.driver_file)


def campaign_tasks(faults, scenes, seeds, spi: str = "software") -> list[CaseTask]:
    """Every fault × scene × seed over the SPI bus ``spi``, in that order (a scene: a built-in one's name or a
    :class:`~bench.campaigns.scene_files.CampaignScene`); ValueError for an empty campaign, an unknown name, or a
    fault the bus cannot carry (:func:`~bench.campaigns.case_names.check_bus`)."""
    faults, scenes, seeds = list(faults), list(scenes), list(seeds)
    if not (faults and scenes and seeds):
        raise ValueError("a campaign needs at least one fault, one scene and one seed (it would pass vacuously)")
    unknown = [f for f in faults if f not in FAULTS] + [s for s in scenes if isinstance(s, str) and s not in SCENES]
    if unknown:
        raise ValueError(f"unknown fault or scene: {', '.join(map(str, unknown))}")
    check_bus(faults, spi)
    return [CaseTask(f, s, seed, spi) for f in faults for s in scenes for seed in seeds]


def run_campaign(faults, scenes, seeds, spec=None, client=None, progress: bool = False,
                 spi: str = "software", firmware=None, driver: str = BENCH_DRIVER,
                 finished: dict | None = None) -> list[dict]:
    """Every fault × scene × seed over the SPI bus ``spi`` with the host ``driver`` (:mod:`bench.campaigns.drivers`)
    on the campaign engine (``spec``: a :class:`~bench.campaigns.engine.ClusterSpec`, default from the environment;
    or a connected ``client``); results in task order, one dict per case.  A fault the bus cannot carry is refused
    (ValueError), and a driver that does not import or cannot take the port
    (:class:`~bench.campaigns.drivers.DriverRefused`), before anything runs.  A ``PATH.py`` driver is read here (a
    relative path from this process's working directory) and its text goes out with every case
    (:class:`~bench.campaigns.drivers.DriverFile`): every worker, local or remote, runs the client's file.
    ``finished`` (a dict of the
    caller's): each case's result by its index as it finishes, so that a campaign stopped midway keeps them."""
    from bench.campaigns.drivers import driver_file, load_driver
    from bench.campaigns.engine import run_tasks
    from bench.hosts.cosim import build_firmware, firmware_library

    tasks = campaign_tasks(faults, scenes, seeds, spi)
    # a PATH.py driver is read here, on the client (a relative path: this working directory), and its text travels
    # with every case: a worker in another directory, or on a machine without the file, runs the same driver
    file = driver_file(driver)
    load_driver(driver, file)  # here, once: a driver that cannot be used is one error, not one per case
    tasks = [replace(t, driver=driver, driver_file=file) for t in tasks]
    if spi == "rtl":  # once, here, as the firmware: not one Verilator build per worker at the same time
        from bench.errors import BuildError
        from emulator.rtl.harness import Harness, HarnessError

        try:
            Harness().ensure_built()
        except HarnessError as e:  # (the emulator's RuntimeError: as the bench's, the campaign could not run)
            raise BuildError(f"--spi rtl: the RTL harness could not be built: {e}") from None
    build_firmware()  # once, here: the workers find it built (and a build error is one error, not one per case)
    compile_kernels([t.scene for t in tasks])  # once, here: no case waits for a compiler
    if firmware is not None:  # yours: built (or refused) here once too; each worker finds it by the same paths
        firmware_library(firmware)
        firmware = tuple(map(str, firmware)) if isinstance(firmware, (list, tuple)) else str(firmware)
        tasks = [replace(t, firmware=firmware) for t in tasks]
    return run_tasks(run_case_task, tasks, spec=spec, client=client, progress=progress, desc="cases",
                     on_result=None if finished is None else finished.__setitem__)


def _bus(results: list[dict]) -> str:
    """The SPI bus the results ran over ("software" or "rtl"; results from before the bus was recorded: software);
    ValueError for results from both buses (one report, one bus)."""
    buses = sorted({r.get("spi", "software") for r in results})
    if len(buses) > 1:
        raise ValueError(f"results over SPI buses {', '.join(buses)}: a report holds one campaign over one bus")
    return buses[0] if buses else "software"


#: how a report's suite states when the campaign began: UTC, to the second, with no zone (the Ant JUnit schema's
#: ``timestamp`` allows none; Jenkins and GitLab show it as the run's date)
JUNIT_TIMESTAMP = "%Y-%m-%dT%H:%M:%S"


def _when_and_where(started) -> dict[str, str]:
    """A report suite's ``timestamp`` — when the campaign ``started`` (a datetime; None: now), in UTC as
    :data:`JUNIT_TIMESTAMP` — and ``hostname``, the machine it ran on (``localhost`` when it has no name), as the
    Ant JUnit schema asks and Jenkins and GitLab show them."""
    import socket
    from datetime import datetime, timezone

    when = (started or datetime.now(timezone.utc)).astimezone(timezone.utc)
    return {"timestamp": when.strftime(JUNIT_TIMESTAMP), "hostname": socket.gethostname() or "localhost"}


#: the characters XML 1.0 cannot hold, escaped or not (its ``Char`` production: tab, line feed and carriage return
#: are the only controls it allows; lone surrogates and U+FFFE, U+FFFF are none)
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def xml_text(text: str) -> str:
    """``text`` with each character XML 1.0 cannot hold spelled out as Python spells it (ESC: ``\\x1b``), so a
    report carrying it stays well-formed and still shows it."""
    return _NOT_XML.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"), text)


def _write_suite(suite: ET.Element, path: Path) -> None:
    """Close ``suite`` with the suite-level ``system-out`` and ``system-err`` the Ant schema requires after the test
    cases (empty: each case carries its own), and write it whole or not at all, every text and attribute value
    made XML-safe (:func:`xml_text`: a problem, a path or a reason may hold control characters)."""
    ET.SubElement(suite, "system-out")
    ET.SubElement(suite, "system-err")
    for element in suite.iter():
        if element.text:
            element.text = xml_text(element.text)
        for key, value in element.attrib.items():
            element.set(key, xml_text(value))
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path) as tmp:
        ET.ElementTree(suite).write(tmp, encoding="utf-8", xml_declaration=True)


def case_output(r: dict) -> str:
    """What a report's test case shows as its output (``system-out``), passed or failed: the fault, scene, seed, SPI
    bus and firmware it ran, the verdict with what was expected (and the problem, for a failure) and its wall time."""
    verdict = "PASS" if r["passed"] else f"{'ERROR' if r.get('error') else 'FAIL'}: {r['problem']}"
    scene = f"{r['scene']} ({r['scene_file']})" if "scene_file" in r else r["scene"]
    return (f"fault {r['fault']} in scene {scene}, seed {r['seed']}, over the {r.get('spi', 'software')} SPI bus, "
            f"firmware {r.get('firmware', 'reference')}, driver {r.get('driver', BENCH_DRIVER)}\n"
            f"expected: {r['expected']}\n{verdict}\n"
            f"wall time {r['seconds']:.3f} s\n")


def write_junit(results: list[dict], path: Path, started=None, stopped: str | None = None,
                spi: str | None = None) -> None:
    """The JUnit XML report: one test case per result (the same names over either bus, so that two reports compare
    case by case), each with its output (:func:`case_output`, a passing case's too: a CI page shows what it
    checked), a failure carrying the problem (an error, for a case whose driver raised); the suite says when the
    campaign ``started`` (a datetime; None: now) and on which host (:func:`_when_and_where`), and the SPI bus
    (``spi``, else the results') as its property ``spi``, and, with results, the firmware and driver as ``firmware``
    and ``driver``.  ``stopped``: why the campaign ended before all its cases (Ctrl-C, SIGTERM, a cluster lost,
    could not run) — one more test case, ``unfinished``, with an error saying so, after the finished ones."""
    n_errors = sum(bool(r.get("error")) for r in results) + (stopped is not None)
    suite = ET.Element("testsuite", name="biotac-fault-campaign", tests=str(len(results) + (stopped is not None)),
                       failures=str(sum(not r["passed"] and not r.get("error") for r in results)),
                       errors=str(n_errors), skipped="0",  # (required by the JUnit schema CI tools validate against)
                       time=f"{sum(r['seconds'] for r in results):.3f}", **_when_and_where(started))
    properties = ET.SubElement(suite, "properties")
    ET.SubElement(properties, "property", name="spi", value=spi or _bus(results))
    if results:  # (a campaign that ran no case: which firmware and driver it would have run is not known here)
        firmwares = sorted({r.get("firmware", "reference") for r in results})
        ET.SubElement(properties, "property", name="firmware", value="; ".join(firmwares))
        drivers = sorted({r.get("driver", BENCH_DRIVER) for r in results})
        ET.SubElement(properties, "property", name="driver", value="; ".join(drivers))
    for r in results:
        case = ET.SubElement(suite, "testcase", classname=f"campaign.{r['fault']}",
                             name=f"{r['scene']}[seed={r['seed']}]", time=f"{r['seconds']:.3f}")
        if r.get("error"):  # the driver raised or could not be used: no verdict (the Ant schema's error)
            ET.SubElement(case, "error", message=r["problem"], type="driver-error").text = f"expected: {r['expected']}"
        elif not r["passed"]:
            ET.SubElement(case, "failure", message=r["problem"]).text = f"expected: {r['expected']}"
            case.find("failure").set("type", "unexpected-reaction")  # (the Ant schema requires a type)
        ET.SubElement(case, "system-out").text = case_output(r)
    if stopped is not None:
        case = ET.SubElement(suite, "testcase", classname="campaign", name="unfinished", time="0")
        ET.SubElement(case, "error", message=stopped, type="unfinished")
        ET.SubElement(case, "system-out").text = f"{stopped}\n"
    _write_suite(suite, path)


def write_unfinished_junit(path: Path, why: str, spi: str = "software", started=None, results=()) -> None:
    """A JUnit report for a campaign that did not finish (stopped by Ctrl-C or SIGTERM, or unable to run): the
    ``results`` of the cases that had finished and one error saying ``why``, so that a CI step that publishes the
    report whatever the exit status shows it, not an earlier campaign's report left at the path; the SPI bus it ran
    over as the suite's property ``spi``, and when it ``started`` (None: now) and on which host, as
    :func:`write_junit` says."""
    write_junit(list(results), path, started, stopped=why, spi=spi)


def summary(results: list[dict]) -> str:
    """The summary table: a header naming the SPI bus the cases ran over, one line per case, the count of passes and
    failures.  The fault, scene and seed columns are as wide as their longest entry (a scene file's name can be
    long), so that every line's result starts in the same column; a problem of several lines is shown on one."""
    fault_w = max([len("fault")] + [len(r["fault"]) for r in results])
    scene_w = max([len("scene")] + [len(str(r["scene"])) for r in results])
    seed_w = max([len("seed")] + [len(str(r["seed"])) for r in results])
    lines = [f"{'fault':{fault_w}s} {'scene':{scene_w}s} {'seed':>{seed_w}s}  result  expected / problem  "
             f"(SPI bus: {_bus(results)})"]
    for r in results:
        said = r["expected"] if r["passed"] else one_line(r["problem"])
        lines.append(f"{r['fault']:{fault_w}s} {str(r['scene']):{scene_w}s} {r['seed']:{seed_w}d}  "
                     f"{'PASS' if r['passed'] else 'ERROR' if r.get('error') else 'FAIL':6s}  {said}")
    n_fail = sum(not r["passed"] and not r.get("error") for r in results)
    n_error = sum(bool(r.get("error")) for r in results)
    lines.append(f"{len(results) - n_fail - n_error} passed, {n_fail} failed"
                 + (f", {n_error} error(s) (the driver raised or could not be used)" if n_error else ""))
    return "\n".join(lines)
