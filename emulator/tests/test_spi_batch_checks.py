"""A driver's mistakes in the transfers it hands a sensor's SPI side are refused with what, where and what is allowed:
a start time that is NaN or infinite (it compared false with every bound and read a word), an SCK that is NaN, a
batch going back in time (naming the transfer and both times, s), and one port object under two sensor numbers."""

from __future__ import annotations

import re

import numpy as np
import pytest

from emulator.sensor import Sensor
from emulator.spi import protocol as proto
from emulator.spi.model import Bus, SensorPort
from emulator.spi.peripheral import TransferBatch

pytestmark = pytest.mark.unit

PDC_COMMAND = int(proto.sample_command(1)) << 8


def port() -> SensorPort:
    return SensorPort(Sensor(channels_read=["PDC"], seed=1), 1)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_start_time_that_is_not_finite_is_refused_naming_the_transfer(bad):
    spi = port()
    with pytest.raises(ValueError, match=rf"transfer #1 of the call: start_s = {bad!r}: must be a finite time \(s\)"):
        spi.exchange(TransferBatch(np.array([0.1, bad, 0.2]), np.array([PDC_COMMAND, 0, 0], np.uint16)))


def test_a_nan_clock_is_refused_naming_the_transfer_and_the_range():
    spi = port()
    clock = np.array([4.4e6, np.nan])
    with pytest.raises(ValueError, match=r"transfer #1 of the call: SCK nan Hz: must be 500000–10000000 Hz"):
        spi.exchange(TransferBatch(np.array([0.1, 0.2]), np.array([PDC_COMMAND, 0], np.uint16), clock))


def test_going_back_in_time_names_the_transfer_and_both_times():
    spi = port()
    spi.exchange(TransferBatch(np.array([1.0, 1.0001]), np.array([PDC_COMMAND, 0], np.uint16)))
    with pytest.raises(ValueError, match=r"transfer #0 of the call starts at 0\.5 s, before the previous call's "
                                         r"last transfer ended \(1\.000103\d* s\)"):
        spi.exchange(TransferBatch(np.array([0.5]), np.array([PDC_COMMAND], np.uint16)))
    with pytest.raises(ValueError, match=r"transfer #2 of the call starts at 2\.000001 s, before transfer #1 "
                                         r"\(from 2 s\) ends at 2\.00000375 s"):
        spi.exchange(TransferBatch(np.array([1.5, 2.0, 2.000001]), np.array([PDC_COMMAND, 0, 0], np.uint16)))


def test_one_port_under_two_sensor_numbers_is_refused():
    p = port()
    with pytest.raises(ValueError, match=r"Bus: sensors 1 and 2 are the same SensorPort object"):
        Bus({1: p, 2: p})
    Bus({1: p, 2: port()})  # two ports: fine


@pytest.mark.parametrize("bad, words", [(1.5, "channel index 1.5: a whole number 0..63"),
                                        (True, "channel index True: a whole number 0..63"),
                                        ("PDC", "channel index 'PDC': a whole number 0..63"),
                                        ([0, 70], "channel index 70: must be 0..63"),
                                        (-1, "channel index -1: must be 0..63")])
def test_a_sampling_command_for_no_channel_is_refused_naming_the_index(bad, words):
    """1.5 and True had been taken as channel 1 (PDC); -1 raised numpy's OverflowError."""
    with pytest.raises(ValueError, match=re.escape(words)):
        proto.sample_command(bad)
    assert proto.sample_command(1) == 0x83 and list(proto.sample_command(np.array([0, 63]))) == [0x80, 0xFE]
    assert proto.sample_command([]).size == 0
