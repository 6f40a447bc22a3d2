"""The BioTac SP through the bridge firmware, the host driver and the Cheetah path.

The firmware recognises an SP by its "BTSP" serial, streams the 54-slot frame when every sensor present is an SP,
and reports E20..E24 asked of a 19-electrode BioTac as error words (status 2), which the driver never hands out as
codes.  Runs the firmware natively in virtual time (in-memory UART, no threads) so the streams are deterministic.
"""

import numpy as np
import pytest

from bench.hosts.cosim import CoSim, VirtualBoard, default_sensors
from bench.hosts.driver import CMD_START, CMD_STATUS, DataFrame, FrameParser, Status, encode
from emulator import channels as ch

pytestmark = pytest.mark.firmware
SP = ch.variant("biotac-sp")


def run_firmware(sensors, seconds=0.5, pattern=None, spi="software"):
    """Firmware against ``sensors`` for ``seconds`` of virtual time: (data frames, last STATUS) via the driver's
    parser."""
    out = bytearray()
    board = VirtualBoard(sensors, uart_out=out.extend, spi=spi)
    try:
        sim = CoSim(board)
        if pattern is not None:
            sim.set_pattern(pattern)
        board.send_to_firmware(encode(CMD_START))
        sim.run(seconds)
        board.send_to_firmware(encode(CMD_STATUS))
        sim.run(0.02)
    finally:
        board.bus.close()
    items = FrameParser().feed(bytes(out), now=0.0)
    frames = [f for f in items if isinstance(f, DataFrame)]
    status = [s for s in items if isinstance(s, Status)]
    return frames, status[-1] if status else None


def test_an_sp_streams_the_54_slot_frame_with_data_in_every_slot():
    frames, status = run_firmware(default_sensors(1, seed=3, variant="biotac-sp"))
    assert len(frames) >= 40
    for f in frames:
        assert [ch.variant("biotac-sp").channel_name[c] for c in f.channels] == list(SP.frame_names)
        assert f.codes.shape == (54, 1) and f.ok.all()
    assert status.sp_mask == 1 and status.sp_sensors == [1] and status.error_words == 0
    e = frames[-1].samples(1)
    assert all(100 < int(e[f"E{k}"][0]) < 4000 for k in range(20, 25))


def test_a_biotac_keeps_the_44_slot_frame_and_a_mixed_bus_the_common_one():
    frames, status = run_firmware(default_sensors(1, seed=3))
    assert frames[-1].codes.shape == (44, 1) and status.sp_mask == 0
    mixed = {**default_sensors(1, seed=3), 2: default_sensors(2, seed=3, variant="biotac-sp")[2]}
    frames, status = run_firmware(mixed)
    assert frames[-1].codes.shape == (44, 2) and status.sp_mask == 0b10 and frames[-1].ok.all()


def test_vendor_e20_to_e24_on_a_19_electrode_sensor_are_errors_never_data():
    """The SP pattern asked of a BioTac (sensor 1) and an SP (sensor 2) on one bus: the SP's E20..E24 are data,
    the BioTac's are its "EX" error words — status 2, absent from samples(), listed by errors()."""
    mixed = {**default_sensors(1, seed=3), 2: default_sensors(2, seed=3, variant="biotac-sp")[2]}
    frames, status = run_firmware(mixed, seconds=0.3, pattern=SP.frame_names)
    f = frames[-1]
    names = [ch.variant("biotac-sp").channel_name[c] for c in f.channels]
    bad = [n in {"E20", "E21", "E22", "E23", "E24"} for n in names]
    assert (f.status[bad, 0] == 2).all() and (f.status[~np.array(bad), 0] == 0).all()
    assert f.ok[:, 1].all()
    assert [e[1] for e in f.errors(1)] == [f"E{k}" for k in range(20, 25)] and not f.errors(2)
    assert all(e[2] == "error word" for e in f.errors(1))
    assert "E20" not in f.samples(1) or f.samples(1)["E20"].size == 0
    assert f.samples(2)["E20"].size == 1
    assert status.error_words == 5 * status.frames > 0 and status.parity_errors == 0


@pytest.mark.rtl
def test_sp_frames_are_identical_over_the_software_model_and_the_rtl():
    """Same sensors, same seed, same firmware: the 54-slot frames from the software bus and the Verilog bus."""
    a, _ = run_firmware(default_sensors(1, seed=5, variant="biotac-sp"), seconds=0.25)
    b, _ = run_firmware(default_sensors(1, seed=5, variant="biotac-sp"), seconds=0.25, spi="rtl")
    assert len(a) == len(b) >= 20
    for x, y in zip(a, b):
        assert x.seq == y.seq and np.array_equal(x.codes, y.codes) and np.array_equal(x.status, y.status)
    assert a[0].codes.shape == (54, 1)
