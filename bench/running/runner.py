"""Run a scene: sensor -> SPI peripheral -> host sampler, streamed in chunks of simulated time."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from bench.running.sampler import Sampler
from bench.scenes.scene import Scene
from emulator.channels import CHANNEL_NAME
from emulator.sensor import Sensor
from emulator.spi.peripheral import SoftwarePeripheral


@dataclass
class ChannelRecord:
    """Samples of one channel: instants (s), codes, and per-sample status (0 = ok)."""

    times: np.ndarray
    codes: np.ndarray
    status: np.ndarray


@dataclass
class Recording:
    scene: Scene
    channels: dict[str, ChannelRecord]
    simulated_s: float
    wall_s: float
    effects: list[dict] = field(default_factory=list)
    error: str | None = None

    @property
    def realtime_factor(self) -> float:
        return self.simulated_s / self.wall_s if self.wall_s > 0 else float("inf")


def build_sensor(scene: Scene, block_s: float = 2.0) -> Sensor:
    return Sensor(params=scene.params, stimuli=scene.stimuli, channels_read=scene.channels,
                  fidelity=scene.fidelity, seed=scene.seed, noise=scene.noise, block_s=block_s, faults=scene.faults)


def peripheral_for(scene: Scene, sensor: Sensor):
    """The sensor's SPI side the scene asks for: the software model, or the RTL through the C++ harness."""
    if scene.spi == "rtl":
        from emulator.rtl.harness import HarnessPeripheral

        return HarnessPeripheral(sensor)
    return SoftwarePeripheral(sensor)


def run_scene(scene: Scene, progress: bool = True, chunk_s: float = 1.0) -> Recording:
    """Run ``scene`` to its end. On an error the recording so far is returned with ``error`` set."""
    from tqdm import tqdm

    t0 = time.perf_counter()
    sensor = build_sensor(scene)
    sampler = Sampler(peripheral_for(scene, sensor), scene.sequence, scene.slot_rate_Hz, scene.spi_clock_Hz)
    total_slots = int(round(scene.duration_s * scene.slot_rate_Hz))
    chunk_slots = max(1, int(round(chunk_s * scene.slot_rate_Hz)))
    parts: dict[int, list] = {c: [] for c in np.unique(sampler.sequence)}
    error = None
    bar = tqdm(total=round(scene.duration_s, 3), unit="sim s", disable=not progress, desc=scene.name,
               bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.1f}/{total:.1f} sim s [{elapsed}<{remaining}]")
    done = 0
    try:
        for s in sampler.chunks(total_slots, chunk_slots):
            for c, lst in parts.items():
                m = s.channels == c
                lst.append((s.times[m], s.codes[m], s.status[m]))
            done += s.times.size
            bar.update(s.times.size / scene.slot_rate_Hz)
    except Exception as e:  # keep what was recorded; the caller reports the error
        error = f"{type(e).__name__}: {e}"
    finally:
        bar.close()
    channels = {}
    for c, lst in parts.items():
        if lst:
            t, code, st = (np.concatenate(x) for x in zip(*lst))
        else:
            t, code, st = np.zeros(0), np.zeros(0, np.uint16), np.zeros(0, np.uint8)
        channels[CHANNEL_NAME[int(c)]] = ChannelRecord(t, code, st)
    return Recording(scene, channels, done / scene.slot_rate_Hz, time.perf_counter() - t0,
                     sensor.effects_report(), error)
