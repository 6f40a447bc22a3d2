"""The reference SPI state machine: every command, multi-sensor buses, faults, and the vectorized path."""

import signal

import numpy as np
import pytest

from emulator.channels import DEFAULT_FRAME_NAMES, channel_index
from emulator.sensor import NoiseSources, Sensor
from emulator.spi import protocol as proto
from emulator.spi.model import (SELECT_ALL, SELECT_CODE, SELECT_NONE, Bus, Faults, SensorPort, Transfer,
                                default_properties)
from emulator.spi.peripheral import TransferBatch

pytestmark = pytest.mark.unit
E = proto.ERROR_WORDS
ALL = list(DEFAULT_FRAME_NAMES)


def port(index=1, faults=None, seed=1, noise=NoiseSources.none()):
    return SensorPort(Sensor(channels_read=ALL, seed=seed + index, noise=noise), index, faults)


def bus(n=1, **kw):
    return Bus({i: port(i, **kw) for i in range(1, n + 1)})


def cmd(t, first, second=0x00, cs=SELECT_CODE[1], **kw):
    return Transfer(t, cs, (first << 8) | second, 16, **kw)


def read(t, cs=SELECT_CODE[1], nbits=16, **kw):
    return Transfer(t, cs, 0, nbits, **kw)


def value(word):
    v, ok = proto.decode_response(word)
    assert ok, hex(word)
    return int(v)


#: PDC's code at rest on a quiet sensor (no noise: every instant, every sensor reads it)
RESTING_PDC = int(Sensor(channels_read=ALL, noise=NoiseSources.none()).sample([1], [3.75e-6])[0])


def test_sample_then_read_returns_a_code_and_a_second_read_finds_nothing():
    b = bus()
    b.transfer(cmd(0.0, 0x83))
    assert value(b.transfer(read(100e-6))) == RESTING_PDC
    assert b.transfer(read(200e-6)) == E["nothing_to_resend"]


def test_a_read_too_soon_does_not_consume_the_result():
    b = bus()
    b.transfer(cmd(0.0, 0x80))
    assert b.transfer(read(20e-6)) == E["insufficient_delay"]
    assert 1900 < value(b.transfer(read(100e-6))) < 2200


def test_resend_repeats_the_last_word_read_and_both_spellings_work():
    b = bus()
    b.transfer(cmd(0.0, 0x83))
    first = b.transfer(read(100e-6))
    for t, resend in ((300e-6, 0x20), (500e-6, 0x50)):
        b.transfer(cmd(t, resend))
        assert b.transfer(read(t + 100e-6)) == first
    fresh = bus()
    fresh.transfer(cmd(0.0, 0x20))
    assert fresh.transfer(read(100e-6)) == E["nothing_to_resend"]


def read_property(b, prop, t0=0.0, cs=SELECT_CODE[1], max_bytes=60):
    """The vendor library's way: command, wait, then one byte per transfer with chip select held."""
    b.transfer(Transfer(t0, cs, (0x61 << 8) | prop, 16))
    out = bytearray()
    t = t0 + 100e-6
    while len(out) < max_bytes:
        byte = b.transfer(Transfer(t, cs, 0, 8, keep_cs=True))
        out.append(byte)
        t += 10e-6
        if byte in (0x00, 0xFF):
            break
    b.transfer(Transfer(t, SELECT_NONE, 0, 0))
    return bytes(out)


@pytest.mark.parametrize("prop", [0x10, 0x13, 0x15, 0x73])
def test_string_properties_stream_byte_by_byte_until_nul(prop):
    data, _ = default_properties(1)[prop]
    assert read_property(bus(), prop) == data + b"\x00"


def test_serial_number_starts_with_BT_and_cpu_speed_is_two_big_endian_bytes():
    b = bus()
    assert read_property(b, 0x15).startswith(b"BT")
    b.transfer(Transfer(1e-3, SELECT_CODE[1], 0x6161, 16))
    word = b.transfer(Transfer(1.2e-3, SELECT_CODE[1], 0, 16))
    assert word == 40000  # kHz


def test_unknown_property_answers_EX():
    b = bus()
    b.transfer(cmd(0.0, 0x61, 0x42))
    assert b.transfer(read(100e-6)) == E["channel_not_recognized"]


def nnnnvvvp(n, v, good_parity=True):
    byte = int(proto.with_odd_parity((n << 3) | v))
    return byte if good_parity else byte ^ 1


@pytest.mark.parametrize("second,expected", [
    (nnnnvvvp(2, 3), "ack"),
    (nnnnvvvp(2, 3, good_parity=False), "parity"),
    (nnnnvvvp(5, 1), "read_only"),
    (nnnnvvvp(1, 7), "write_error"),  # V = 7 is reserved
])
def test_write_command(second, expected):
    b = bus()
    b.transfer(cmd(0.0, 0x40, second))
    word = b.transfer(read(100e-6))
    if expected == "ack":
        assert value(word) == 2 * 8 + 3 and b.ports[1].registers[2] == 3
    else:
        assert word == E[expected]


def test_sampling_commands_closer_than_5_us_find_the_adc_busy():
    b = bus()
    b.transfer(cmd(0.0, 0x80))
    b.transfer(cmd(4e-6, 0x83))  # the first ends at 3.75 µs (tick 3); this one at 7.75 µs (tick 7): 4 ticks
    assert b.transfer(read(100e-6)) == E["insufficient_sampling_delay"]


def test_fewer_than_16_bits_of_a_command_are_ignored():
    b = bus()
    b.transfer(cmd(0.0, 0x83))
    b.transfer(Transfer(20e-6, SELECT_CODE[1], 0x86, 8))  # truncated command
    assert b.ports[1].incomplete == 1
    assert value(b.transfer(read(100e-6))) == RESTING_PDC  # the PDC sample is still there


def test_broadcast_sampling_then_per_sensor_reads_on_a_five_sensor_bus():
    b = bus(5)
    t = 0.0
    b.transfer(cmd(t, 0x83, cs=SELECT_ALL))
    t = 60e-6
    words = []
    for n in range(1, 6):  # the vendor library switches select codes back to back, chip select held
        words.append(b.transfer(Transfer(t, SELECT_CODE[n], 0, 16, keep_cs=True)))
        t += 16.5 / 4.4e6
    b.transfer(Transfer(t, SELECT_NONE, 0, 0))
    assert [value(w) for w in words] == [RESTING_PDC] * 5
    # each sensor sampled at the same instant (the broadcast's end)
    ends = {p.sensor.simulated_s > 0 for p in b.ports.values()}
    assert ends == {True}


@pytest.mark.parametrize("pull_up,expected", [(False, 0x0000), (True, 0xFFFF)])
def test_an_absent_sensor_reads_back_all_zeros_or_all_ones(pull_up, expected):
    b = Bus({1: port(1)}, pull_up=pull_up)
    b.transfer(cmd(0.0, 0x83, cs=SELECT_ALL))
    assert b.transfer(read(100e-6, cs=SELECT_CODE[3])) == expected


def test_cs_glitch_with_no_clock_edges_changes_nothing():
    b = bus()
    b.transfer(cmd(0.0, 0x83))
    b.transfer(Transfer(30e-6, SELECT_CODE[1], 0, 0))
    assert value(b.transfer(read(100e-6))) == RESTING_PDC


def test_clock_above_the_limit_makes_the_host_sample_each_bit_late():
    b = bus()
    b.transfer(cmd(0.0, 0x83))
    good = b.transfer(read(100e-6))
    b.transfer(cmd(300e-6, 0x20))  # resend the same word, now read at 20 MHz
    late = b.transfer(read(400e-6, clock_hz=20e6))
    assert late == good >> 1 and b.out_of_spec_transfers == 1
    assert not proto.decode_response(late)[1] or late != good


@pytest.mark.parametrize("clock_hz, shift", [(10.5e6, 0), (11.0e6, 0), (12.5e6, 1), (1 / 28e-9, 2)])
def test_a_clock_past_10_MHz_is_counted_and_shifts_the_word_once_past_11_1_MHz(clock_hz, shift):
    """docs/faults.md: MISO is valid 45 ns after it changes, so above ~11.1 MHz (half period < 45 ns) each bit is
    sampled one bit late, by one bit down to 15 ns half periods and two below; every transfer above the 10 MHz limit
    is counted out of spec, shifted or not."""
    from emulator.spi.model import late_bits

    assert late_bits(1 / (2 * clock_hz)) == shift
    b = bus()
    b.transfer(cmd(0.0, 0x83))
    good = b.transfer(read(100e-6))
    b.transfer(cmd(300e-6, 0x20))  # resend the same word, read at clock_hz
    word = b.transfer(read(400e-6, clock_hz=clock_hz))
    assert b.out_of_spec_transfers == 1
    assert (word << shift) & 0xFFFF == (good >> shift << shift) & 0xFFFF and (shift == 0) == (word == good)


@pytest.mark.parametrize("faults,check", [
    (Faults(miso_flip_bit=3), lambda good, bad: bad == good ^ (1 << 12)),
    (Faults(miso_stuck=1), lambda good, bad: bad == 0xFFFF),
    (Faults(miso_stuck=0), lambda good, bad: bad == 0x0000),
    (Faults(bad_parity=True), lambda good, bad: bad == good ^ 0x0100 and not proto.decode_response(bad)[1]),
])
def test_miso_faults_change_what_the_host_receives(faults, check):
    ref, bad = bus(), bus(faults=faults)
    for b in (ref, bad):
        b.transfer(cmd(0.0, 0x83))
    assert check(ref.transfer(read(100e-6)), bad.transfer(read(100e-6)))


def test_mosi_bit_flip_turns_a_command_into_a_parity_error():
    b = bus(faults=Faults(mosi_flip_bit=4))
    b.transfer(cmd(0.0, 0x83))
    assert b.transfer(read(100e-6)) == E["parity"]


def test_slow_response_refuses_reads_at_50_us_and_answers_at_100():
    b = bus(faults=Faults(slow_response=True))
    b.transfer(cmd(0.0, 0x83))
    assert b.transfer(read(60e-6)) == E["insufficient_delay"]
    assert proto.decode_response(b.transfer(read(120e-6)))[1]


def test_reset_mid_stream_forgets_the_pending_result():
    b = bus()
    b.transfer(cmd(0.0, 0x83))
    b.ports[1].reset()
    assert b.transfer(read(100e-6)) == E["nothing_to_resend"]


def test_reset_forgets_the_resend_buffer_too():
    """docs/faults.md: after a reset "the pending result and the resend buffer are gone" — a resend command after a
    served result gets it again, unless the sensor was reset in between."""
    from emulator.spi.model import CMD_RESEND

    for reset in (False, True):
        b = bus()
        b.transfer(cmd(0.0, 0x83))
        served = b.transfer(read(100e-6))
        assert proto.decode_response(served)[1]
        if reset:
            b.ports[1].reset()
        b.transfer(cmd(200e-6, CMD_RESEND))
        again = b.transfer(read(300e-6))
        assert again == (E["nothing_to_resend"] if reset else served)


def _random_word_traffic(rng, n):
    """Plain traffic: sampling commands (good and bad), odd first bytes, reads, at varied spacings and clocks."""
    firsts = np.concatenate([proto.sample_command(np.arange(64)), rng.integers(1, 256, 40)])
    firsts = firsts[~np.isin(firsts, [0x20, 0x40, 0x50, 0x61])]
    words = np.where(rng.random(n) < 0.5, 0, (rng.choice(firsts, n).astype(np.uint16) << 8) | rng.integers(0, 256, n))
    clocks = rng.choice([0.5e6, 1e6, 4.4e6, 10e6], n)
    gaps = rng.choice([0.2e-6, 2e-6, 30e-6, 49.5e-6, 50e-6, 60e-6, 300e-6], n)
    start = np.concatenate([[0.0], np.cumsum(16.5 / clocks + gaps)[:-1]])  # each waits for the previous one
    return start, words.astype(np.uint16), clocks


@pytest.mark.parametrize("seed", range(5))
def test_vectorized_path_matches_the_transfer_level_path(seed):
    rng = np.random.default_rng(seed)
    start, words, clocks = _random_word_traffic(rng, 3000)
    fast = port(seed=seed, noise=NoiseSources())
    slow = port(seed=seed, noise=NoiseSources())
    cuts = np.sort(rng.choice(np.arange(1, 3000), 6, replace=False))
    a = np.concatenate([fast.exchange(TransferBatch(start[i:j], words[i:j], clocks[i:j]))
                        for i, j in zip(np.r_[0, cuts], np.r_[cuts, 3000])])
    b_ = Bus({1: slow})
    b = np.array([b_.transfer(Transfer(float(s), SELECT_CODE[1], int(w), 16, float(c)))
                  for s, w, c in zip(start, words, clocks)])
    assert np.array_equal(a, b)
    for attr in ("last_sent", "last_sampling_tick", "coupled_conversions", "unprovided_requests"):
        assert getattr(fast, attr) == getattr(slow, attr), attr


def test_garbage_never_wedges_the_bus_and_a_good_command_then_works():
    rng = np.random.default_rng(3)
    b = bus(3)
    t = 0.0
    for _ in range(3000):
        nbits = int(rng.integers(0, 40))
        t += float(rng.uniform(0.1e-6, 80e-6))
        tr = Transfer(t, int(rng.integers(0, 8)), int(rng.integers(0, 2**40)) & ((1 << nbits) - 1), nbits,
                      float(rng.choice([0.5e6, 4.4e6, 10e6, 20e6])), keep_cs=bool(rng.random() < 0.2))
        b.transfer(tr)
        t = tr.end_s
    t += 1e-3
    b.transfer(Transfer(t, SELECT_NONE, 0, 0))
    for n in (1, 2, 3):
        b.transfer(cmd(t + n * 1e-3, 0x83, cs=SELECT_CODE[n]))
        assert value(b.transfer(read(t + n * 1e-3 + 100e-6, cs=SELECT_CODE[n]))) == RESTING_PDC


@pytest.mark.parametrize("seed", range(3))
def test_bus_word_path_matches_transfer_level_for_multi_sensor_frames(seed):
    """Broadcast sampling then per-sensor reads with the select code switching, as bridge firmware does."""
    rng = np.random.default_rng(seed)
    present = sorted(rng.choice([1, 2, 3, 4, 5], int(rng.integers(1, 6)), replace=False).tolist())
    start, cs, mosi, keep = [], [], [], []
    t = 1e-3
    for k in range(600):
        ch = int(rng.choice([0, 1, 17, 35, 3]))
        start.append(t), cs.append(SELECT_ALL), mosi.append(int(proto.sample_command(ch)) << 8), keep.append(False)
        t += 16.5 / 4.4e6 + float(rng.choice([50e-6, 60e-6, 30e-6]))
        for n in range(1, 6):
            start.append(t), cs.append(SELECT_CODE[n]), mosi.append(0), keep.append(n < 5)
            t += 16.5 / 4.4e6
        t += float(rng.choice([10e-6, 100e-6]))
    start, cs, mosi, keep = map(np.array, (start, cs, mosi, keep))
    fast = Bus({n: port(n, noise=NoiseSources()) for n in present})
    slow = Bus({n: port(n, noise=NoiseSources()) for n in present})
    cut = int(rng.integers(1, start.size - 1))
    a = np.concatenate([fast.exchange_words(start[:cut], cs[:cut], mosi[:cut], 4.4e6, keep[:cut]),
                        fast.exchange_words(start[cut:], cs[cut:], mosi[cut:], 4.4e6, keep[cut:])])
    b = np.array([slow.transfer(Transfer(float(s), int(c), int(m), 16, 4.4e6, bool(k)))
                  for s, c, m, k in zip(start, cs, mosi, keep)])
    assert np.array_equal(a, b)


def test_the_samplers_transfers_are_its_slots_command_then_read():
    """(consistency) :meth:`Sampler.read` (one compiled pass over the slots) sends, per slot of :meth:`Sampler.slots`,
    the slot's sampling command at its start and a read of zeros ``word_s`` + ``sample_delay_s`` after it, and
    reports the instant sampled and the channel of each slot, to the bit, from any slot on (here a 44-slot frame
    read in three uneven parts)."""
    from bench.running.sampler import Sampler
    from emulator.spi import protocol as proto

    class Recorder:
        variant = None

        def __init__(self):
            self.batches = []

        def exchange(self, batch):
            self.batches.append(batch)
            return np.zeros(batch.start_s.size, dtype=np.uint16)

    rec = Recorder()
    sampler = Sampler(rec)
    parts = [samples for n in (7, 100, 61) for samples in [sampler.read(n)]]
    k = np.arange(168)
    t_cmd, t_sampled, channel = sampler.slots(k)
    start = np.concatenate([b.start_s for b in rec.batches])
    mosi = np.concatenate([b.mosi for b in rec.batches])
    np.testing.assert_array_equal(start[0::2], t_cmd)
    np.testing.assert_array_equal(start[1::2], t_sampled + sampler.sample_delay_s)
    np.testing.assert_array_equal(mosi[0::2], proto.sample_command(channel).astype(np.uint16) << 8)
    assert not mosi[1::2].any() and mosi.dtype == np.uint16
    np.testing.assert_array_equal(np.concatenate([p.times for p in parts]), t_sampled)
    np.testing.assert_array_equal(np.concatenate([p.channels for p in parts]), channel)
    assert parts[0].channels.dtype == channel.dtype and sampler.next_slot == 168


def test_the_samplers_chunks_read_exactly_the_slots_asked_and_its_slot_must_hold_two_words_and_the_delay():
    """``chunks(n, c)`` reads n slots in reads of at most c (the last one shorter), refusing c < 1; a slot too short
    for the command, the 50 µs wait and the read (at 150 kHz a word takes 110 µs: 270 µs of the 227 µs slot at
    4.4 kHz, though one word and the wait would fit) is refused when the sampler is made."""
    from bench.running.sampler import Sampler

    class Zeros:
        variant = None

        def exchange(self, batch):
            return np.zeros(batch.start_s.size, dtype=np.uint16)

    sampler = Sampler(Zeros())
    assert [s.codes.size for s in sampler.chunks(10, 4)] == [4, 4, 2] and sampler.next_slot == 10
    with pytest.raises(ValueError, match="chunk_slots = 0: must be at least 1"):
        next(sampler.chunks(10, 0))
    with pytest.raises(ValueError, match="cannot hold command"):
        Sampler(Zeros(), clock_hz=150e3)
    assert Sampler(Zeros(), clock_hz=300e3).word_s < 0.5 * (1 / 4400 - 50e-6)  # two words fit at 300 kHz


def test_the_sampler_reads_the_frame_of_the_sensor_behind_an_rtl_peripheral():
    """A peripheral that has no variant of its own but holds a sensor (the RTL harness's peripheral) gets its
    sensor's default frame: 54 slots behind an SP, 44 behind a BioTac; a peripheral with neither gets the default
    BioTac's (:func:`variant_of`)."""
    from bench.running.sampler import Sampler, variant_of

    class Holder:
        def __init__(self, variant):
            self.sensor = type("FakeSensor", (), {"variant": variant})()

    assert variant_of(Holder("biotac-sp")) == "biotac-sp" and Sampler(Holder("biotac-sp")).sequence.size == 54
    assert variant_of(Holder("biotac")) == "biotac" and Sampler(Holder("biotac")).sequence.size == 44
    assert variant_of(object()) == variant_of(None) == "biotac"


def test_the_sampler_decodes_each_reads_word_as_the_protocol_does():
    """(consistency) :meth:`Sampler.read` decodes each slot's read word (a table look-up, compiled) as
    :func:`~emulator.spi.protocol.decode_response` does — the code, and status ok, parity error, or error word —
    for every 16-bit word, the commands' words ignored."""
    from bench.running.sampler import STATUS_ERROR_WORD, STATUS_OK, STATUS_PARITY, Sampler

    words = np.arange(1 << 16, dtype=np.uint16)

    class Words:
        variant = None

        def exchange(self, batch):
            miso = np.full(batch.start_s.size, 0xFFFF, dtype=np.uint16)
            miso[1::2] = words
            return miso

    got = Sampler(Words()).read(words.size)
    value, parity_ok = proto.decode_response(words)
    status = np.where(proto.is_error_word(words), STATUS_ERROR_WORD, np.where(parity_ok, STATUS_OK, STATUS_PARITY))
    np.testing.assert_array_equal(got.words, words)
    np.testing.assert_array_equal(got.codes, value)
    np.testing.assert_array_equal(got.status, status)
    assert got.codes.dtype == np.uint16 and got.status.dtype == np.uint8


@pytest.mark.parametrize("reply, needle", [
    (lambda n: np.zeros(n // 2, dtype=np.uint16), "words for"),             # half the words
    (lambda n: np.full(n, 70000, dtype=np.int64), "outside 0..0xFFFF"),     # not 16-bit words
    (lambda n: np.full(n, -1, dtype=np.int64), "outside 0..0xFFFF"),
    (lambda n: np.zeros(n, dtype=float), "outside 0..0xFFFF"),              # not integers
])
def test_the_sampler_refuses_a_malformed_reply_naming_the_peripheral(reply, needle):
    """A peripheral whose exchange() returns the wrong number of words, or words that are not 16-bit integers, is
    refused with its name — never decoded past the reply's end or folded into a status code; 16-bit words in a
    wider integer type are accepted as they are."""
    from bench.running.sampler import Sampler

    class Odd:
        variant = None

        def __init__(self, make):
            self.make = make

        def exchange(self, batch):
            return self.make(batch.start_s.size)

    with pytest.raises(ValueError, match=f"Odd.exchange returned .*{needle}"):
        Sampler(Odd(reply)).read(8)
    wide = Sampler(Odd(lambda n: np.full(n, 0x1234, dtype=np.int64))).read(8)
    assert wide.words.dtype == np.uint16 and np.all(wide.words == 0x1234)


def _fast_and_slow(batches, clock=10e6, seed=2):
    """The answers of one sensor to word ``batches`` (lists of (start s, word)) through the vectorised path (one
    ``exchange`` per batch) and through the transfer-level Bus, and the two ports."""
    fast, slow = port(seed=seed, noise=NoiseSources()), port(seed=seed, noise=NoiseSources())
    a = np.concatenate([fast.exchange(TransferBatch(np.array([s for s, _ in b]), np.array([w for _, w in b], np.uint16),
                                                    np.full(len(b), clock))) for b in batches])
    slow_bus = Bus({1: slow})
    b = np.array([slow_bus.transfer(Transfer(s, SELECT_CODE[1], w, 16, clock)) for batch in batches for s, w in batch])
    return a, b, fast, slow


@pytest.mark.parametrize("name, batches", [
    # a sampling command answered busy restarts the conversion window: the third, 6 µs after the first, is busy too
    ("busy restarts the window", [[(0.0, 0x8300), (3e-6, 0x8300), (6e-6, 0x8300), (200e-6, 0), (400e-6, 0)]]),
    # a read in a batch of its own consumes the result the previous batch's command made: the next read has none
    ("a read consumes across batches", [[(0.0, 0x8300)], [(100e-6, 0)], [(300e-6, 0)]]),
    # 0x50 resends the last answer (the manual resend), on the vectorised path too
    ("manual resend", [[(0.0, 0x8300), (100e-6, 0), (300e-6, 0x5000), (400e-6, 0)]]),
])
def test_the_vectorised_path_answers_the_protocols_corners_as_the_transfer_level_path(name, batches):
    """Consistency on the corners random traffic rarely meets (a mutation hunt found each unguarded on the fast
    path): the answers word for word, and the ports' state after."""
    a, b, fast, slow = _fast_and_slow(batches)
    assert np.array_equal(a, b), (name, [hex(x) for x in a], [hex(x) for x in b])
    assert (fast.last_sent, fast.last_sampling_tick) == (slow.last_sent, slow.last_sampling_tick)


def test_a_reset_clears_the_written_registers_as_the_rtls_reset_does():
    """Consistency with biotac_spi.v, whose reset clears its four registers: a register written, then the sensor
    reset (a brown-out), holds 0 again — and a write after the reset takes."""
    b = bus()
    b.transfer(cmd(0.0, 0x40, nnnnvvvp(2, 3)))
    b.transfer(read(100e-6))
    assert b.ports[1].registers == [0, 0, 3, 0]
    b.ports[1].reset()
    assert b.ports[1].registers == [0, 0, 0, 0]
    b.transfer(cmd(1e-3, 0x40, nnnnvvvp(1, 5)))
    assert value(b.transfer(read(1.1e-3))) == 1 * 8 + 5 and b.ports[1].registers == [0, 5, 0, 0]


# --- corners of the word path and the bus a second mutation hunt found unguarded --------------------------------
WORD_S = 16.5 / 4.4e6  # one 16-bit transfer at the default clock, chip select fall to rise


def test_clocking_for_another_sensor_during_a_conversion_couples_into_it_on_both_paths():
    """Model docstring (emulator/spi/model.py): a conversion is disturbed if *the bus* clocks again within
    ``adc_conversion_s`` (5 µs) — SCK and MOSI are shared, so a transfer addressed to sensor 2 1 µs after sensor 1's
    sampling command disturbs sensor 1's conversion; sensor 2's own (nothing clocks within 5 µs after it) is
    clean.  Exact counts, on the word path (``Bus.exchange_words``) as on the transfer-level path, and the same
    words."""
    t0 = 1e-3
    start = np.array([t0, t0 + WORD_S + 1e-6, t0 + 200e-6, t0 + 300e-6])
    cs = np.array([SELECT_CODE[1], SELECT_CODE[2], SELECT_CODE[1], SELECT_CODE[2]])
    mosi = np.array([0x8300, 0x8300, 0, 0], np.uint16)
    fast, slow = bus(2), bus(2)
    words = fast.exchange_words(start, cs, mosi, 4.4e6)
    ref = [slow.transfer(Transfer(float(s), int(c), int(m), 16)) for s, c, m in zip(start, cs, mosi)]
    for b in (fast, slow):
        assert (b.ports[1].coupled_conversions, b.ports[2].coupled_conversions) == (1, 0)
    assert words.tolist() == ref


def test_an_absent_sensor_reads_back_the_pull_up_on_the_word_path_too():
    """Bus docstring: with nobody driving MISO the line idles at the pull level, so a read addressed to an absent
    sensor returns 0xFFFF with a pull-up — through ``exchange_words`` as through ``transfer``."""
    b = Bus({1: port(1)}, pull_up=True)
    words = b.exchange_words(np.array([0.0, 100e-6]), np.array([SELECT_ALL, SELECT_CODE[3]]),
                             np.array([0x8300, 0], np.uint16), 4.4e6)
    assert words[1] == 0xFFFF


def test_chip_select_held_on_one_sensor_makes_one_window_on_the_word_path_too():
    """Model docstring: ``keep_cs`` continues the same window, and MOSI acts when chip select rises.  A sampling
    command with chip select held into a read is one 32-bit window: MISO is what was chosen at its fall (``E_``,
    nothing prepared) then zeros; the second half is not a read of its own (no ``E.``).  Exact words, the same
    through ``exchange_words`` and ``transfer``, and when ``transfer`` opens the window and ``exchange_words``
    continues it."""
    start = np.array([0.0, WORD_S, 200e-6])
    cs = np.full(3, SELECT_CODE[1])
    mosi = np.array([0x8300, 0, 0], np.uint16)
    keep = np.array([True, False, False])
    fast, slow = bus(), bus()
    words = fast.exchange_words(start, cs, mosi, 4.4e6, keep)
    ref = [slow.transfer(Transfer(float(s), int(c), int(m), 16, keep_cs=bool(k)))
           for s, c, m, k in zip(start, cs, mosi, keep)]
    assert words.tolist() == ref
    assert words[0] == E["nothing_to_resend"] and words[1] == 0x0000 and value(words[2]) == RESTING_PDC
    # the same window opened by ``transfer`` (chip select held) and continued by ``exchange_words``
    b = bus()
    b.transfer(Transfer(0.0, SELECT_CODE[1], 0x8300, 16, keep_cs=True))
    assert b.exchange_words(start[1:], cs[1:], mosi[1:], 4.4e6).tolist() == words[1:].tolist()


def test_a_window_held_open_by_the_last_word_of_a_call_goes_on_into_the_next_call_on_the_word_path():
    """Chip select held by a call's last word (``keep_cs``) stays asserted into the next call, as ``transfer``
    and the RTL bus hold it: the sampling command and the next call's read are one 32-bit window (the read's half
    is zeros, not the converted code).  The word path had taken such a call as plain word traffic and released
    chip select at its end, so the next call read a conversion."""
    start = np.array([0.0, 200e-6, 400e-6])
    cs = np.full(3, SELECT_CODE[1])
    mosi = np.array([0x8300, 0, 0], np.uint16)
    keep = np.array([True, False, False])
    fast, slow = bus(), bus()
    words = [int(w) for w in fast.exchange_words(start[:1], cs[:1], mosi[:1], 4.4e6, keep[:1])]
    words += [int(w) for w in fast.exchange_words(start[1:], cs[1:], mosi[1:], 4.4e6, keep[1:])]
    ref = [slow.transfer(Transfer(float(s), int(c), int(m), 16, keep_cs=bool(k)))
           for s, c, m, k in zip(start, cs, mosi, keep)]
    assert words == ref
    assert words[:2] == [E["nothing_to_resend"], 0x0000] and value(words[2]) == RESTING_PDC  # (converted as CS rose)


def test_a_window_held_until_the_select_code_moves_on_ends_when_it_moves_on_on_the_word_path():
    """A sampling command with chip select held, the select code moving to nobody 100 µs later: the sensor sees
    chip select rise as the code moves on (transfer-level path, RTL), so a read 20 µs after that is too soon ("E.");
    the word path had ended the window with the command's own transfer and served the code."""
    start = np.array([0.0, 100e-6, 120e-6])
    cs = np.array([SELECT_CODE[1], SELECT_NONE, SELECT_CODE[1]])
    mosi = np.array([0x8300, 0, 0], np.uint16)
    keep = np.array([True, False, False])
    words = bus().exchange_words(start, cs, mosi, 4.4e6, keep).tolist()
    slow = bus()
    assert words == [slow.transfer(Transfer(float(s), int(c), int(m), 16, keep_cs=bool(k)))
                     for s, c, m, k in zip(start, cs, mosi, keep)]
    assert words == [E["nothing_to_resend"], 0x0000, E["insufficient_delay"]]


@pytest.mark.parametrize("seed", range(4))
def test_word_traffic_holding_chip_select_anywhere_gives_the_transfer_level_words(seed):
    """Commands and reads to two sensors, chip select held on a random fifth of them (into a transfer to another
    sensor, to nobody, or past the call's end), gaps from 0 to 100 µs (so a conversion meets the bus or not), cut
    into calls at random: word for word, and the conversions coupled, as transfer by transfer."""
    rng = np.random.default_rng(seed)
    n = 400
    cs = rng.choice([SELECT_CODE[1], SELECT_CODE[3], SELECT_ALL, SELECT_NONE], n)
    mosi = np.where(rng.random(n) < 0.5, 0, [int(proto.sample_command(c)) << 8 for c in rng.choice([0, 1, 17], n)])
    keep = rng.random(n) < 0.2
    keep[:-1] &= ~(((cs[:-1] == cs[1:]) & (cs[:-1] != SELECT_NONE)) | (cs[:-1] == SELECT_ALL) | (cs[1:] == SELECT_ALL))
    start = 1e-3 + np.cumsum(16.5 / 4.4e6 + rng.choice([0.0, 2e-6, 20e-6, 100e-6], n))
    cuts = [0, *sorted(rng.choice(np.arange(1, n), 8, replace=False).tolist()), n]
    fast = Bus({k: port(k, noise=NoiseSources()) for k in (1, 3)})
    slow = Bus({k: port(k, noise=NoiseSources()) for k in (1, 3)})
    a = np.concatenate([fast.exchange_words(start[i:j], cs[i:j], mosi[i:j].astype(np.uint16), 4.4e6, keep[i:j])
                        for i, j in zip(cuts[:-1], cuts[1:])])
    b = np.array([slow.transfer(Transfer(float(s), int(c), int(m), 16, 4.4e6, bool(k)))
                  for s, c, m, k in zip(start, cs, mosi, keep)])
    assert np.array_equal(a, b), np.flatnonzero(a != b)[:5]
    assert [p.coupled_conversions for p in fast.ports.values()] == [p.coupled_conversions for p in slow.ports.values()]


def test_a_clock_past_10_MHz_on_the_word_path_is_counted_and_sampled_late():
    """docs/faults.md (as the transfer-level test above): every transfer above 10 MHz is counted out of spec and at
    20 MHz (25 ns half period < 45 ns) the host samples each bit one bit late: the word read is the good one shifted
    right by one.  ``exchange_words`` must not take its in-spec shortcut for such traffic."""
    b = bus()
    words = b.exchange_words(np.array([0.0, 100e-6]), np.full(2, SELECT_CODE[1]),
                             np.array([0x8300, 0], np.uint16), 20e6)
    assert b.out_of_spec_transfers == 2
    assert words[1] == int(proto.encode_response(RESTING_PDC)) >> 1


def test_word_traffic_must_stay_in_time_order_across_batches_and_within_one():
    """Model docstring: transfers are in time order and never overlap; a host that sends a batch starting before
    the previous batch ended, or two transfers of one batch overlapping, is refused (ValueError) — on the bus's word
    path and on a lone sensor's ``exchange``, not silently evaluated."""
    b = bus()
    b.exchange_words(np.array([0.0, 100e-6]), np.full(2, SELECT_CODE[1]), np.array([0x8300, 0], np.uint16), 4.4e6)
    with pytest.raises(ValueError):  # starts 50 µs before the previous batch's last transfer ended
        b.exchange_words(np.array([50e-6]), np.array([SELECT_CODE[1]]), np.array([0x8300], np.uint16), 4.4e6)
    with pytest.raises(ValueError):  # the second starts 1 µs into the first (3.75 µs long)
        bus().exchange_words(np.array([0.0, 1e-6]), np.full(2, SELECT_CODE[1]), np.array([0x8300, 0], np.uint16),
                             4.4e6)
    p = port()
    p.exchange(TransferBatch(np.array([0.0, 100e-6]), np.array([0x8300, 0], np.uint16), 4.4e6))
    with pytest.raises(ValueError, match="time order"):
        p.exchange(TransferBatch(np.array([50e-6, 200e-6]), np.array([0x8300, 0], np.uint16), 4.4e6))


def test_a_word_read_after_a_property_command_gets_the_propertys_first_two_bytes():
    """Model docstring: a property is its bytes followed by 0xFF, and what MISO carries is chosen at chip-select
    fall for every transfer; a 16-bit read 100 µs after the serial-number command (0x61 0x15) therefore carries its
    first two characters, "BT" = 0x4254 — also when the command and the read come in separate ``exchange``
    batches (the read must not take the word-only fast path)."""
    fast, slow = port(), port()
    got = [fast.exchange(TransferBatch(np.array([s]), np.array([w], np.uint16), 4.4e6))[0]
           for s, w in ((0.0, 0x6115), (100e-6, 0))]
    slow_bus = Bus({1: slow})
    ref = [slow_bus.transfer(Transfer(s, SELECT_CODE[1], w, 16)) for s, w in ((0.0, 0x6115), (100e-6, 0))]
    assert got[1] == 0x4254 and got == ref


def test_a_sensor_numbered_3_answers_traffic_that_takes_the_transfer_level_path():
    """A lone sensor's ``exchange`` sends anything but plain words (here a resend, 0x20) transfer by transfer on a bus
    of its own, addressed with *its* select code (sensor 3: 0b100, SENSOR.md §6): the data word read, then the same
    word resent (P: resend repeats the last word read)."""
    p = port(3)
    assert p.index == 3
    start = np.array([0.0, 100e-6, 300e-6, 400e-6])
    words = p.exchange(TransferBatch(start, np.array([0x8300, 0, 0x2000, 0], np.uint16), 4.4e6))
    assert value(words[1]) == RESTING_PDC and words[3] == words[1]


def test_slow_response_still_refuses_a_read_just_before_100_us():
    """docs/faults.md: with ``slow_response`` results take 100 µs instead of 50: the command ends at 3.75 µs (tick 3),
    so a read at 99 µs (tick 99, 96 ticks later) is still refused with ``E.``; at 104 µs (101 ticks) it is answered."""
    b = bus(faults=Faults(slow_response=True))
    b.transfer(cmd(0.0, 0x83))
    assert b.transfer(read(99e-6)) == E["insufficient_delay"]
    assert value(b.transfer(read(104e-6))) == RESTING_PDC


def test_a_channel_the_sensor_was_not_built_for_is_counted_on_the_transfer_level_path_too():
    """Model docstring: a channel the sensor does not provide answers ``EX`` and is counted
    (``unprovided_requests``), whichever path evaluates the command: here one E1 command through ``Bus.transfer``
    to a sensor built for PAC and PDC only.  Exact count."""
    b = Bus({1: SensorPort(Sensor(channels_read=["PAC", "PDC"], seed=1, noise=NoiseSources.none()), 1)})
    b.transfer(cmd(0.0, int(proto.sample_command(17))))
    assert b.transfer(read(100e-6)) == E["channel_not_recognized"]
    assert b.ports[1].unprovided_requests == 1


@pytest.mark.parametrize("nbits", [1, 7, 9, 15])
def test_any_transfer_of_1_to_15_bits_is_counted_incomplete(nbits):
    """Model docstring: fewer than 16 bits of a command are ignored and counted in ``incomplete`` — a single clock
    edge as well as 15 (a read, first byte 0, of 8 or more bits is not a command)."""
    b = bus()
    b.transfer(Transfer(0.0, SELECT_CODE[1], (1 << nbits) - 1, nbits))
    assert b.ports[1].incomplete == 1


def test_a_software_port_takes_faults_only_as_the_rtl_port_does():
    """``port.faults`` takes a ``Faults`` (``Faults()`` clears them; None at construction means none); a dict or
    None set later is refused naming the sensor and what it takes (a dict had failed at the next transfer, deep in
    the state machine) — one rule for the software and the RTL bus."""
    p = port(2)
    assert p.faults == Faults()
    p.faults = Faults(bad_parity=True)
    assert p.faults.bad_parity
    for bad in ({"bad_parity": True}, None):
        with pytest.raises(ValueError, match=r"sensor 2: faults = .*must be an emulator\.spi\.model\.Faults"):
            p.faults = bad
    assert p.faults == Faults(bad_parity=True)  # unchanged by the refused values


def unplugged_mid_stream(b, port_of, clock_hz: float = proto.HOST_DEFAULT_CLOCK_HZ, sampling: bool = False
                         ) -> list[int]:
    """The words of: sensor 1's serial number asked for and its first two bytes read with chip select held (with
    ``sampling``: a read, then a whole PDC sampling command sent with chip select held), sensor 1 unplugged (its
    port removed from ``b.ports``) inside that window, two more reads of it (the last releasing chip select), sensor
    3 sampling PAC and read, sensor 1 plugged back in (``port_of(b)``) and read, then sampling PDC and read.  One
    transfer a call, 100 µs apart.  Closes ``b``."""
    s1, s3, t, out = SELECT_CODE[1], SELECT_CODE[3], 0.01, []
    pac, pdc = (int(proto.sample_command(channel_index(c))) << 8 for c in ("PAC", "PDC"))
    held = [(s1, 0, False), (s1, pdc, True)] if sampling else [(s1, 0x6115, False), (s1, 0, True)]
    steps = [*held, None, (s1, 0, True), (s1, 0, False), (s3, pac, False), (s3, 0, False),
             "plug", (s1, 0, False), (s1, pdc, False), (s1, 0, False)]
    try:
        for step in steps:
            if step is None:
                b.ports.pop(1)
            elif step == "plug":
                b.ports[1] = port_of(b)
            else:
                out.append(b.transfer(Transfer(t, step[0], step[1], 16, clock_hz, keep_cs=step[2])))
                t += 100e-6
    finally:
        b.close()
    return out


@pytest.mark.parametrize("sampling", [False, True], ids=["property-stream", "sampling-command"])
@pytest.mark.parametrize("pull_up,idle", [(False, 0x0000), (True, 0xFFFF)])
def test_a_sensor_unplugged_with_chip_select_held_on_it_leaves_the_idle_line(pull_up, idle, sampling):
    """Unplugging a sensor inside a chip-select window held open on it (a property stream, or a whole sampling
    command not yet acted on): its select code then reads the pull level (no error), the other sensor answers as
    ever, and plugged back in it starts from power-on ("E_": nothing prepared, the held command forgotten) and
    samples as ever."""
    sensors = {n: Sensor(channels_read=ALL, seed=n, noise=NoiseSources.none()) for n in (1, 3)}
    words = unplugged_mid_stream(Bus({n: SensorPort(s, n) for n, s in sensors.items()}, pull_up=pull_up),
                                 lambda b: SensorPort(sensors[1], 1), sampling=sampling)
    assert words[1] == (E["nothing_to_resend"] if sampling else int.from_bytes(b"BT", "big"))
    assert words[2] == words[3] == idle
    assert proto.decode_response(words[5])[1] and words[6] == words[7] == E["nothing_to_resend"]
    assert proto.decode_response(words[8])[1]


def _probe(b: Bus) -> tuple:
    """What a bus's state shows: when its last transfer ended, its ports' counters and what the sensors answer next
    (every frame channel of sensors 1 and 2 sampled, then read, 1 s on)."""
    from emulator.spi.model import PORT_COUNTERS

    counters = tuple(getattr(p, c) for p in b.ports.values() for c in PORT_COUNTERS)
    t = max(b._last_end, 0.0) + 1.0
    commands = [int(proto.sample_command(channel_index(name))) << 8 for name in ALL[:6]]
    start = t + 100e-6 * np.arange(2 * 2 * len(commands))
    mosi = np.array([w for c in commands for w in (c, c, 0, 0)], np.uint16)
    cs = np.tile([SELECT_CODE[1], SELECT_CODE[2]], mosi.size // 2)
    return b._last_end, counters, b.exchange_words(start, cs, mosi, 4.4e6).tolist()


def test_an_interrupt_inside_exchange_words_leaves_the_bus_wholly_before_or_after_the_call():
    """Module docstring ("A call is whole"): a real SIGALRM, whose handler raises KeyboardInterrupt as Ctrl-C's does,
    is raised in the main thread as the 500th of 2000 words to two sensors goes through (one of them a property
    request, so the call goes word by word: the bus's own ``transfer`` is wrapped to raise it, then goes on as it
    was).  The call still raises KeyboardInterrupt, and the bus is then as one that made no call or the whole call:
    the same end, counters and next answers.  The handler used to run between two words, leaving the bus part-way:
    its last end mid-batch.  (The signal comes at that word whatever the machine's load: a timer could land after
    the call and test nothing.)"""
    n = 2000
    start = 1e-3 + 60e-6 * np.arange(n)
    cs = np.tile([SELECT_CODE[1], SELECT_CODE[2]], n // 2)
    commands = [int(proto.sample_command(channel_index(name))) << 8 for name in ALL]
    mosi = np.array([commands[(k // 4) % len(commands)] if k % 4 < 2 else 0 for k in range(n)], np.uint16)
    mosi[n // 2] = 0x6100 | 0x02  # (a property request: not plain word traffic)
    before, after = bus(2), bus(2)
    whole = after.exchange_words(start, cs, mosi, 4.4e6)
    interrupted = bus(2)
    words = []

    def transfer_then_signal(tr):  # the bus's own transfer; SIGALRM raised as its 500th word is through
        bits = Bus.transfer(interrupted, tr)
        words.append(tr)
        if len(words) == n // 4:
            signal.raise_signal(signal.SIGALRM)
        return bits

    def interrupt(sig, frame):
        raise KeyboardInterrupt("SIGALRM")

    interrupted.transfer = transfer_then_signal
    previous = signal.signal(signal.SIGALRM, interrupt)
    try:
        with pytest.raises(KeyboardInterrupt, match="SIGALRM"):
            interrupted.exchange_words(start, cs, mosi, 4.4e6)
    finally:
        signal.signal(signal.SIGALRM, previous)
        del interrupted.transfer
    assert len(words) in (n // 4, n)  # the word path ran, and the signal came inside the call
    state = _probe(interrupted)
    assert state in (_probe(before), _probe(after)), "the bus was left part-way through the call"
    assert whole.size == n


def test_every_signal_held_inside_a_bus_call_runs_its_handler_even_after_one_raises():
    """signals_held: SIGUSR1 and SIGUSR2 come inside the block, SIGUSR1's handler raising as Ctrl-C's does.  Both
    handlers run as the block ends, in the order the signals came, and the exception propagates (as Python would
    run SIGUSR2's handler at its next check).  SIGUSR2's used to be dropped once SIGUSR1's had raised."""
    from emulator.spi.model import signals_held

    ran = []

    def first(sig, frame):
        ran.append(sig)
        raise KeyboardInterrupt("SIGUSR1")

    def second(sig, frame):
        ran.append(sig)

    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGUSR1, signal.SIGUSR2)}
    try:
        signal.signal(signal.SIGUSR1, first)
        signal.signal(signal.SIGUSR2, second)
        with pytest.raises(KeyboardInterrupt, match="SIGUSR1"):
            with signals_held():
                signal.raise_signal(signal.SIGUSR1)
                signal.raise_signal(signal.SIGUSR2)
                assert ran == [], "a handler ran inside the block"
        assert ran == [signal.SIGUSR1, signal.SIGUSR2]
        assert signal.getsignal(signal.SIGUSR1) is first and signal.getsignal(signal.SIGUSR2) is second
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def test_a_handler_installed_inside_a_block_holding_signals_stays_installed():
    """signals_held puts back only the handlers it swapped: one the block installs itself (here for SIGUSR1) is
    the handler after the block, not the one before it (which the block used to put back over it)."""
    from emulator.spi.model import signals_held

    def before(sig, frame):
        pass

    def installed(sig, frame):
        pass

    previous = signal.getsignal(signal.SIGUSR1)
    try:
        signal.signal(signal.SIGUSR1, before)
        with signals_held():
            signal.signal(signal.SIGUSR1, installed)
        assert signal.getsignal(signal.SIGUSR1) is installed
    finally:
        signal.signal(signal.SIGUSR1, previous)

