"""The bridge firmware over the Verilog RTL (persistent C++ Verilator harness): identical frames to the
software model, detection by property reads included."""

import numpy as np
import pytest

from bench.hosts.cosim import VirtualBoard, default_sensors
from bench.tests.host_benches import run_firmware

pytestmark = [pytest.mark.firmware, pytest.mark.rtl]


@pytest.mark.parametrize("n_sensors", [1, 3])
def test_firmware_over_rtl_streams_the_same_frames_as_over_the_software_model(n_sensors):
    soft = run_firmware(default_sensors(n_sensors, seed=5), 0.3, status=False).frames
    over_rtl = run_firmware(default_sensors(n_sensors, seed=5), 0.3, spi="rtl", status=False)
    rtl = over_rtl.frames
    assert len(rtl) == len(soft) >= 25 and over_rtl.stats.crc_errors == 0
    assert rtl[0].sensor_mask == (1 << n_sensors) - 1
    for a, b in zip(soft, rtl):
        assert np.array_equal(a.codes, b.codes) and np.array_equal(a.status, b.status)


def test_faults_that_need_the_software_bus_say_so():
    board = VirtualBoard(default_sensors(1), spi="rtl")
    with pytest.raises(ValueError, match="needs the software SPI bus"):
        board.unplug(1)
    board.bus.close()


def test_spi_faults_on_the_rtl_bus_are_refused_not_ignored():
    """The documented way to inject an SPI fault on a bridge, ``setattr(board.bus.ports[k], "faults", Faults(...))``,
    changed nothing over the RTL (its fault ports are fixed while the harness streams): the host saw clean frames
    and the test passed.  It is refused by name; clearing faults (an empty ``Faults()``) stays allowed."""
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.driver import BridgeDriver
    from emulator.spi.model import Faults

    board = VirtualBoard(default_sensors(1), spi="rtl")
    try:
        board.bus.ports[1].faults = Faults()
        with pytest.raises(ValueError, match=r"sensor 1: SPI faults .*need the software SPI bus"):
            board.bus.ports[1].faults = Faults(miso_stuck=1)
        assert not board.bus.ports[1].faults.any
    finally:
        board.bus.close()
    bench = FirmwareBench(n_sensors=1, spi="rtl").start()
    driver = BridgeDriver(bench.port)
    try:
        driver.start()
        next(driver.frames(max_frames=1))
        bench.at(bench.virtual_time, lambda b: setattr(b.bus.ports[1], "faults", Faults(bad_parity=True)))
        list(driver.frames(max_frames=20, timeout_s=2.0))
    finally:
        driver.close()
        with pytest.raises(RuntimeError, match="need the software SPI bus"):
            bench.stop()
