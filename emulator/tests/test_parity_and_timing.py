"""The protocol's parity and timing rules at their boundaries (SENSOR.md §6), as the host sampler and the sensor
apply them: parity of *each* byte of a response word, error words reported as such, the 50 µs rule, the 5 µs
sampling delay, the conversion window that SPI clocking disturbs, the vendor library's timing, and the host
driver's CRC."""

import binascii

import numpy as np
import pytest

from bench.hosts.driver import crc16
from bench.running.sampler import STATUS_ERROR_WORD, STATUS_OK, STATUS_PARITY, Sampler
from emulator.sensor import NoiseSources, Sensor
from emulator.spi import protocol as proto
from emulator.spi.model import SELECT_CODE, Bus, Faults, SensorPort, Transfer
from emulator.spi.peripheral import SoftwarePeripheral, TransferBatch

pytestmark = pytest.mark.unit
WORD_S = 16.5 / 4.4e6  # one 16-bit transfer at the host's 4.4 MHz (3.75 µs)
E = proto.ERROR_WORDS


def quiet_sensor(channels=("PAC", "PDC"), seed=1):
    return Sensor(channels_read=list(channels), seed=seed, noise=NoiseSources.none())


# --- parity of each byte ----------------------------------------------------------------------------------------
def test_every_single_bit_error_in_a_response_word_is_flagged():
    """Both bytes of a response word carry odd parity (bit 8 for the first, bit 0 for the second): the host's
    decoder accepts every clean word and flags every word with one bit flipped, in either byte."""
    words = proto.RESPONSE_WORD.astype(np.int64)
    value, ok = proto.decode_response(words)
    assert ok.all() and np.array_equal(value, np.arange(4096))
    for bit in range(16):
        _, ok = proto.decode_response((words ^ (1 << bit)).astype(np.uint16))
        assert not ok.any(), f"a flipped bit {bit} went unnoticed"


@pytest.mark.parametrize("position,what", [(7, "first byte's parity bit (word bit 8)"),
                                           (15, "second byte's parity bit (word bit 0)"),
                                           (2, "a data bit of the first byte"),
                                           (11, "a data bit of the second byte")])
def test_the_host_sampler_flags_parity_faults_in_either_byte(position, what):
    """A sensor whose MISO inverts one bit position of every word: the host sampler flags every sample as a parity
    error (status 1), whichever byte the bit is in, and never passes it on as a good code."""
    clean = Sampler(SoftwarePeripheral(quiet_sensor()), ["PAC", "PDC"], 4400.0).read(200)
    assert (clean.status == STATUS_OK).all()
    port = SoftwarePeripheral(quiet_sensor())
    port.faults = Faults(miso_flip_bit=position)
    bad = Sampler(port, ["PAC", "PDC"], 4400.0).read(200)
    assert (bad.status == STATUS_PARITY).all(), what
    assert np.array_equal(bad.words ^ clean.words, np.full(200, 1 << (15 - position))), what


def test_the_host_sampler_marks_error_words_as_error_words():
    """Error words (first byte 0xA5) are reported as error words (status 2), not as parity errors or data: a
    sensor built for PAC only answers "EX" to PDC."""
    s = Sampler(SoftwarePeripheral(quiet_sensor(("PAC",))), ["PAC", "PDC"], 4400.0).read(100)
    assert (s.status[0::2] == STATUS_OK).all()
    assert (s.status[1::2] == STATUS_ERROR_WORD).all()
    assert (s.words[1::2] == E["channel_not_recognized"]).all()


# --- the 50 µs rule ---------------------------------------------------------------------------------------------
def _command_then_read(delay_s, vectorized):
    """A PDC sampling command whose chip select rises exactly on a timer tick (4 µs), then a read ``delay_s``
    after it; returns the word read."""
    start_cmd = 4e-6 - WORD_S
    start_read = 4e-6 + delay_s
    if vectorized:
        per = SoftwarePeripheral(quiet_sensor())
        return int(per.exchange(TransferBatch(np.array([start_cmd, start_read]),
                                              np.array([0x8300, 0x0000], np.uint16), 4.4e6))[1])
    b = Bus({1: SensorPort(quiet_sensor(), 1)})
    b.transfer(Transfer(start_cmd, SELECT_CODE[1], 0x8300, 16, 4.4e6))
    return b.transfer(Transfer(start_read, SELECT_CODE[1], 0, 16, 4.4e6))


@pytest.mark.parametrize("vectorized", [False, True])
def test_the_50_us_rule_has_its_boundary_at_50_us(vectorized):
    """The result is ready 50 µs (50 ticks of the sensor's 1 MHz timer) after the command's chip select rose:
    a read 49.5 µs after gets "E.", one at 50 µs or later gets the code."""
    assert _command_then_read(49.5e-6, vectorized) == E["insufficient_delay"]
    for delay in (50.0e-6, 50.5e-6, 80e-6):
        _, ok = proto.decode_response(_command_then_read(delay, vectorized))
        assert ok, f"read {delay * 1e6:.1f} µs after the command"


def test_the_host_sampler_reads_every_slot_cleanly_with_the_vendor_timing():
    """The vendor library's timing: command, 50 µs after its chip select rises, the read; one slot each at 4.4 kHz.
    Every word of a clean sensor then arrives with good parity and no error word."""
    seen = []

    class Recording:
        def __init__(self, port):
            self.port = port

        def exchange(self, batch):
            seen.append(batch)
            return self.port.exchange(batch)

    sampler = Sampler(Recording(SoftwarePeripheral(quiet_sensor())), ["PAC", "PDC"], 4400.0)
    s = sampler.read(4400)
    assert (s.status == STATUS_OK).all()
    assert np.abs(s.codes[0::2].astype(float) - 2048).max() <= 1  # PAC at mid-scale
    b = seen[0]
    cmd_start, read_start = b.start_s[0::2], b.start_s[1::2]
    assert np.allclose(np.diff(cmd_start), 1 / 4400.0, rtol=0, atol=1e-12)
    assert np.allclose(read_start - (cmd_start + WORD_S), 50e-6, rtol=0, atol=1e-12)
    assert np.allclose(s.times, cmd_start + WORD_S, rtol=0, atol=1e-12)  # sampled when the command ends


# --- the 5 µs sampling delay and the conversion window ---------------------------------------------------------------
@pytest.mark.parametrize("vectorized", [False, True])
def test_the_5_us_sampling_delay_has_its_boundary_at_5_us(vectorized):
    """A sampling command less than 5 ticks after the previous one finds the ADC busy ("E-"); 5 ticks is enough."""
    for ticks_apart, busy in ((4, True), (5, False), (6, False)):
        first_end, second_end = 4e-6, 4e-6 + ticks_apart * 1e-6
        starts = np.array([first_end - WORD_S, second_end - WORD_S, second_end + 100e-6])
        mosi = np.array([0x8000, 0x8300, 0x0000], np.uint16)
        if vectorized:
            word = int(SoftwarePeripheral(quiet_sensor()).exchange(TransferBatch(starts, mosi, 4.4e6))[2])
        else:
            b = Bus({1: SensorPort(quiet_sensor(), 1)})
            word = [b.transfer(Transfer(float(t), SELECT_CODE[1], int(m), 16, 4.4e6)) for t, m in zip(starts, mosi)][2]
        if busy:
            assert word == E["insufficient_sampling_delay"], ticks_apart
        else:
            assert proto.decode_response(word)[1], ticks_apart


def test_clocking_within_5_us_of_a_sampling_command_disturbs_the_conversion():
    """The conversion takes 5 µs after the command's chip select rises (``adc_conversion_s``): bus activity that
    starts within it couples into the sample, activity after it does not."""
    for gap_s, coupled in ((4.5e-6, 1), (5.5e-6, 0)):
        per = SoftwarePeripheral(quiet_sensor())
        starts = np.array([0.0, WORD_S + gap_s])
        per.exchange(TransferBatch(starts, np.array([0x8000, 0x0000], np.uint16), 4.4e6))
        per.resolve_conversion(1.0)
        assert per.coupled_conversions == coupled, gap_s
        b = Bus({1: SensorPort(quiet_sensor(), 1)})
        b.transfer(Transfer(0.0, SELECT_CODE[1], 0x8000, 16, 4.4e6))
        b.transfer(Transfer(WORD_S + gap_s, SELECT_CODE[1], 0, 16, 4.4e6))
        assert b.ports[1].coupled_conversions == coupled, gap_s


# --- the serial link's CRC -----------------------------------------------------------------------------------------
def test_the_driver_crc_is_ccitt_false():
    """bt_bridge.h: CRC-16/CCITT-FALSE (polynomial 0x1021, initial value 0xFFFF, no reflection, no final XOR):
    its published check value for "123456789" is 0x29B1; it equals the standard library's crc_hqx from 0xFFFF."""
    assert crc16(b"123456789") == 0x29B1
    rng = np.random.default_rng(0)
    for n in (0, 1, 7, 64, 300):
        data = rng.integers(0, 256, n).astype(np.uint8).tobytes()
        assert crc16(data) == binascii.crc_hqx(data, 0xFFFF)
