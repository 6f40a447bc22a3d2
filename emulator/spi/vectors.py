"""Protocol vectors: transfers in, MISO and ADC conversions out — the contract both implementations meet.

A vector file (JSON) holds the bus set-up (sensors present, MISO pull, faults; optionally ``variants``,
{sensor: "biotac-sp"} where a sensor is not the default BioTac, and ``provided``, {sensor: channel indices} where
a sensor provides fewer channels than its variant recognises — the others answer "EX"), every transfer (start,
select code, bits, MOSI, SCK half period, chip select kept) with the MISO the host must receive, and
every conversion the sensors perform (sensor, channel, instant, code) in order.  Replaying feeds the
recorded codes back, so vectors test the protocol, not the physics.

Times are integers in picoseconds.  Generated traffic keeps every chip-select edge at 5 ns past a
10 ns grid, away from the sensor timer's microsecond edges, so both implementations count the same
ticks.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np

from emulator import channels as ch
from emulator.params import SensorParams
from emulator.sensor import NoiseSources, Sensor
from emulator.spi.model import SELECT_ALL, SELECT_CODE, SELECT_NONE, Bus, Faults, SensorPort, Transfer

PS = 1e-12


def variants_of(vectors: dict) -> dict[int, str]:
    """{sensor: variant name} of a vector dict (every sensor the default BioTac unless ``variants`` says)."""
    named = {int(k): v for k, v in vectors.get("variants", {}).items()}
    return {int(n): named.get(int(n), ch.DEFAULT_VARIANT) for n in vectors["sensors"]}


def provided_of(vectors: dict) -> dict[int, list[int]]:
    """{sensor: channel indices it provides}: its variant's channels unless ``provided`` names fewer."""
    named = {int(k): [int(c) for c in v] for k, v in vectors.get("provided", {}).items()}
    return {n: named.get(n, sorted(ch.variant(v).sampled_channels)) for n, v in variants_of(vectors).items()}


def rtl_provided_masks(vectors: dict) -> list[int]:
    """The RTL's ``provided`` port for sensors 1..5 (bit c set: channel index c): the channels ``provided`` names,
    or all 64 bits (every channel the sensor's variant recognises) for a sensor it does not name."""
    named = {int(k): sum(1 << int(c) for c in set(v)) for k, v in vectors.get("provided", {}).items()}
    return [named.get(n, 2**64 - 1) for n in range(1, 6)]


class ScriptedCodes:
    """A code source that replays recorded conversions in order and checks each request matches; ``variant`` and
    ``channels_read`` (indices) are the recorded sensor's."""

    def __init__(self, conversions: list[dict], sensor_index: int, params: SensorParams | None = None,
                 variant: str = ch.DEFAULT_VARIANT, channels_read=None):
        self.queue = [c for c in conversions if c["sensor"] == sensor_index]
        self.params = params or SensorParams()
        self.variant = variant
        self.channels_read = sorted(ch.variant(variant).sampled_channels if channels_read is None else channels_read)
        self.served = 0

    def sample(self, channels, times, bus_active=None):
        out = []
        for channel, t in zip(np.atleast_1d(channels), np.atleast_1d(times)):
            if self.served >= len(self.queue):
                raise AssertionError(f"unexpected conversion of channel {int(channel)} at {t:.9f} s")
            want = self.queue[self.served]
            if int(channel) != want["channel"] or abs(t - want["t_ps"] * PS) > 1e-9:
                raise AssertionError(f"conversion #{self.served}: got channel {int(channel)} at {t:.9f} s, "
                                     f"recorded channel {want['channel']} at {want['t_ps'] * PS:.9f} s")
            out.append(want["code"])
            self.served += 1
        return np.array(out, dtype=np.uint16)


class _Recorder:
    """Wraps a real sensor and records every conversion it performs."""

    def __init__(self, sensor, index, log):
        self.sensor, self.index, self.log = sensor, index, log
        self.channels_read, self.params, self.variant = sensor.channels_read, sensor.params, sensor.variant

    def sample(self, channels, times, bus_active=None):
        codes = self.sensor.sample(channels, times, bus_active)
        for channel, t, c in zip(channels, times, codes):
            self.log.append({"sensor": self.index, "channel": int(channel), "t_ps": int(round(t / PS)),
                             "code": int(c)})
        return codes


def transfer_from(d: dict) -> Transfer:
    return Transfer(d["t_ps"] * PS, d["cs"], int(d["mosi"], 16), d["nbits"], 1.0 / (2 * d["half_ps"] * PS),
                    d["keep_cs"])


def _faults_from(d: dict) -> dict[int, Faults]:
    return {int(k): Faults(**v) for k, v in d.items()}


def record(description: str, transfers: list[dict], sensors=(1,), pull_up=False, faults=None, seed=1,
           resets: dict | None = None, variants: dict | None = None, provided: dict | None = None) -> dict:
    """Run ``transfers`` (dicts with t_ps, cs, nbits, mosi hex, half_ps, keep_cs) through the reference model.

    ``resets`` maps a transfer index to the sensors reset just before it (the reset fault); ``variants`` {sensor:
    variant name} makes sensors BioTac SPs; ``provided`` {sensor: channel names} builds a sensor that provides
    only those (the rest of its variant's channels answer "EX").
    """
    faults, variants, provided = faults or {}, dict(variants or {}), dict(provided or {})
    unknown = sorted((set(variants) | set(provided)) - set(sensors))
    if unknown:
        raise ValueError(f"variants/provided name sensors {unknown} not among the sensors {list(sensors)}")
    log: list[dict] = []
    ports = {}
    for i in sensors:
        v = ch.variant(variants.get(i, ch.DEFAULT_VARIANT))
        names = provided.get(i, [v.channel_name[c] for c in sorted(v.sampled_channels)])
        real = Sensor(channels_read=list(names), seed=seed + i, noise=NoiseSources(), variant=v.name)
        ports[i] = SensorPort(_Recorder(real, i, log), i, faults.get(i))
    bus = Bus(ports, pull_up=pull_up)
    out = []
    for k, d in enumerate(transfers):
        for n in (resets or {}).get(k, []):
            bus.ports[n].reset()
        miso = bus.transfer(transfer_from(d))
        out.append({**d, "miso": f"{miso:x}"})
    bus.flush()
    extra = {}
    if any(v != ch.DEFAULT_VARIANT for v in variants.values()):
        extra["variants"] = {str(k): v for k, v in sorted(variants.items()) if v != ch.DEFAULT_VARIANT}
    if provided:
        extra["provided"] = {str(k): sorted(ports[k].provided) for k in sorted(provided)}
    return {"description": description, "sensors": list(sensors), "pull_up": pull_up,
            "faults": {str(k): asdict(v) for k, v in faults.items()},
            "resets": {str(k): v for k, v in (resets or {}).items()}, **extra,
            "transfers": out, "conversions": log}


def replay(vectors: dict) -> list[int]:
    """MISO of every transfer when the reference model replays ``vectors`` with the recorded codes."""
    faults = _faults_from(vectors["faults"])
    variants, provided = variants_of(vectors), provided_of(vectors)
    ports = {i: SensorPort(ScriptedCodes(vectors["conversions"], i, variant=variants[i], channels_read=provided[i]),
                           i, faults.get(i)) for i in vectors["sensors"]}
    bus = Bus(ports, pull_up=vectors["pull_up"])
    resets = {int(k): v for k, v in vectors.get("resets", {}).items()}
    out = []
    for k, d in enumerate(vectors["transfers"]):
        for n in resets.get(k, []):
            bus.ports[n].reset()
        out.append(bus.transfer(transfer_from(d)))
    bus.flush()
    for p in ports.values():
        if p.sensor.served != len(p.sensor.queue):
            raise AssertionError(f"sensor {p.index}: {len(p.sensor.queue) - p.sensor.served} recorded conversions "
                                 f"never requested")
    return out


def save(vectors: dict, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(vectors, indent=1))


def load(path: Path) -> dict:
    return json.loads(Path(path).read_text())


# --- traffic -------------------------------------------------------------------------------------------
HALF_PERIODS_PS = (50_000, 100_000, 120_000, 250_000, 500_000, 1_000_000)  # 10 MHz .. 500 kHz
FAST_HALF_PERIODS_PS = (20_000, 40_000)  # 25 and 12.5 MHz: above the limit


def tr(t_ps: int, cs: int, mosi: int, nbits: int = 16, half_ps: int = 100_000, keep_cs: bool = False) -> dict:
    return {"t_ps": int(t_ps), "cs": cs, "nbits": nbits, "mosi": f"{mosi:x}", "half_ps": half_ps, "keep_cs": keep_cs}


def end_ps(d: dict) -> int:
    return d["t_ps"] + (2 * d["nbits"] + 1) * d["half_ps"]


def on_grid(t_ps: int) -> int:
    """The next instant ≥ t at 5 ns past a 10 ns grid line."""
    return (t_ps + 4_999) // 10_000 * 10_000 + 5_000


def random_traffic(rng: np.random.Generator, n: int, sensors=(1, 2, 3), fast_clocks=False) -> list[dict]:
    """Random but mostly meaningful traffic: samplings, reads, properties, resends, writes, garbage, glitches."""
    from emulator.spi import protocol as proto

    codes = [SELECT_CODE[s] for s in sensors] + [SELECT_ALL, SELECT_NONE, SELECT_CODE[5]]
    out: list[dict] = []
    t = 1_000_005
    halves = HALF_PERIODS_PS + (FAST_HALF_PERIODS_PS if fast_clocks else ())
    for _ in range(n):
        kind = rng.choice(["sample", "read", "read", "property", "resend", "write", "garbage", "glitch", "short"])
        half = int(rng.choice(halves))
        cs = int(rng.choice(codes))
        if kind == "sample":
            ch = int(rng.choice([0, 1, 2, 3, 15, 17, 23, 35, 40]))
            mosi, nbits = (int(proto.sample_command(ch)) << 8) | int(rng.integers(0, 256)), 16
        elif kind == "read":
            mosi, nbits = int(rng.choice([0x0000, 0x0001])), int(rng.choice([16, 16, 24, 8]))
        elif kind == "property":
            mosi, nbits = (0x61 << 8) | int(rng.choice([0x10, 0x13, 0x15, 0x61, 0x70, 0x73, 0x42])), 16
        elif kind == "resend":
            mosi, nbits = (int(rng.choice([0x20, 0x50])) << 8), 16
        elif kind == "write":
            mosi, nbits = (0x40 << 8) | int(rng.integers(0, 256)), 16
        elif kind == "garbage":
            nbits = int(rng.integers(1, 40))
            mosi = int(rng.integers(0, 2**40)) & ((1 << nbits) - 1)
        elif kind == "glitch":
            mosi, nbits = 0, 0
        else:
            nbits = int(rng.integers(1, 16))
            mosi = int(rng.integers(0, 1 << nbits))
        keep = bool(rng.random() < 0.1)
        gap = int(rng.choice([200_000, 2_000_000, 20_000_000, 49_000_000, 51_000_000, 120_000_000]))
        d = tr(on_grid(t), cs, mosi, nbits, half, keep)
        out.append(d)
        t = end_ps(d) + (0 if keep and rng.random() < 0.5 else gap)
    out.append(tr(on_grid(t + 1_000_000), SELECT_NONE, 0, 0))  # release any held chip select
    return out
