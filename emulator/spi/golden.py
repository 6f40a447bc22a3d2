"""The golden protocol vectors in fixtures/spi_vectors/: scenarios that pin the protocol down.

Regenerate with ``python -m emulator.spi.golden`` (only when the protocol itself changes on purpose:
the software model and the RTL must both reproduce these files bit for bit).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from emulator.channels import DEFAULT_FRAME_NAMES, channel_index
from emulator.spi import protocol as proto
from emulator.spi.model import SELECT_ALL, SELECT_CODE, SELECT_NONE, Faults
from emulator.spi.vectors import end_ps, on_grid, random_traffic, record, save, tr

OUT_DIR = Path(__file__).resolve().parents[2] / "fixtures" / "spi_vectors"
HALF = 100_000  # 5 MHz keeps every edge on the 10 ns grid
US = 1_000_000  # ps
S1 = SELECT_CODE[1]


class Script:
    """Builds a list of transfers, each starting ``gap`` after the previous one ended (on the grid)."""

    def __init__(self, t0_ps=1_000_005):
        self.items: list[dict] = []
        self.t = t0_ps

    def add(self, cs, mosi, nbits=16, gap_ps=60 * US, half_ps=HALF, keep_cs=False):
        d = tr(on_grid(self.t), cs, mosi, nbits, half_ps, keep_cs)
        self.items.append(d)
        self.t = end_ps(d) + gap_ps
        return self

    def sample(self, channel, cs=S1, second=0x00, **kw):
        return self.add(cs, (int(proto.sample_command(channel)) << 8) | second, **kw)

    def read(self, cs=S1, nbits=16, mosi=0x0000, **kw):
        return self.add(cs, mosi, nbits, **kw)

    def release(self):
        return self.add(SELECT_NONE, 0, 0, gap_ps=10 * US)


def sampling_and_errors() -> dict:
    s = Script()
    for name in DEFAULT_FRAME_NAMES[:8]:
        s.sample(channel_index(name)).read()
    s.sample(1).read(mosi=0x0001)  # the manual's 0x0001 read
    s.sample(0, gap_ps=20 * US).read().read().read()  # too soon (E.), then the word, then nothing left (E_)
    s.add(S1, 0x8100).read()  # PAC command with bad parity -> EE
    s.sample(15).read()  # HAL is not sampled -> EX
    s.add(S1, 0x8900).read()  # channel 4 does not exist -> EX
    s.add(S1, 0x0700).read()  # odd parity, not a command -> E?
    s.sample(0, gap_ps=1 * US).sample(1).read()  # ADC busy -> E-
    s.sample(1).add(S1, 0x86, nbits=8).read()  # a truncated command is ignored: the PDC sample is served
    return record("sampling, reads and every error word", s.items)


def properties() -> dict:
    s = Script()
    for prop, length in ((0x10, 3), (0x13, 5), (0x15, 17), (0x73, 45)):
        s.add(S1, 0x6100 | prop)
        for k in range(length + 1):  # one byte per transfer, chip select held, past the NUL into 0xFF
            s.add(S1, 0, 8, gap_ps=10 * US, keep_cs=True)
        s.release()
    for prop in (0x61, 0x70):  # binary: two bytes in one transfer
        s.add(S1, 0x6100 | prop).read()
    s.add(S1, 0x6142).read()  # unknown property -> EX
    return record("property reads, byte by byte with chip select held", s.items)


def resend_and_write() -> dict:
    s = Script()
    s.add(S1, 0x2000).read()  # nothing to resend yet
    s.sample(1).read().add(S1, 0x2000).read().add(S1, 0x5000).read()
    for n, v, good in ((0, 5, True), (3, 2, True), (1, 3, False), (6, 1, True), (2, 7, True)):
        byte = int(proto.with_odd_parity((n << 3) | v)) ^ (0 if good else 1)
        s.add(S1, 0x4000 | byte).read()
    return record("resend (both spellings) and parameter writes", s.items)


def _broadcast_then_each() -> list[dict]:
    """Four sampling commands to all sensors, each followed by a read of every sensor in turn."""
    s = Script()
    for channel in (0, 1, 0, 17):
        s.sample(channel, cs=SELECT_ALL, gap_ps=50 * US)
        for n in range(1, 6):  # back to back, the select code switching with chip select held
            s.add(SELECT_CODE[n], 0, 16, gap_ps=0, keep_cs=True)
        s.release()
    return s.items


def variants_and_provided() -> dict:
    """A BioTac SP (sensor 1) beside a BioTac that provides only some channels (sensor 2): the SP answers
    E20..E24 (0xC8..0xD0) and its own serial; the BioTac answers "EX" for E20 (not a channel it has) and for E2 and
    TAC (channels it has but was not built to provide), data for the rest; a broadcast E20 converts on the SP only."""
    s, s2 = Script(), SELECT_CODE[2]
    for name in ("E20", "E21", "E22", "E23", "E24", "PAC"):
        s.sample(channel_index(name, "biotac-sp"), cs=S1).read(cs=S1)
    for name in ("E20", "E2", "TAC", "PAC", "E1"):
        s.sample(channel_index(name, "biotac-sp"), cs=s2).read(cs=s2)
    s.sample(channel_index("E20", "biotac-sp"), cs=SELECT_ALL, gap_ps=50 * US)
    for n in (1, 2):
        s.add(SELECT_CODE[n], 0, 16, gap_ps=0, keep_cs=True)
    s.release()
    for cs in (S1, s2):  # the serial numbers, byte by byte: 16 characters, the NUL, and 0xFF past it
        s.add(cs, 0x6115)
        for _ in range(18):
            s.add(cs, 0, 8, gap_ps=10 * US, keep_cs=True)
        s.release()
    return record("a BioTac SP beside a BioTac providing PAC, PDC, TDC and E1 only", s.items, sensors=(1, 2),
                  variants={1: "biotac-sp"}, provided={2: ["PAC", "PDC", "TDC", "E1"]})


def five_sensors(present=(1, 2, 3, 4, 5), pull_up=False, name="five sensors", faults=None) -> dict:
    return record(f"{name}: broadcast sampling, per-sensor reads", _broadcast_then_each(), sensors=present,
                  pull_up=pull_up, faults=faults)


def with_fault(name: str, faults: dict, builder=None) -> dict:
    s = builder() if builder else Script().sample(1).read().sample(0).read()
    return record(f"fault: {name}", s.items, faults=faults)


def fault_vectors() -> dict[str, dict]:
    out = {
        "miso_bit_flip": with_fault("MISO bit 3 inverted", {1: Faults(miso_flip_bit=3)}),
        "mosi_bit_flip": with_fault("MOSI bit 4 inverted", {1: Faults(mosi_flip_bit=4)}),
        "miso_stuck_low": with_fault("MISO stuck at 0", {1: Faults(miso_stuck=0)}),
        "miso_stuck_high": with_fault("MISO stuck at 1", {1: Faults(miso_stuck=1)}),
        "corrupted_parity": with_fault("response parity inverted", {1: Faults(bad_parity=True)}),
        "slow_response": with_fault("results ready after 100 µs", {1: Faults(slow_response=True)},
                                    lambda: Script().sample(1).read().sample(1).read(gap_ps=110 * US)),
    }
    s = Script().sample(1).add(S1, 0, 0, gap_ps=60 * US).read()  # CS glitch: no clock edges
    out["cs_glitch"] = record("fault: chip-select glitch", s.items)
    s = Script().sample(1).read(nbits=13).read()  # truncated read, then a full one
    out["truncated_word"] = record("fault: truncated word", s.items)
    s = Script().sample(1).read(half_ps=40_000).add(S1, 0x2000).read(half_ps=20_000)  # 12.5 and 25 MHz
    out["clock_above_limit"] = record("fault: SCK above 10 MHz", s.items)
    out["sensor_absent"] = five_sensors((1, 2, 4), name="sensors 3 and 5 absent (MISO pulled down)")
    out["sensor_absent_pull_up"] = five_sensors((1, 2, 4), pull_up=True, name="sensors 3 and 5 absent (pull-up)")
    # faults on sensors other than the first: each bench must route a sensor's fault to that sensor alone
    out["other_sensors"] = five_sensors(
        name="fault: MISO stuck high on sensor 2, MOSI bit 4 inverted on sensor 3",
        faults={2: Faults(miso_stuck=1), 3: Faults(mosi_flip_bit=4)})
    # a reset between command and read (the pending result is gone), then one between a served read and a resend
    # command (the resend buffer is gone too)
    s = Script().sample(1).sample(0).read().sample(1).read().add(S1, 0x2000).read()
    out["reset_mid_stream"] = record("fault: sensor reset between command and read, and before a resend", s.items,
                                     resets={2: [1], 5: [1]})
    return out


def all_vectors() -> dict[str, dict]:
    out = {"sampling_and_errors": sampling_and_errors(), "properties": properties(),
           "resend_and_write": resend_and_write(), "five_sensors": five_sensors(),
           "variants_and_provided": variants_and_provided()}
    out.update({f"fault_{k}": v for k, v in fault_vectors().items()})
    out["random"] = record("random traffic on three sensors", random_traffic(np.random.default_rng(2012), 1500,
                                                                            fast_clocks=True), sensors=(1, 2, 3))
    return out


def main() -> None:
    for name, vec in all_vectors().items():
        save(vec, OUT_DIR / f"{name}.json")
        print(f"wrote {OUT_DIR / name}.json ({len(vec['transfers'])} transfers, {len(vec['conversions'])} conversions)")


if __name__ == "__main__":
    main()
