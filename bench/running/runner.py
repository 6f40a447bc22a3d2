"""Run a scene: sensor -> SPI peripheral -> host sampler, streamed in chunks of simulated time.

Each chunk's samples go, per channel, to a :class:`~bench.running.aggregate.RunSummary` (statistics and plot
data of bounded size), to any ``sinks`` (e.g. the HDF5 store that writes ``samples.h5`` as the run goes), and —
when ``keep_samples`` is true, the default for runs up to :data:`KEEP_SAMPLES_MAX_S` — to memory, so that
``Recording.channels["PAC"].codes`` works as it always did.  A run keeps going until its end, an error (kept in
``Recording.error``, status ``"failed"``), or ``should_stop()`` turning true at a chunk boundary (status
``"interrupted"``; also when a native build that a stop signal reached fails, its error kept); whatever was
recorded up to then is in the recording.

A scene with several sensors (``[[sensors]]``, or a stimulus's ``sensor = k``) runs each sensor through its own
SPI peripheral and host sampler (the scene's host sequence, independent noise: seed + k - 1): the recording is
sensor 1's, as for a one-sensor scene, and ``Recording.sensors`` maps 2..N to each other sensor's own
:class:`Recording` (its scene is ``scene.for_sensor(k)``).  ``sinks`` receive sensor 1's samples only.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from bench.errors import BuildError, SceneError
from bench.running.aggregate import RunSummary
from bench.running.sampler import Sampler
from bench.running.slides import SlideRecorder
from bench.scenes.scene import Scene
from emulator.channels import ALL_CHANNEL_INDEX
from emulator.sensor import DEFAULT_BLOCK_S, Sensor
from emulator.spi.peripheral import SoftwarePeripheral

#: Every channel any variant has (E1..E24), by index: a BioTac SP's E20..E24 are named too.
CHANNEL_NAME: dict[int, str] = {i: n for n, i in ALL_CHANNEL_INDEX.items()}

#: ``run_scene`` keeps every sample in memory by default only up to this simulated duration (s).
KEEP_SAMPLES_MAX_S = 600.0


@dataclass
class ChannelRecord:
    """Samples of one channel: instants (s), codes, and per-sample status (0 = ok)."""

    times: np.ndarray
    codes: np.ndarray
    status: np.ndarray


@dataclass
class Recording:
    """What a run produced.  ``channels`` maps channel names to :class:`ChannelRecord`: in memory, or read back
    on demand from ``samples.h5`` (see ``bench.reporting.store``), or empty when the samples were neither kept
    nor stored; ``summary`` always holds the statistics and plot data."""

    scene: Scene
    channels: Mapping[str, ChannelRecord]
    simulated_s: float
    wall_s: float
    effects: list[dict] = field(default_factory=list)
    error: str | None = None
    status: str = ""  # "ok" | "failed" | "interrupted"; derived from ``error`` when left empty
    summary: RunSummary | None = None
    channel_names: list[str] = field(default_factory=list)
    slides: list[dict] = field(default_factory=list)  # one row per sliding trial: texture, movement, properties
    forces: dict = field(default_factory=dict)  # the sliding contact's force log at 100 Hz (s, N, N, m/s)
    sensors: dict = field(default_factory=dict)  # sensors 2..N of a several-sensor scene: number -> Recording

    def __post_init__(self):
        if not self.status:
            self.status = "failed" if self.error else "ok"
        if not self.channel_names:
            self.channel_names = list(self.channels)

    @property
    def realtime_factor(self) -> float:
        return self.simulated_s / self.wall_s if self.wall_s > 0 else float("inf")


def build_sensor(scene: Scene, block_s: float = DEFAULT_BLOCK_S) -> Sensor:
    """Sensor 1 of ``scene`` (``scene.for_sensor(k)`` for another), carrying its unit's serial as ``.serial``
    (None for the nominal unit: the host then sees the port's own default serial, different per sensor)."""
    sensor = Sensor(params=scene.params, stimuli=scene.stimuli, channels_read=scene.channels,
                    fidelity=scene.fidelity, seed=scene.seed, noise=scene.noise, block_s=block_s, faults=scene.faults,
                    variant=scene.variant)
    sensor.serial = None if scene.unit == "nominal" or not scene.serial else scene.serial
    return sensor


def check_buildable(scene: Scene) -> None:
    """Build every sensor of ``scene`` once (milliseconds), as a run would first: values each valid that no sensor
    can have together raise :class:`~bench.errors.SceneError` naming the scene — before a run touches its out
    folder, and in ``validate``, so that the two agree."""
    problems = []
    for k in range(1, scene.n_sensors + 1):
        try:
            build_sensor(scene.for_sensor(k))
        except (ValueError, TypeError) as e:
            problems.append(f"sensor {k}: {e}" if scene.n_sensors > 1 else str(e))
    if problems:
        raise SceneError(str(scene.source), problems)


def peripheral_for(scene: Scene, sensor: Sensor):
    """The sensor's SPI side the scene asks for: the software model, or the RTL through the C++ harness (a process:
    ``close()`` it when done, as :func:`run_one_sensor` does)."""
    if scene.spi == "rtl":
        from emulator.rtl.harness import HarnessPeripheral

        return HarnessPeripheral(sensor)
    return SoftwarePeripheral(sensor)


def build_rtl_first(scene: Scene, sensor: Sensor, bar) -> bool:
    """Build the RTL harness the scene's sensor runs on, if it is not built from today's sources (a first
    ``--spi rtl``, or the RTL changed), saying so on the progress ``bar`` (tqdm) while Verilator runs; whether it
    built (the run's wall time and its bar then start after the build, which is no part of the run's speed)."""
    if scene.spi != "rtl":
        return False
    from emulator.rtl.harness import harness_for

    harness = harness_for({1: sensor})
    if harness.up_to_date():
        return False
    bar.set_description_str(f"{scene.name}: building the RTL harness with Verilator (first use, a minute or more)")
    harness.ensure_built()
    bar.set_description_str(scene.name)
    return True


def read_channel_names(scene: Scene) -> list[str]:
    """The channels the scene's host reads, in channel-index order (the keys of ``Recording.channels``)."""
    seq = Sampler(None, scene.sequence, scene.slot_rate_Hz, scene.spi_clock_Hz, variant=scene.variant).sequence
    return [CHANNEL_NAME[int(c)] for c in np.unique(seq)]


@dataclass
class Chunk:
    """One chunk of samples sorted by channel (time order kept within each channel), and ``parts``: channel
    name → (instants, codes, status) as views into those arrays."""

    times: np.ndarray
    channels: np.ndarray
    codes: np.ndarray
    status: np.ndarray
    parts: dict


def split_by_channel(times, channels, codes, status) -> Chunk:
    """Interleaved samples of consecutive slots → a :class:`Chunk` sorted by channel."""
    order = np.argsort(channels, kind="stable")
    t, ch, code, st = times[order], channels[order], codes[order], status[order]
    cut = np.concatenate([[0], np.flatnonzero(np.diff(ch)) + 1, [ch.size]])
    parts = {CHANNEL_NAME[int(ch[a])]: (t[a:b], code[a:b], st[a:b]) for a, b in zip(cut[:-1], cut[1:]) if b > a}
    return Chunk(t, ch, code, st, parts)


def make_chunk(parts: dict) -> Chunk:
    """A :class:`Chunk` from channel name → (instants, codes, status) given in channel-index order or not."""
    CHANNEL_INDEX = ALL_CHANNEL_INDEX  # noqa: N806

    names = sorted((n for n in parts if len(parts[n][0])), key=lambda n: CHANNEL_INDEX[n])
    if not names:
        z = np.zeros(0)
        return Chunk(z, z.astype(np.int64), z.astype(np.uint16), z.astype(np.uint8), {})
    t, code, st = (np.concatenate([np.asarray(parts[n][i]) for n in names]) for i in range(3))
    ch = np.concatenate([np.full(len(parts[n][0]), CHANNEL_INDEX[n]) for n in names])
    return split_by_channel(t, ch, code, st)


def run_scene(scene: Scene, progress: bool = True, chunk_s: float = 1.0, *, keep_samples: bool | None = None,
              sinks=(), should_stop=None, block_s: float = DEFAULT_BLOCK_S) -> Recording:
    """Run every sensor of ``scene``: sensor 1 as :func:`run_one_sensor` (with ``sinks``), then sensors 2..N, each
    into ``Recording.sensors[k]`` (samples kept in memory for scenes up to :data:`KEEP_SAMPLES_MAX_S`); every
    sensor computes its physics in blocks of ``block_s`` (s), which changes no sample."""
    rec = run_one_sensor(scene, progress, chunk_s, keep_samples=keep_samples, sinks=sinks, should_stop=should_stop,
                         block_s=block_s)
    for k in range(2, scene.n_sensors + 1):
        if rec.status != "ok":
            break
        rec.sensors[k] = run_one_sensor(scene.for_sensor(k), progress, chunk_s, should_stop=should_stop,
                                        block_s=block_s)
        if rec.sensors[k].status != "ok" and rec.error is None:
            rec.status = rec.sensors[k].status
            rec.error = None if rec.sensors[k].error is None else f"sensor {k}: {rec.sensors[k].error}"
    return rec


def run_one_sensor(scene: Scene, progress: bool = True, chunk_s: float = 1.0, *, keep_samples: bool | None = None,
                   sinks=(), should_stop=None, block_s: float = DEFAULT_BLOCK_S) -> Recording:
    """Run ``scene`` to its end, an error, or ``should_stop()`` (checked at every chunk boundary).

    ``keep_samples``: hold every sample in ``Recording.channels`` (default: only for scenes up to
    :data:`KEEP_SAMPLES_MAX_S`; longer ones keep the summary only).  ``sinks``: objects with ``add(parts)``
    receiving each chunk as channel name → (instants, codes, status).  An exception in the sampler or a sink
    ends the run: the recording so far is returned with ``error`` set and status ``"failed"`` (``"interrupted"``
    for a :class:`~bench.errors.BuildError` after a stop signal: the compilers got the same Ctrl-C).
    ``block_s``: the sensor's physics block (s, :class:`~emulator.sensor.Sensor`); no sample depends on it.
    """
    from tqdm import tqdm

    if keep_samples is None:
        keep_samples = scene.duration_s <= KEEP_SAMPLES_MAX_S
    t0 = time.perf_counter()
    names = read_channel_names(scene)
    summary = RunSummary(scene, names)
    slide_recorder = SlideRecorder(scene)
    parts: dict[str, list] = {n: [] for n in names}
    error, status = None, "ok"
    done = 0
    sensor = peripheral = None
    bar = tqdm(total=round(scene.duration_s, 3), unit="sim s", disable=not progress, desc=scene.name,
               bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.1f}/{total:.1f} sim s [{elapsed}<{remaining}]")
    try:
        sensor = build_sensor(scene, block_s)
        if build_rtl_first(scene, sensor, bar):
            t0 = time.perf_counter()
            bar.reset()
        peripheral = peripheral_for(scene, sensor)
        sampler = Sampler(peripheral, scene.sequence, scene.slot_rate_Hz, scene.spi_clock_Hz, variant=scene.variant)
        total_slots = int(round(scene.duration_s * scene.slot_rate_Hz))
        chunk_slots = max(1, int(round(chunk_s * scene.slot_rate_Hz)))
        for s in sampler.chunks(total_slots, chunk_slots):
            chunk = split_by_channel(s.times, s.channels, s.codes, s.status)
            summary.add(chunk)
            if slide_recorder:
                slide_recorder.add(chunk.parts)
            for sink in sinks:
                sink.add(chunk.parts)
            if keep_samples:
                for name, p in chunk.parts.items():
                    parts[name].append(p)
            done += s.times.size
            bar.update(s.times.size / scene.slot_rate_Hz)
            if should_stop is not None and should_stop() and done < total_slots:
                status = "interrupted"
                break
    except Exception as e:  # keep what was recorded; the caller reports the error
        error = f"{type(e).__name__}: {e}"
        # a build the same Ctrl-C reached (a first RTL build's compilers die of it) ended the run: interrupted, the
        # build's last words kept in the error; any other failure is one, signal or not
        status = "interrupted" if isinstance(e, BuildError) and should_stop is not None and should_stop() else "failed"
    finally:
        bar.close()
        if hasattr(peripheral, "close"):  # the RTL's harness process
            peripheral.close()
    try:
        summary.finish()
    except Exception as e:  # a summary that cannot finish must not hide the run
        if error is None:
            error, status = f"{type(e).__name__}: {e}", "failed"
    channels: dict[str, ChannelRecord] = {}
    if keep_samples:
        for name, lst in parts.items():
            if lst:
                t, code, st = (np.concatenate(x) for x in zip(*lst))
            else:
                t, code, st = np.zeros(0), np.zeros(0, np.uint16), np.zeros(0, np.uint8)
            channels[name] = ChannelRecord(t, code, st)
    effects = sensor.effects_report() if sensor is not None else []
    slides, forces = [], {}
    if slide_recorder:
        try:
            slides, forces = slide_recorder.finish(sensor), slide_recorder.force_traces(sensor)
        except Exception as e:  # properties that cannot be computed must not hide the run
            if error is None:
                error, status = f"{type(e).__name__}: {e}", "failed"
    return Recording(scene, channels, done / scene.slot_rate_Hz, time.perf_counter() - t0, effects, error, status,
                     summary, names, slides, forces)
