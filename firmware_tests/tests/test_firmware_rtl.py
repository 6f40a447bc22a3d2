"""The bridge firmware over the Verilog RTL (persistent C++ Verilator harness): identical frames to the
software model, detection by property reads included."""

import numpy as np
import pytest

from bench.hosts.cosim import VirtualBoard, default_sensors
from bench.tests.host_benches import run_firmware
from emulator.spi.model import Faults

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


def _same_frames_on_both_buses(seconds: float, prepare, min_frames: int, status: bool = False) -> dict:
    """Run the bridge firmware with three sensors over the software model and over the RTL, ``prepare`` scheduling
    the same events on each board; check the host got the same frames (sensors, codes, status words) over both and
    no CRC error; return both runs by bus."""
    runs = {spi: run_firmware(default_sensors(3, seed=5), seconds, status=status, spi=spi, prepare=prepare)
            for spi in ("software", "rtl")}
    soft, rtl = runs["software"].frames, runs["rtl"].frames
    assert len(rtl) == len(soft) >= min_frames and runs["rtl"].stats.crc_errors == 0
    for k, (a, b) in enumerate(zip(soft, rtl)):
        assert a.sensor_mask == b.sensor_mask and np.array_equal(a.codes, b.codes) and \
            np.array_equal(a.status, b.status), f"frame {k} differs"
    return runs


def _schedule_hot_plugging(board) -> None:
    """Sensor 2 unplugged at 50 ms and plugged back in at 120 ms; sensor 3 unplugged at 150 ms, back at 200 ms."""
    for dt, act, n in ((0.05, "unplug", 2), (0.12, "plug", 2), (0.15, "unplug", 3), (0.2, "plug", 3)):
        board.at(board.t + dt, lambda b, act=act, n=n: getattr(b, act)(n))


def test_hot_plugging_gives_the_same_frames_and_status_over_the_rtl_as_over_the_software_model():
    """``board.unplug`` / ``board.plug`` over the RTL (the RTL's sensors present changed, a sensor plugged back in
    reset, at the next word) give the host the same frames and the same status as over the software model: sensor
    2 lost and found again (it answers its serial number from power-on), sensor 3 lost."""
    runs = _same_frames_on_both_buses(0.4, _schedule_hot_plugging, 35, status=True)
    rtl = runs["rtl"].frames
    assert runs["rtl"].status == runs["software"].status
    assert (runs["rtl"].status.losses, runs["rtl"].status.finds) == (2, 1)
    masks = [f.sensor_mask for f in rtl]
    assert masks[0] == 0b111 and 0b101 in masks and masks[-1] == 0b011


#: brown-outs (virtual s after start-up, sensor) and chip-select glitches (virtual s, sensor)
RESETS = [(0.05 + 20e-6, 2), (0.1 + 20e-6, 1), (0.1 + 30e-6, 3), (0.15 + 1e-3, 2), (0.2, 2)]
GLITCHES = [(0.06, 1), (0.12, 3), (0.17, 2)]


def _schedule_resets_and_glitches(board) -> None:
    for dt, n in RESETS:
        board.reset_at(n, board.t + dt)
    for dt, n in GLITCHES:
        board.at(board.t + dt, lambda b, n=n: b.glitch(n))


def test_brownouts_and_glitches_give_the_same_frames_over_the_rtl_as_over_the_software_model():
    """``board.reset_at`` (a brown-out inside a frame's SPI sequence: the port's reset reaches the RTL sensor with
    the next word) and ``board.glitch`` on three sensors give the host the same frames over the RTL as over the
    software model: each reset loses a pending result (an error word reaches the host for that sensor), no sensor
    is dropped, and the glitches change nothing."""
    rtl = _same_frames_on_both_buses(0.3, _schedule_resets_and_glitches, 25)["rtl"].frames
    flagged = [{n for n, bad in zip(f.sensors, (f.status != 0).any(axis=0)) if bad} for f in rtl]
    assert set().union(*flagged) == {1, 2, 3}  # every reset sensor lost a result the host then saw flagged
    assert rtl[-1].sensors == [1, 2, 3]


#: (virtual s after start-up, sensor, faults): each sensor's fault set, then cleared (Faults()) 40 ms later.
FAULT_SCHEDULE = [(0.04, 1, Faults(bad_parity=True)), (0.08, 1, Faults()), (0.08, 2, Faults(miso_flip_bit=5)),
                  (0.12, 2, Faults()), (0.12, 3, Faults(slow_response=True)), (0.16, 3, Faults()),
                  (0.16, 2, Faults(miso_stuck=0)), (0.20, 2, Faults()), (0.20, 1, Faults(mosi_flip_bit=1)),
                  (0.24, 1, Faults())]


def _schedule_faults(board) -> None:
    for dt, n, faults in FAULT_SCHEDULE:
        board.at(board.t + dt, lambda b, n=n, f=faults: setattr(b.bus.ports[n], "faults", f))


def test_a_fault_schedule_gives_the_same_frames_over_the_rtl_as_over_the_software_model():
    """The documented way to inject SPI faults on a bridge, ``board.at(t, lambda b: setattr(b.bus.ports[k], "faults",
    Faults(...)))``: corrupted parity, a flipped MISO bit, a slow response, MISO stuck low and a MOSI bit flip, on
    sensors 1, 2 and 3, each set and cleared mid-stream, give the host the same frames over the RTL (its fault ports
    changed while the harness streams) as over the software model.  Each fault shows (its sensor's samples flagged;
    sensor 2 stuck low reads as unplugged and is dropped) and the stream is clean before the first and after the
    last."""
    rtl = _same_frames_on_both_buses(0.3, _schedule_faults, 25)["rtl"].frames
    flagged = [{n for n, bad in zip(f.sensors, (f.status != 0).any(axis=0)) if bad} for f in rtl]
    assert set().union(*flagged) == {1, 2, 3}  # every sensor's fault reached the host
    assert not set().union(*flagged[:3], *flagged[-3:])
    assert rtl[-1].sensors == [1, 3]  # MISO stuck low: the firmware took sensor 2 for unplugged, on both buses


def _first_frame(driver, wanted, max_frames: int = 200):
    """The first frame the driver yields that is ``wanted``, within ``max_frames`` (None if none is)."""
    return next((f for f in driver.frames(max_frames=max_frames, timeout_s=10.0) if wanted(f)), None)


def test_an_spi_fault_set_on_the_rtl_bridge_reaches_the_host_and_a_bad_one_is_refused_by_name():
    """Over a bridge on the RTL (threads, pty, driver): a parity fault set with ``bench.at`` flags the host's
    samples, clearing it makes them clean again, and a value that is not a ``Faults`` stops the bench naming the
    sensor and what it takes (the RTL port used to refuse every fault; it now takes them and refuses only that)."""
    from bench.hosts.bridge import FirmwareBench
    from bench.hosts.driver import BridgeDriver

    def set_faults(faults):
        return lambda b: setattr(b.bus.ports[1], "faults", faults)

    board = VirtualBoard(default_sensors(1), spi="rtl")
    try:
        board.bus.ports[1].faults = Faults(miso_stuck=1)
        board.bus.ports[1].faults = Faults()
        with pytest.raises(ValueError, match=r"sensor 1: faults = .*must be an emulator\.spi\.model\.Faults"):
            board.bus.ports[1].faults = {"miso_stuck": 1}
    finally:
        board.bus.close()
    bench = FirmwareBench(n_sensors=1, spi="rtl").start()
    driver = BridgeDriver(bench.port)
    try:
        driver.start()
        next(driver.frames(max_frames=1))
        bench.at(bench.virtual_time, set_faults(Faults(bad_parity=True)))
        assert _first_frame(driver, lambda f: (f.status == 1).all()) is not None  # (frames already sent first)
        bench.at(bench.virtual_time, set_faults(Faults()))
        assert _first_frame(driver, lambda f: (f.status == 0).all()) is not None
        bench.at(bench.virtual_time, set_faults("bad_parity"))
        list(driver.frames(max_frames=5, timeout_s=2.0))
    finally:
        driver.close()
        with pytest.raises(RuntimeError, match=r"sensor 1: faults = .*bad_parity.*: must be an emulator\.spi"):
            bench.stop()
