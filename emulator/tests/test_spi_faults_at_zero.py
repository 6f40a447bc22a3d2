"""SPI faults whose value is 0 (MISO stuck low, bit 0 of MISO or MOSI inverted) act like any other value, on every
path: a sensor alone (the vectorized fast path), the bus's batch of words (the firmware's traffic), transfer by
transfer, and through the bridge firmware (docs/faults.md: every word reads 0x0000 / bit k is inverted).

``0 == False`` once made ``Faults.any`` treat them as "no fault", so the fast path ignored them."""

import numpy as np
import pytest

from emulator.sensor import NoiseSources, Sensor
from emulator.spi import protocol as proto
from emulator.spi.model import SELECT_CODE, Bus, Faults, SensorPort, Transfer
from emulator.spi.peripheral import TransferBatch

PDC = 1
COMMAND = int(proto.sample_command(PDC)) << 8  # sample PDC (first byte 0x83)
READ_DELAY_S = 60e-6  # the read comes after the 50 µs the result takes
START_S = np.array([0.1, 0.1 + READ_DELAY_S])
MOSI = np.array([COMMAND, 0x0000], np.uint16)

#: fault -> the word a host reads back, from the word a healthy sensor answers
AT_ZERO = {
    "miso_stuck=0": (Faults(miso_stuck=0), lambda good: 0x0000),
    "miso_flip_bit=0": (Faults(miso_flip_bit=0), lambda good: good ^ 0x8000),
    # the sensor receives 0x03 for 0x83: even parity, so it answers EE
    "mosi_flip_bit=0": (Faults(mosi_flip_bit=0), lambda good: proto.ERROR_WORDS["parity"]),
}


def _port(faults: Faults | None = None) -> SensorPort:
    return SensorPort(Sensor(channels_read=["PDC"], seed=4, noise=NoiseSources.none()), faults=faults)


def _good_word() -> int:
    return int(_port().exchange(TransferBatch(START_S, MOSI))[1])


@pytest.mark.parametrize("name", AT_ZERO)
def test_a_fault_at_zero_is_a_fault(name):
    assert AT_ZERO[name][0].any


@pytest.mark.parametrize("name", AT_ZERO)
def test_a_fault_at_zero_on_the_fast_path(name):
    """A sensor alone, a batch of plain words (what the host sampler sends): the fault shows in the read."""
    faults, expected = AT_ZERO[name]
    good = _good_word()
    assert proto.decode_response(np.array([good], np.uint16))[1][0], "the healthy sensor answers a good word"
    read = int(_port(faults).exchange(TransferBatch(START_S, MOSI))[1])
    assert read == expected(good), f"{name}: read {read:#06x}, healthy {good:#06x}"


@pytest.mark.parametrize("name", AT_ZERO)
def test_a_fault_at_zero_on_the_bus_batch_path(name):
    """The bus's batch of words with select codes (the firmware's traffic)."""
    faults, expected = AT_ZERO[name]
    good = _good_word()
    cs = np.full(2, SELECT_CODE[1])
    read = int(Bus({1: _port(faults)}).exchange_words(START_S, cs, MOSI, proto.HOST_DEFAULT_CLOCK_HZ)[1])
    assert read == expected(good), f"{name}: read {read:#06x}, healthy {good:#06x}"


@pytest.mark.parametrize("name", AT_ZERO)
def test_a_fault_at_zero_transfer_by_transfer(name):
    faults, expected = AT_ZERO[name]
    good = _good_word()
    bus = Bus({1: _port(faults)})
    read = [bus.transfer(Transfer(float(t), SELECT_CODE[1], int(m))) for t, m in zip(START_S, MOSI)][1]
    assert read == expected(good), f"{name}: read {read:#06x}, healthy {good:#06x}"


@pytest.mark.firmware
@pytest.mark.parametrize("name", AT_ZERO)
def test_the_firmware_never_passes_a_sample_through_a_fault_at_zero(name):
    """The bridge firmware with the fault set after it detected the sensor: every sample it streams is flagged
    (parity error or error word), none passes as good; without the fault every sample is good."""
    from bench.hosts.cosim import default_sensors
    from bench.tests.host_benches import run_firmware

    def with_fault(board):
        board.bus.ports[1].faults = AT_ZERO[name][0]

    clean = run_firmware(default_sensors(1, seed=3, noise=NoiseSources.none()), 0.1)
    assert clean.frames and all((f.status == 0).all() for f in clean.frames)
    run = run_firmware(default_sensors(1, seed=3, noise=NoiseSources.none()), 0.1, prepare=with_fault)
    assert run.frames, f"{name}: nothing streamed"
    flagged = np.concatenate([f.status.ravel() for f in run.frames])
    assert (flagged != 0).all(), f"{name}: {int((flagged == 0).sum())} of {flagged.size} samples passed as good"
