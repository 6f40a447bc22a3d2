"""The reference bridge firmware's documented behaviour, run in virtual time without a pty (deterministic, fast):
it flags parity faults in *either* byte of a response word, it samples with the vendor library's timing (odd
parity commands, the 50 µs rule, one 4.4 kHz slot each, 100 frames per second), and its CRC is CCITT-FALSE."""

import ctypes as C

import numpy as np
import pytest

from bench.hosts.cosim import build_firmware, default_sensors
from bench.tests.host_benches import run_firmware
from emulator.sensor import NoiseSources
from emulator.spi import protocol as proto
from emulator.spi.model import Faults

pytestmark = pytest.mark.firmware
WORD_S = 16.5 / 4.4e6


def quiet_sensor_run(seconds, faults=None, record=None):
    """Firmware + one quiet emulated sensor: optionally set SPI faults (once it has detected the sensor by its
    serial number), stream for ``seconds`` of virtual time, ask for the status; returns (the frames streamed in
    those seconds, status, parser stats)."""

    def prepare(board):
        if record is not None:
            exchange = board.bus.exchange_words

            def recording(start, cs, mosi, clock_hz, keep_cs=None):
                record.append((np.array(start), np.array(cs), np.array(mosi)))
                return exchange(start, cs, mosi, clock_hz, keep_cs)

            board.bus.exchange_words = recording
        if faults is not None:
            board.bus.ports[1].faults = faults

    run = run_firmware(default_sensors(1, seed=3, noise=NoiseSources.none()), seconds, prepare=prepare)
    return run.frames[:run.n_streamed], run.status, run.stats


@pytest.mark.parametrize("position", [7, 15])
def test_the_firmware_flags_parity_faults_in_either_byte(position):
    """MISO inverts bit 8 (the first byte's parity) or bit 0 (the second byte's) of every word: every sample is
    flagged with status 1 and counted as a parity error (within one second: re-detection reads the serial number,
    which the same fault corrupts)."""
    frames, status, stats = quiet_sensor_run(0.5, Faults(miso_flip_bit=position))
    assert len(frames) >= 40 and stats.crc_errors == 0
    assert all((f.status == 1).all() for f in frames)
    assert status.parity_errors >= sum(f.status.size for f in frames)


def test_the_firmware_samples_with_the_vendor_timing():
    """One sensor, default 44-slot frame: each slot is a sampling command (odd parity) and, 50 µs after its chip
    select rises, a read; slots 1/4.4 kHz apart; 100 frames per second; every word good, every frame's CRC good."""
    record = []
    frames, status, stats = quiet_sensor_run(1.0, record=record)
    assert stats.crc_errors == 0 and stats.dropped_frames == 0
    assert 99 <= len(frames) <= 101
    assert all((f.status == 0).all() for f in frames) and status.parity_errors == status.error_words == 0
    pac = np.concatenate([f.codes[f.channels == 0, 0] for f in frames]).astype(float)
    assert np.abs(pac - 2048).max() <= 1
    start, cs, mosi = record[-1]
    assert start.size == 88
    commands, reads = mosi[0::2] >> 8, mosi[1::2]
    assert proto.ODD_PARITY_OK[commands].all() and (reads == 0).all()
    assert np.array_equal(commands, proto.sample_command(frames[-1].channels))
    gap = start[1::2] - (start[0::2] + WORD_S)
    assert np.allclose(gap, 50e-6, atol=2e-9)
    assert np.allclose(np.diff(start[0::2]), 1 / 4400.0, atol=2e-9)


def test_the_firmware_crc_is_ccitt_false():
    """bt_bridge.h: CRC-16/CCITT-FALSE; its published check value for "123456789" is 0x29B1."""
    lib = C.CDLL(str(build_firmware()))
    lib.bt_crc16.restype = C.c_uint16
    lib.bt_crc16.argtypes = [C.c_char_p, C.c_size_t]
    assert lib.bt_crc16(b"123456789", 9) == 0x29B1
    assert lib.bt_crc16(b"", 0) == 0xFFFF
