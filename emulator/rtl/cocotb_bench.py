"""cocotb 2.x test bench for the SPI RTL (loaded by the simulator; run through emulator.rtl.runner).

``SpiMaster`` drives the HDL master in tb_top one transaction at a time: Python wakes per transfer,
the simulator clocks SCK itself.  ``CodeServer`` answers the peripherals' ADC requests.

Tests read their inputs from environment variables set by the runner and write JSON results:
``vectors`` replays a vector file; ``frame_stream`` streams the default frame (44 slots; 54 on a BioTac SP).
"""

from __future__ import annotations

import json
import os
import time

import cocotb
from cocotb.triggers import Timer
from cocotb.utils import get_sim_time

from emulator.rtl.harness import fault_port_values
from emulator.spi.model import Transfer
from emulator.spi.vectors import load, rtl_provided_masks

PS = 1e-12


class SpiMaster:
    """Transaction-level SPI master: ``await master.transfer(...)`` returns the MISO bits the host sampled."""

    def __init__(self, dut):
        self.dut = dut

    async def transfer(self, t_ps: int, cs: int, mosi: int, nbits: int, half_ps: int, keep_cs: bool = False) -> int:
        now = get_sim_time("ps")
        if t_ps < now:
            raise ValueError(f"transfer at {t_ps} ps is in the past (now {now} ps)")
        if t_ps > now:
            await Timer(t_ps - now, unit="ps")
        d = self.dut
        d.req_cs.value = cs
        d.req_nbits.value = nbits
        d.req_mosi.value = mosi & ((1 << 64) - 1)
        d.req_half_ps.value = half_ps
        d.req_keep_cs.value = int(keep_cs)
        d.req_go.value = 1 - int(d.req_go.value)
        await d.rsp_done.value_change
        return int(d.rsp_miso.value) & ((1 << nbits) - 1) if nbits else 0

    async def run(self, tr: Transfer) -> int:
        half_ps = int(round(0.5 / tr.clock_hz / PS))
        return await self.transfer(int(round(tr.start_s / PS)), tr.cs, tr.mosi, tr.nbits, half_ps, tr.keep_cs)


class CodeServer:
    """Answers every ADC request of the five peripherals with ``source(sensor, channel, t_s) -> code``."""

    def __init__(self, dut, source):
        self.dut, self.source = dut, source
        self.requests = 0
        self._task = cocotb.start_soon(self._serve())

    async def _serve(self):
        d = self.dut
        seen = int(d.sample_req.value)
        while True:
            await d.sample_req.value_change
            now = int(d.sample_req.value)
            changed = now ^ seen
            seen = now
            codes = int(d.sample_code.value)
            channels = int(d.sample_channel.value)
            t = get_sim_time("ps") * PS
            for i in range(5):
                if changed >> i & 1:
                    ch = channels >> (6 * i) & 0x3F
                    code = int(self.source(i + 1, ch, t))
                    codes = codes & ~(0xFFF << (12 * i)) | (code << (12 * i))
                    self.requests += 1
            d.sample_code.value = codes
            d.sample_ack.value = now


async def reset(dut, present=0b11111, pull_up=False):
    dut.present.value = present
    dut.pull_up.value = int(pull_up)
    dut.rst_n.value = 0
    await Timer(100, unit="ns")
    dut.rst_n.value = 0b11111
    await Timer(100, unit="ns")


def set_faults(dut, faults: dict) -> None:
    """Set the fault ports to per-sensor faults given as {sensor: a ``Faults`` or its fields as a dict}; a sensor not
    named has none (the harness's own mapping: :func:`emulator.rtl.harness.fault_port_values`)."""
    for port, value in fault_port_values(faults).items():
        getattr(dut, port).value = value


@cocotb.test()
async def vectors(dut):
    """Replay vector files (BIOTAC_VECTORS, separated by os.pathsep); write each one's MISO to BIOTAC_RESULT.

    Each file starts on a fresh reset, shifted to the next whole microsecond after the previous one, so
    every timer difference is what the file recorded.
    """
    paths = [p for p in os.environ.get("BIOTAC_VECTORS", "").split(os.pathsep) if p]
    if not paths:
        return  # this test runs only when the runner hands it vector files
    results = {}
    queues: dict[int, list] = {}
    mismatched: list = []
    offset = [0]

    def source(sensor, channel, t_s):
        q = queues.get(sensor, [])
        t_ps = round(t_s / PS) - offset[0]
        if not q:
            mismatched.append({"sensor": sensor, "channel": channel, "t_ps": t_ps})
            return 0
        want = q.pop(0)
        if want["channel"] != channel or abs(want["t_ps"] - t_ps) > 1000:
            mismatched.append({"sensor": sensor, "channel": channel, "t_ps": t_ps, "recorded": want})
        return want["code"]

    CodeServer(dut, source)
    master = SpiMaster(dut)
    for path in paths:
        vec = load(path)
        offset[0] = (get_sim_time("ps") // 1_000_000 + 2) * 1_000_000
        await Timer(offset[0] - get_sim_time("ps") - 500_000, unit="ps")
        await reset(dut, sum(1 << (s - 1) for s in vec["sensors"]), vec["pull_up"])
        set_faults(dut, vec["faults"])
        dut.provided.value = sum(m << (64 * i) for i, m in enumerate(rtl_provided_masks(vec)))
        queues.clear()
        queues.update({s: [c for c in vec["conversions"] if c["sensor"] == s] for s in vec["sensors"]})
        mismatched.clear()
        resets = {int(k): v for k, v in vec.get("resets", {}).items()}
        miso = []
        for k, d in enumerate(vec["transfers"]):
            if k in resets:
                mask = sum(1 << (n - 1) for n in resets[k])
                dut.rst_n.value = 0b11111 & ~mask
                await Timer(10, unit="ps")
                dut.rst_n.value = 0b11111
                await Timer(10, unit="ps")
            miso.append(await master.transfer(offset[0] + d["t_ps"], d["cs"], int(d["mosi"], 16), d["nbits"],
                                              d["half_ps"], d["keep_cs"]))
        await Timer(200, unit="us")  # let any last conversion request arrive
        results[path] = {"miso": [f"{m:x}" for m in miso], "mismatched_requests": list(mismatched),
                         "unrequested": {s: len(q) for s, q in queues.items() if q},
                         "user_registers": f"{int(dut.user_registers.value):x}"}
        set_faults(dut, {})
    with open(os.environ["BIOTAC_RESULT"], "w") as f:
        json.dump(results, f)


@cocotb.test()
async def frame_stream(dut):
    """Stream the default frame from sensor 1 for BIOTAC_SECONDS with physics codes; write codes and rate."""
    seconds = float(os.environ.get("BIOTAC_SECONDS", "0"))
    if seconds <= 0:
        return
    import numpy as np

    from emulator.channels import parse_sequence
    from emulator.sensor import Sensor
    from emulator.spi import protocol as proto

    variant = os.environ.get("BIOTAC_VARIANT", "biotac")  # sensor 1's variant (the build's SP parameter)
    seq = parse_sequence("default", variant)
    sensor = Sensor(channels_read=list(seq), seed=int(os.environ.get("BIOTAC_SEED", "1")), variant=variant)
    await reset(dut)
    # coupling is decided by the next bus activity, which this schedule knows: reads start 50 µs later
    CodeServer(dut, lambda s, ch, t: int(sensor.sample(np.array([ch]), np.array([t]),
                                                        bus_active=np.array([False]))[0]))
    master = SpiMaster(dut)
    half_ps = int(round(0.5 / proto.HOST_DEFAULT_CLOCK_HZ / PS))
    slot_ps = int(round(1 / 4400 / PS))
    word_ps = 33 * half_ps
    n = int(seconds * 4400)
    words = []
    t0 = time.perf_counter()
    for k in range(n):
        t = 1_000_005 + k * slot_ps
        await master.transfer(t, 1, int(proto.sample_command(int(seq[k % len(seq)]))) << 8, 16, half_ps)
        words.append(await master.transfer(t + word_ps + 50_000_000, 1, 0, 16, half_ps))
    wall = time.perf_counter() - t0
    with open(os.environ["BIOTAC_RESULT"], "w") as f:
        json.dump({"words": words, "wall_s": wall, "simulated_s": seconds, "slots": n,
                   "t0_ps": 1_000_005, "slot_ps": slot_ps, "half_ps": half_ps}, f)
