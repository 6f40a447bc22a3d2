"""The bridge firmware over the Verilog RTL (persistent C++ Verilator harness): identical frames to the
software model, detection by property reads included."""

import numpy as np
import pytest

from bench.hosts.cosim import CoSim, VirtualBoard, default_sensors
from bench.hosts.driver import CMD_START, DataFrame, FrameParser, encode

pytestmark = [pytest.mark.firmware, pytest.mark.rtl]


def frames_over(spi: str, n_sensors: int, seconds: float):
    parser, items = FrameParser(), []
    board = VirtualBoard(default_sensors(n_sensors, seed=5), uart_out=lambda b: items.extend(parser.feed(b)), spi=spi)
    sim = CoSim(board)
    board.send_to_firmware(encode(CMD_START))
    sim.run(seconds)
    if spi == "rtl":
        board.bus.close()
    return [i for i in items if isinstance(i, DataFrame)], parser.stats


@pytest.mark.parametrize("n_sensors", [1, 3])
def test_firmware_over_rtl_streams_the_same_frames_as_over_the_software_model(n_sensors):
    soft, _ = frames_over("software", n_sensors, 0.3)
    rtl, stats = frames_over("rtl", n_sensors, 0.3)
    assert len(rtl) == len(soft) >= 25 and stats.crc_errors == 0
    assert rtl[0].sensor_mask == (1 << n_sensors) - 1
    for a, b in zip(soft, rtl):
        assert np.array_equal(a.codes, b.codes) and np.array_equal(a.status, b.status)


def test_faults_that_need_the_software_bus_say_so():
    board = VirtualBoard(default_sensors(1), spi="rtl")
    with pytest.raises(ValueError, match="needs the software SPI bus"):
        board.unplug(1)
    board.bus.close()
