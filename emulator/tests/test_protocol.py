"""The SPI protocol facts (SENSOR.md §6) and the software peripheral's behaviour."""

import numpy as np
import pytest

from emulator.sensor import NoiseSources, Sensor
from emulator.spi import protocol as proto
from emulator.spi.peripheral import SoftwarePeripheral, TransferBatch

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("channel,byte", [(0, 0x80), (1, 0x83), (2, 0x85), (3, 0x86), (17, 0xA2), (18, 0xA4),
                                          (35, 0xC7)])
def test_sampling_command_bytes_match_the_published_examples(channel, byte):
    assert int(proto.sample_command(channel)) == byte



def test_a_channel_index_past_63_is_refused_not_wrapped_onto_PAC():
    """SENSOR.md §6: the channel is a 6-bit field (0..63); index 64 would wrap to channel 0 (PAC, 0x80), so it is
    refused with ValueError."""
    with pytest.raises(ValueError, match="0..63"):
        proto.sample_command(64)
    with pytest.raises(ValueError, match="0..63"):
        proto.sample_command([1, 64])
    assert int(proto.sample_command(63)) == 0xFE  # 1 111111 0: seven ones already, parity bit 0

def test_every_sampling_command_has_odd_parity():
    cmds = proto.sample_command(np.arange(64))
    assert np.all(proto.ODD_PARITY_OK[cmds])
    assert np.all(cmds & 0x80)


def test_response_words_round_trip_every_code_with_odd_parity_and_zero_bits():
    codes = np.arange(4096)
    words = proto.encode_response(codes)
    value, ok = proto.decode_response(words)
    assert np.array_equal(value, codes)
    assert ok.all()
    assert np.all((words & 0b110) == 0)  # bits 2-1 are zero
    assert np.array_equal(words >> 9, codes >> 5)  # bits 15-9 = data[11:5]
    assert np.array_equal((words >> 3) & 0x1F, codes & 0x1F)  # bits 7-3 = data[4:0]


def test_error_words_fail_the_hosts_parity_check():
    for word in proto.ERROR_WORDS.values():
        assert word >> 8 == 0xA5
        _, ok = proto.decode_response(word)
        assert not ok


def _peripheral(**kw):
    sensor = Sensor(channels_read=["PAC", "PDC"], seed=1, noise=NoiseSources.none(), **kw)
    return SoftwarePeripheral(sensor), sensor


def _exchange(per, schedule):
    """schedule: list of (start_s, mosi)."""
    t = np.array([s for s, _ in schedule], float)
    m = np.array([w for _, w in schedule], np.uint16)
    return per.exchange(TransferBatch(t, m, 4.4e6))


def test_sample_then_read_after_50us_returns_the_code_sampled_at_the_command():
    per, sensor = _peripheral()
    word_s = 16.5 / 4.4e6
    miso = _exchange(per, [(1e-3, 0x8300), (1e-3 + word_s + 50e-6, 0x0000)])
    value, ok = proto.decode_response(miso[1])
    assert ok
    resting = sensor.adc.convert(sensor.analog([1], [1e-3 + word_s]))[0]
    assert value == resting
    assert miso[0] == proto.ERROR_WORDS["nothing_to_resend"]  # MISO during a command: nothing pending yet


def test_host_may_clock_0x0001_while_reading():
    per, _ = _peripheral()
    word_s = 16.5 / 4.4e6
    a = _exchange(per, [(0.0, 0x8000), (word_s + 50e-6, 0x0001)])
    _, ok = proto.decode_response(a[1])
    assert ok


@pytest.mark.parametrize("first_byte,expected", [
    (0x81, "parity"),  # PAC command with the parity bit wrong
    (0x89, "channel_not_recognized"),  # channel 4 does not exist (0x89 = 1 000100 1, odd parity)
    (0x07, "unknown_command"),  # odd parity, not a sampling command
])
def test_bad_commands_prepare_the_published_error_words(first_byte, expected):
    per, _ = _peripheral()
    miso = _exchange(per, [(0.0, first_byte << 8), (1e-4, 0x0000)])
    assert miso[1] == proto.ERROR_WORDS[expected]


def test_reading_sooner_than_50us_answers_insufficient_delay():
    per, _ = _peripheral()
    word_s = 16.5 / 4.4e6
    miso = _exchange(per, [(0.0, 0x8000), (word_s + 40e-6, 0x0000)])
    assert miso[1] == proto.ERROR_WORDS["insufficient_delay"]


def test_read_with_no_command_before_answers_nothing_to_resend():
    per, _ = _peripheral()
    assert _exchange(per, [(0.0, 0x0000)])[0] == proto.ERROR_WORDS["nothing_to_resend"]


def test_pending_result_carries_across_batches():
    per, _ = _peripheral()
    word_s = 16.5 / 4.4e6
    _exchange(per, [(0.0, 0x8300)])
    miso = _exchange(per, [(word_s + 60e-6, 0x0000)])
    _, ok = proto.decode_response(miso[0])
    assert ok


def test_the_50us_rule_holds_after_many_hours():
    """Regression: at 2^14 s float64 time spacing exceeded the old 1 ps tolerance and exact-50 µs reads failed."""
    word_s = 16.5 / 4.4e6
    for t0 in (16384.0, 1e5, 3.6e6):
        per, _ = _peripheral(start_s=t0)
        k = np.arange(1000)
        t_cmd = t0 + k / 4400
        start = np.empty(2000)
        start[0::2], start[1::2] = t_cmd, t_cmd + word_s + 50e-6
        mosi = np.zeros(2000, np.uint16)
        mosi[0::2] = 0x8000
        miso = per.exchange(TransferBatch(start, mosi, 4.4e6))
        _, ok = proto.decode_response(miso[1::2])
        assert ok.all(), f"error words at t0 = {t0}"


def test_clock_outside_500kHz_to_10MHz_is_refused_with_the_transfer_named():
    per, _ = _peripheral()
    with pytest.raises(ValueError, match="transfer #0 of the call: SCK 20000000 Hz"):
        per.exchange(TransferBatch(np.array([0.0]), np.array([0x8000], np.uint16), 20e6))


def test_overlapping_or_backward_transfers_are_refused():
    per, _ = _peripheral()
    with pytest.raises(ValueError, match="time order"):
        per.exchange(TransferBatch(np.array([0.0, 1e-6]), np.array([0x8000, 0], np.uint16), 4.4e6))



def test_a_clock_just_below_500_kHz_is_refused_and_500_kHz_itself_accepted():
    """SENSOR.md §6: the clock range is 500 kHz–10 MHz, so 450 kHz is refused with the transfer named, and 500 kHz
    (the range's edge) is served."""
    per, _ = _peripheral()
    with pytest.raises(ValueError, match="transfer #0 of the call: SCK 450000 Hz"):
        per.exchange(TransferBatch(np.array([0.0]), np.array([0x8000], np.uint16), 450e3))
    per.exchange(TransferBatch(np.array([0.0]), np.array([0x8000], np.uint16), 500e3))


def test_transfers_overlapping_by_100_ns_are_refused_and_back_to_back_ones_accepted():
    """The timing tolerance is 1 ns (protocol.TIME_TOLERANCE_S: far below any SPI timing): a transfer starting 100 ns
    before the previous one releases chip select is refused, by a lone sensor and by the bus, while one starting
    exactly at the release is accepted."""
    from emulator.spi.model import Bus, SensorPort, Transfer

    end = 16.5 / 4.4e6
    per, _ = _peripheral()
    with pytest.raises(ValueError, match="time order"):
        per.exchange(TransferBatch(np.array([0.0, end - 100e-9]), np.array([0x8000, 0], np.uint16), 4.4e6))
    _peripheral()[0].exchange(TransferBatch(np.array([0.0, end]), np.array([0x8000, 0], np.uint16), 4.4e6))
    bus = Bus({1: SensorPort(Sensor(channels_read=["PAC"], seed=1, noise=NoiseSources.none()))})
    bus.transfer(Transfer(0.0, mosi=0x8000))
    with pytest.raises(ValueError, match="time order"):
        bus.transfer(Transfer(end - 100e-9))
    bus.transfer(Transfer(end))


def test_a_channel_the_sensor_was_not_built_for_answers_EX_and_is_counted():
    per, _ = _peripheral()  # built for PAC and PDC only
    miso = _exchange(per, [(0.0, 0xA200), (1e-4, 0x0000)])  # E1
    assert miso[1] == proto.ERROR_WORDS["channel_not_recognized"]
    assert per.unprovided_requests == 1


def test_after_random_garbage_a_well_formed_command_is_answered_correctly():
    rng = np.random.default_rng(0)
    per, sensor = _peripheral()
    t = np.cumsum(rng.uniform(5e-6, 80e-6, 5000))
    per.exchange(TransferBatch(t, rng.integers(0, 65536, t.size).astype(np.uint16), 4.4e6))
    t1 = t[-1] + 1e-3
    miso = _exchange(per, [(t1, 0x8300), (t1 + 16.5 / 4.4e6 + 50e-6, 0x0000)])
    value, ok = proto.decode_response(miso[1])
    resting = _peripheral()[1].sample([1], [1e-3])[0]  # a quiet sensor's PDC reads the same at any instant
    assert ok and value == resting


def _frame_traffic(n, gap_s):
    """n sampling commands for PAC, each followed after ``gap_s`` by a read."""
    word_s = 16.5 / 4.4e6
    t_cmd = np.arange(n) / 4400.0
    start = np.empty(2 * n)
    start[0::2], start[1::2] = t_cmd, t_cmd + word_s + gap_s
    mosi = np.zeros(2 * n, np.uint16)
    mosi[0::2] = 0x8000
    return start, mosi


def test_peripheral_output_does_not_depend_on_how_traffic_is_split_into_batches():
    start, mosi = _frame_traffic(400, 60e-6)
    whole = SoftwarePeripheral(Sensor(channels_read=["PAC"], seed=4)).exchange(TransferBatch(start, mosi))
    per = SoftwarePeripheral(Sensor(channels_read=["PAC"], seed=4))
    cuts = [0, 1, 2, 3, 50, 51, 333, 800]
    pieces = [per.exchange(TransferBatch(start[a:b], mosi[a:b])) for a, b in zip(cuts[:-1], cuts[1:])]
    assert np.array_equal(whole, np.concatenate(pieces))


def test_clocking_the_bus_during_a_conversion_couples_noise_into_the_sample():
    quiet_start, quiet_mosi = _frame_traffic(2000, 60e-6)
    quiet = SoftwarePeripheral(Sensor(channels_read=["PAC"], seed=4))
    q = proto.decode_response(quiet.exchange(TransferBatch(quiet_start, quiet_mosi))[1::2])[0]
    # an impatient host reads 1 µs after each command: the read is refused (E.) and it disturbed the conversion
    busy_start, busy_mosi = _frame_traffic(2000, 1e-6)
    busy = SoftwarePeripheral(Sensor(channels_read=["PAC"], seed=4))
    miso = busy.exchange(TransferBatch(busy_start, busy_mosi))
    assert quiet.coupled_conversions == 0
    assert busy.coupled_conversions == 2000
    assert np.all(miso[1::2] == proto.ERROR_WORDS["insufficient_delay"])
    codes = busy.sensor.adc.convert(np.full(500, 1.65), bus_active=np.ones(500, bool)).astype(float)
    assert codes.std() > 3 * q.astype(float).std()
