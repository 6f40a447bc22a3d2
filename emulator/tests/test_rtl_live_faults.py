"""SPI faults set while the RTL streams: a fault schedule (``bus.ports[k].faults = Faults(...)`` between calls, as a
bridge's ``bench.at`` events set them) gives the same words over the RTL in the C++ harness (:class:`RtlBus`) as
over the software bus, each change acting from the first transfer after it, on its own sensor only."""

import numpy as np
import pytest

from emulator.rtl.harness import STREAM_READY
from emulator.spi import protocol as proto
from emulator.spi.model import SELECT_CODE, Bus, Faults, SensorPort

pytestmark = pytest.mark.rtl

ERR = proto.ERROR_WORDS
RESEND = 0x2000  # the resend command (first byte 0x20): the sensor prepares the last word it served again
CALL_S, CLOCK_HZ = 1e-3, proto.HOST_DEFAULT_CLOCK_HZ
#: One call's transfers: (µs after the call's start, sensor, channel sampled or None for a read).  The first two
#: read the commands that ended the call before (so a fault set in between acts on a result converted before it).
CALL = [(0, 1, None), (10, 3, None), (100, 1, "PDC"), (110, 3, "PAC"), (170, 1, None), (180, 3, None),
        (300, 1, "E1"), (310, 3, "TDC")]
S1 = [k for k, (_, n, _) in enumerate(CALL) if n == 1]
S3 = [k for k, (_, n, _) in enumerate(CALL) if n == 3]
READS_S1, READS_S3 = ([k for k, (_, n, c) in enumerate(CALL) if n == s and c is None] for s in (1, 3))
#: The schedule: {call: {sensor: faults set just before it}}; each fault is cleared (Faults()) a call later.
SCHEDULE = {1: {1: Faults(miso_stuck=1)},
            2: {1: Faults(), 3: Faults(bad_parity=True)},
            3: {3: Faults(), 1: Faults(miso_flip_bit=3)},
            4: {1: Faults(), 3: Faults(slow_response=True)},
            5: {3: Faults(), 1: Faults(mosi_flip_bit=0)},
            6: {1: Faults()},
            7: {1: Faults(bad_parity=True)},
            8: {1: Faults()}}
CALLS = 9


@pytest.fixture(scope="module")
def harness():
    from emulator.rtl.harness import Harness

    h = Harness()
    h.ensure_built()
    return h


def _sensors():
    from emulator.channels import DEFAULT_FRAME_NAMES
    from emulator.sensor import Sensor

    return {n: Sensor(channels_read=list(DEFAULT_FRAME_NAMES), seed=n + 4) for n in (1, 3)}


def _call(k: int):
    """(start s, select codes, MOSI words) of call ``k``."""
    from emulator.channels import channel_index

    start = np.array([0.01 + k * CALL_S + us * 1e-6 for us, _, _ in CALL])
    cs = np.array([SELECT_CODE[n] for _, n, _ in CALL])
    mosi = np.array([0 if c is None else int(proto.sample_command(channel_index(c))) << 8 for _, _, c in CALL],
                    np.uint16)
    return start, cs, mosi


def _play(bus, schedule: dict) -> np.ndarray:
    """Words of the calls over ``bus`` (a software Bus or an RtlBus) with ``schedule``'s faults: (call, transfer)."""
    words = []
    try:
        for k in range(CALLS):
            for n, faults in schedule.get(k, {}).items():
                bus.ports[n].faults = faults
            start, cs, mosi = _call(k)
            words.append(bus.exchange_words(start, cs, mosi, CLOCK_HZ))
    finally:
        bus.close()
    return np.array(words, np.uint16)


def _software(schedule: dict) -> np.ndarray:
    return _play(Bus({n: SensorPort(s, n) for n, s in _sensors().items()}), schedule)


def _rtl(harness, schedule: dict) -> np.ndarray:
    from emulator.rtl.harness import RtlBus

    return _play(RtlBus(_sensors(), harness=harness), schedule)


def test_a_fault_schedule_gives_the_same_words_over_the_rtl_as_over_the_software_bus(harness):
    """MISO stuck high, a flipped MISO bit and a MOSI bit flip on sensor 1, corrupted parity and a slow response on
    sensor 3, and corrupted parity on sensor 1 after a call with no faults, each set between two calls and cleared a
    call later: word for word the same over the RTL (its fault
    ports changed while it streams) as over the software bus — the MOSI flip turning sensor 1's reads into PAC
    commands whose conversions the RTL requests (a code the emulator did not compute would be a HarnessError)."""
    soft = _software(SCHEDULE)
    rtl = _rtl(harness, SCHEDULE)
    differ = [(k, i, hex(a), hex(b)) for k, i in zip(*np.nonzero(rtl != soft)) for a, b in [(rtl[k, i], soft[k, i])]]
    assert not differ, f"(call, transfer, RTL, software): {differ[:6]}"


def test_each_fault_acts_from_the_first_transfer_after_it_and_on_its_own_sensor_only(harness):
    """Over the RTL, against the same calls without faults: a fault acts on its sensor's first transfer of the call
    it was set before (a read, first in the call) and on no other sensor's, and a cleared one is gone by then — a
    change landing one transfer late, or on the other sensor, fails here."""
    clean, rtl = _rtl(harness, {}), _rtl(harness, SCHEDULE)
    data = proto.decode_response(clean[:, [0, 1, 4, 5]])[1]
    assert data[1:].all() and not proto.is_error_word(clean[1:, [0, 1, 4, 5]]).any()  # clean reads: data
    # call 1, sensor 1 stuck high: every word 0xFFFF; sensor 3 untouched
    assert (rtl[1, S1] == 0xFFFF).all() and np.array_equal(rtl[1, S3], clean[1, S3])
    # call 2: sensor 1 cleared; sensor 3's reads leave with the parity bit inverted, the first one too (its
    # conversion was made in call 1, before the fault was set)
    assert np.array_equal(rtl[2, S1], clean[2, S1])
    assert np.array_equal(rtl[2, READS_S3], clean[2, READS_S3] ^ 0x0100)
    assert not proto.decode_response(rtl[2, READS_S3])[1].any()
    # call 3: sensor 3 cleared; sensor 1's bit 3 (from chip-select fall) inverted in every word
    assert np.array_equal(rtl[3, S3], clean[3, S3])
    assert np.array_equal(rtl[3, S1], clean[3, S1] ^ 0x1000)
    # call 4: sensor 1 cleared; sensor 3 slow: its result 70 µs after the command is not ready yet ("E.")
    assert np.array_equal(rtl[4, S1], clean[4, S1])
    assert rtl[4, 5] == ERR["insufficient_delay"] and rtl[4, 1] == clean[4, 1]
    # call 5: sensor 1 receives bit 0 inverted: its E1 command arrives with even parity, read in call 6 as "EE";
    # sensor 3 (cleared) reads data again
    assert rtl[6, 0] == ERR["parity"] and proto.decode_response(rtl[5, READS_S3])[1].all()
    # call 7, after a call with no faults: sensor 1's reads leave with the parity bit inverted, the first one (its
    # conversion made by the software bus's vectorized path in call 6) too; sensor 3 untouched
    assert np.array_equal(rtl[7, READS_S1], clean[7, READS_S1] ^ 0x0100) and np.array_equal(rtl[7, S3], clean[7, S3])
    assert np.array_equal(rtl[8], clean[8])  # all clear


def test_an_rtl_port_takes_faults_only(harness):
    """``port.faults`` on the RTL bus takes a ``Faults`` (set or cleared); anything else — a dict, None — is refused
    naming the sensor and what it takes; a field set in place out of range is refused by name at the next call,
    before the harness sees it."""
    from emulator.rtl.harness import RtlBus

    bus = RtlBus(_sensors(), harness=harness)
    try:
        bus.ports[3].faults = Faults(bad_parity=True)
        bus.ports[3].faults = Faults()
        for bad in ({"bad_parity": True}, None):
            with pytest.raises(ValueError, match=r"sensor 3: faults = .*must be an emulator\.spi\.model\.Faults"):
                bus.ports[3].faults = bad
        bus.ports[1].faults.miso_flip_bit = 16
        with pytest.raises(ValueError, match=r"sensor 1: Faults\.miso_flip_bit = 16: must be None or a bit position"):
            bus.exchange_words(*_call(0), CLOCK_HZ)
        bus.ports[1].faults = Faults()
        assert bus.exchange_words(*_call(0), CLOCK_HZ).size == len(CALL)  # the harness goes on
    finally:
        bus.close()


def test_a_fault_changed_inside_a_held_chip_select_acts_on_the_bits_clocked_after_it(harness):
    """With chip select held across calls (how a host streams a property byte by byte), a fault set between two
    bytes acts from the next byte on: MISO stuck high for one byte of the serial number reads 0xFF there only; a
    MOSI flip of bit 0 set before a command's first byte turns 0x80 (sample PAC) into a read, and set only after
    it has been clocked changes nothing, the PAC conversion happening — over the RTL as over the software bus."""
    from emulator.rtl.harness import RtlBus
    from emulator.spi.model import SELECT_NONE, Transfer

    s1 = SELECT_CODE[1]
    steps = [(None, (s1, 0x6115, 16, False)), (None, (s1, 0, 8, True)), (Faults(miso_stuck=1), (s1, 0, 8, True)),
             (Faults(), (s1, 0, 8, True)), (None, (SELECT_NONE, 0, 0, False)),
             (Faults(mosi_flip_bit=0), (s1, 0x80, 8, True)), (Faults(), (s1, 0, 8, False)),
             (None, (s1, 0, 16, False)),
             (None, (s1, 0x80, 8, True)), (Faults(mosi_flip_bit=0), (s1, 0, 8, False)),
             (Faults(), (s1, 0, 16, False))]

    def play(bus):
        try:
            out = []
            for k, (faults, (cs, mosi, nbits, keep)) in enumerate(steps):
                if faults is not None:
                    bus.ports[1].faults = faults
                out.append(bus.transfer(Transfer(0.01 + 100e-6 * k, cs, mosi, nbits, CLOCK_HZ, keep)))
            return out
        finally:
            bus.close()

    soft = play(Bus({n: SensorPort(s, n) for n, s in _sensors().items()}))
    rtl = play(RtlBus(_sensors(), harness=harness))
    assert rtl == soft, ([hex(w) for w in rtl], [hex(w) for w in soft])
    assert rtl[1:4] == [ord("B"), 0xFF, ord("0")]  # "BT0…": the second byte read stuck high
    assert not proto.decode_response(rtl[7])[1] and proto.decode_response(rtl[10])[1]


def test_a_write_acknowledgement_keeps_the_parity_fault_in_force_when_the_write_was_taken(harness):
    """Corrupted parity acts on a write's acknowledgement as the write is taken, not as it is read: set between the
    write and its read it leaves the acknowledgement clean; cleared there, the acknowledgement still reads with
    the parity bit inverted — over the RTL as over the software bus (a sample's word, by contrast, takes the fault
    in force when it is read: the schedule test)."""
    from emulator.rtl.harness import RtlBus

    write = 0x400B  # parameter 0 := 5 (odd parity)
    s1 = np.array([SELECT_CODE[1]])
    words = {}
    for name, make in (("software", lambda: Bus({n: SensorPort(s, n) for n, s in _sensors().items()})),
                       ("RTL", lambda: RtlBus(_sensors(), harness=harness))):
        bus = make()
        try:
            out = []
            for k, (before_write, before_read) in enumerate(((None, Faults(bad_parity=True)),
                                                            (Faults(bad_parity=True), Faults()))):
                t = 0.01 + k * 1e-3
                if before_write is not None:
                    bus.ports[1].faults = before_write
                bus.exchange_words(np.array([t]), s1, np.array([write], np.uint16), CLOCK_HZ)
                bus.ports[1].faults = before_read
                out += list(bus.exchange_words(np.array([t + 100e-6]), s1, np.array([0], np.uint16), CLOCK_HZ))
            words[name] = out
        finally:
            bus.close()
    assert words["RTL"] == words["software"], words
    clean, corrupted = words["RTL"]
    assert proto.decode_response(clean)[1] and corrupted == clean ^ 0x0100


@pytest.mark.parametrize("record,words", [
    (dict(sensor=6), "fault change: a fault record for sensor 6 outside its ranges"),
    (dict(sensor=2, stuck_en=2), "fault change: a fault record for sensor 2 outside its ranges"),
    (dict(sensor=1, miso_flip_en=1, miso_flip_bit=16), "fault change: a fault record for sensor 1 outside"),
    (None, "malformed stream header"),
], ids=["sensor-6", "flag-2", "bit-16", "old-format-header"])
def test_the_streaming_harness_refuses_what_its_fault_ports_cannot_take(harness, record, words):
    """The harness checks each fault change it is sent (sensor 1–5, flags 0/1, bit positions 0–15) and stops with
    a message naming it, rather than set ports of another sensor or bits past the 16 a word has; a stream in the
    format before fault changes (header BTSPIV2) is refused at its header."""
    import struct
    import subprocess

    from emulator.rtl.harness import FAULTS, TRANSFER, Harness

    header = Harness._header({"sensors": [1, 2], "pull_up": False}, 0)
    tr = np.zeros(1, TRANSFER)
    tr["t_ps"], tr["half_ps"], tr["nbits"], tr["cs"] = 10_000_000, 113_636, 16, SELECT_CODE[1]
    rec = np.zeros(1, FAULTS)
    for key, value in (record or {}).items():
        rec[key] = value
    if record is None:
        header = b"BTSPIV2\0" + header[8:]
    batch = struct.pack("<III", 1, 0, 1) + tr.tobytes() + rec.tobytes()
    r = subprocess.run([str(harness.binary), "--stream"], input=header + batch, capture_output=True, timeout=60)
    assert r.returncode == 2 and words in r.stderr.decode(), r.stderr
    assert r.stdout == (b"" if record is None else STREAM_READY)  # nothing played (a header refused: not taken)


def test_an_edited_harness_cpp_is_rebuilt_not_reused(tmp_path, monkeypatch):
    """The stream format lives in harness.cpp (the fault changes came with an edit of it): a build whose stamp is
    another harness.cpp's digest is rebuilt, never run with the new format (one with the same sources is reused)."""
    from emulator.rtl import harness as H

    builds = []

    def fake_build(self):
        builds.append(self.build_dir)
        self.binary.parent.mkdir(parents=True, exist_ok=True)
        self.binary.write_text("built")
        return self.binary

    monkeypatch.setattr(H.Harness, "_build", fake_build)
    h = H.Harness(tmp_path / "h")
    h.ensure_built()
    h.ensure_built()
    assert len(builds) == 1
    edited = tmp_path / "harness.cpp"
    edited.write_text(H.HARNESS_CPP.read_text() + "\n// edited\n")
    monkeypatch.setattr(H, "HARNESS_CPP", edited)
    h.ensure_built()
    assert len(builds) == 2


def _play_with_resets(bus, calls, resets: dict) -> list:
    """Words of ``calls`` ([(start s, select codes, MOSI words)]) over ``bus``, resetting the ports ``resets`` names
    ({call: [sensors]}) just before each call (``bus.ports[n].reset()``, a brown-out as a bridge's ``reset_at``)."""
    out = []
    try:
        for k, (start, cs, mosi) in enumerate(calls):
            for n in resets.get(k, []):
                bus.ports[n].reset()
            out.append([int(w) for w in bus.exchange_words(start, cs, mosi, CLOCK_HZ)])
    finally:
        bus.close()
    return out


def test_a_port_reset_reaches_the_rtl_at_the_next_transfer_with_the_software_bus_words(harness):
    """``bus.ports[k].reset()`` between calls resets that sensor in the RTL just before the next call's first
    transfer, as on the software bus: the result converted before it is gone (its read gets "E_"), the other
    sensor's is served, and a sampling command 4 µs after one from before the reset is accepted (the reset forgot
    the ADC-busy window: "E-" without it) and its result read — word for word the same over both buses."""
    from emulator.rtl.harness import RtlBus

    calls = [_call(k) for k in range(4)]
    s1, pdc = np.array([SELECT_CODE[1]]), np.array([int(proto.sample_command(1)) << 8], np.uint16)
    t = calls[3][0][-1] + 100e-6
    calls.append((np.array([t]), s1, pdc))  # a sampling command ends the call; the next one starts 0.2 µs later
    t += 16.5 / CLOCK_HZ + 0.2e-6
    calls.append((np.array([t, t + 100e-6]), np.repeat(s1, 2), np.array([pdc[0], 0], np.uint16)))
    resets = {1: [1], 3: [1, 3], 5: [1]}
    soft = _play_with_resets(Bus({n: SensorPort(s, n) for n, s in _sensors().items()}), calls, resets)
    rtl = _play_with_resets(RtlBus(_sensors(), harness=harness), calls, resets)
    assert rtl == soft, [(k, [hex(w) for w in a], [hex(w) for w in b]) for k, (a, b) in enumerate(zip(rtl, soft))
                         if a != b]
    nothing = ERR["nothing_to_resend"]
    assert rtl[1][0] == nothing and rtl[2][0] != nothing and proto.decode_response(rtl[1][1])[1]  # sensor 3 kept
    assert rtl[3][0] == rtl[3][1] == nothing
    assert not proto.is_error_word(rtl[5][1]) and proto.decode_response(rtl[5][1])[1]  # accepted, not "E-"


def test_a_port_reset_inside_a_window_held_open_over_the_rtl_is_refused_by_name(harness):
    """A reset while this bus holds chip select open on the sensor across calls is refused naming the sensor (the
    RTL's bit counter would run on where the software port's restarts); released, the reset is taken."""
    from emulator.rtl.harness import RtlBus
    from emulator.spi.model import Transfer

    bus = RtlBus(_sensors(), harness=harness)
    try:
        bus.transfer(Transfer(0.01, SELECT_CODE[1], 0x61, 8, CLOCK_HZ, keep_cs=True))
        with pytest.raises(ValueError, match=r"sensor 1: reset\(\) inside a chip-select window held open"):
            bus.ports[1].reset()
        bus.ports[3].reset()  # another sensor's: taken
        bus.transfer(Transfer(0.0101, SELECT_CODE[1], 0x15, 8, CLOCK_HZ))
        bus.ports[1].reset()
        assert bus.transfer(Transfer(0.0102, SELECT_CODE[1], 0, 16, CLOCK_HZ)) == ERR["nothing_to_resend"]
    finally:
        bus.close()


def test_the_fault_ports_a_simulator_sets_come_from_the_harness_records_sensor_by_sensor():
    """:func:`fault_port_values` (what the cocotb bench assigns) packs each sensor's record into its own slice of the
    bus's ports — a one-bit flag at bit n-1, a bit position at bits 12(n-1).. — sensors named by number or string (a
    vector file's keys); no faults clear every port; a sensor outside 1–5 is refused by name."""
    from emulator.rtl.harness import FAULT_PORTS, fault_port_values

    ports = fault_port_values({1: Faults(miso_stuck=0), 2: Faults(miso_stuck=1, bad_parity=True),
                               "3": {"mosi_flip_bit": 5}, 5: Faults(miso_flip_bit=0, slow_response=True)})
    assert ports == {"flt_miso_flip_en": 0b10000, "flt_miso_flip_bit": 0, "flt_mosi_flip_en": 0b00100,
                     "flt_mosi_flip_bit": 5 << 24, "flt_miso_stuck_en": 0b00011, "flt_miso_stuck_val": 0b00010,
                     "flt_bad_parity": 0b00010, "flt_slow": 0b10000}
    assert fault_port_values({}) == dict.fromkeys(FAULT_PORTS, 0)
    assert fault_port_values({4: Faults(miso_flip_bit=15)})["flt_miso_flip_bit"] == 15 << 36
    with pytest.raises(ValueError, match=r"fault records for sensors \[6\]: sensors are 1 to 5"):
        fault_port_values({6: Faults()})


def test_hot_plugging_over_the_rtl_gives_the_software_bus_words_and_refuses_a_port_it_cannot_hold(harness):
    """A port removed from ``bus.ports`` (unplugged: its reads see the idle line) and put back (plugged in, in
    power-on state: its first read "E_", and a resend "E_" too) give the same words over the RTL as over the
    software bus.  The RTL bus refuses, naming the sensor, a sensor it did not start with, a port that is not its
    own ``RtlSensorPort``, and a sensor of other channels — before anything reaches the harness (it goes on
    afterwards)."""
    from emulator.rtl.harness import RtlBus, RtlSensorPort
    from emulator.sensor import Sensor

    def call(k):  # _call(k): it ends on sensor 3's sampling command, converted at the next call on either bus —
        # never, if sensor 3 is unplugged before it (the RTL's request then answered with no code computed)
        start, cs, mosi = _call(k)
        if k == 3:  # sensor 3's first transfer after it is plugged back in asks to resend its last word
            mosi[1] = RESEND
        return start, cs, mosi

    def play(bus, port_of):
        out = []
        try:
            for k in range(5):
                if k == 1:
                    bus.ports.pop(3)
                if k == 3:
                    bus.ports[3] = port_of(bus)
                out.append([int(w) for w in bus.exchange_words(*call(k), CLOCK_HZ)])
        finally:
            bus.close()
        return out

    sensors, rtl_sensors = _sensors(), _sensors()
    soft = play(Bus({n: SensorPort(s, n) for n, s in sensors.items()}), lambda bus: SensorPort(sensors[3], 3))
    rtl = play(RtlBus(rtl_sensors, harness=harness), lambda bus: RtlSensorPort(rtl_sensors[3], 3, bus))
    assert rtl == soft
    assert set(rtl[1][k] for k in S3) == set(rtl[2][k] for k in S3) == {0}  # unplugged: the idle line (pull-down)
    # power-on: nothing prepared, and nothing to resend (the word it read before it was unplugged is gone); then data
    assert rtl[3][1] == rtl[3][3] == ERR["nothing_to_resend"] and proto.decode_response(rtl[3][5])[1]

    bus = RtlBus(_sensors(), harness=harness)
    try:
        for n, port, words in ((4, lambda: RtlSensorPort(sensors[1], 4, bus), r"sensor 4: not on this RTL bus when "
                                r"it started \(sensors \[1, 3\]\): its set of sensors is fixed"),
                               (3, lambda: SensorPort(sensors[3], 3), r"sensor 3: a port plugged into an RTL bus must "
                                r"be RtlSensorPort\(sensor, 3, bus\).*not SensorPort"),
                               (3, lambda: RtlSensorPort(Sensor(channels_read=["PAC"]), 3, bus),
                                r"sensor 3: plugged back in as biotac providing 1 channels; the RTL was started with "
                                r"biotac providing")):
            kept = dict(bus.ports)
            bus.ports[n] = port()
            with pytest.raises(ValueError, match=words):
                bus.exchange_words(*_call(0), CLOCK_HZ)
            bus.ports.clear()
            bus.ports.update(kept)
        assert bus.exchange_words(*_call(1), CLOCK_HZ).size == len(CALL)
    finally:
        bus.close()


@pytest.mark.parametrize("field,value", [("reset_mask", 0x20), ("set_present", 2), ("present", 0x21)])
def test_the_streaming_harness_refuses_a_reset_or_sensors_present_outside_its_five_sensors(harness, field, value):
    """A transfer's reset mask or sensors present with a bit past the five sensors, or a set_present flag other than
    0/1, stops the harness with a message naming it, before anything is played."""
    tr = _raw_transfers([(SELECT_CODE[1], 0)])
    tr["set_present"] = 1
    tr[field] = value
    r = _stream(harness, [1, 2], tr)
    assert r.returncode == 2 and b"transfer 0 of a batch: a reset mask or sensors present outside" in r.stderr, r.stderr
    assert r.stdout == STREAM_READY  # the header taken, nothing played


def _raw_transfers(words) -> np.ndarray:
    """The streaming harness's records of 16-bit transfers ``words`` ([(select code, MOSI word)]), 100 µs apart from
    10 µs, at the host's default clock, each releasing chip select."""
    from emulator.rtl.harness import TRANSFER

    tr = np.zeros(len(words), TRANSFER)
    tr["t_ps"] = 10_000_000 + 100_000_000 * np.arange(len(words))
    tr["half_ps"], tr["nbits"] = round(0.5e12 / CLOCK_HZ), 16
    tr["cs"], tr["mosi"] = [c for c, _ in words], [w for _, w in words]
    return tr


def _stream(harness, sensors: list, tr: np.ndarray):
    """Run the streaming harness (no faults, pull-down, ``sensors`` present) on one batch ``tr`` with no codes: the
    finished process (its stdout: STREAM_READY, then a uint64 MISO per transfer, then the counts)."""
    import struct
    import subprocess

    from emulator.rtl.harness import Harness

    header = Harness._header({"sensors": sensors, "pull_up": False}, 0)
    return subprocess.run([str(harness.binary), "--stream"],
                          input=header + struct.pack("<III", len(tr), 0, 0) + tr.tobytes(), capture_output=True,
                          timeout=60)


def test_the_rtl_holds_an_absent_sensor_in_reset_so_it_comes_back_in_power_on_state_by_itself(harness):
    """``biotac_bus`` alone (no reset pulse from the bench): sensor 1 asked for its serial number, then read, serves
    "BT"; asked, unplugged (its ``present`` bit cleared: its select code reads the idle line), plugged back in and
    read, it answers "E_" (nothing prepared: it was held in reset while away).  No request, no code left over."""
    ask, read = (SELECT_CODE[1], 0x6115), (SELECT_CODE[1], 0)
    plugged, away = _raw_transfers([ask, read]), _raw_transfers([ask, read, read])
    away["set_present"][1:], away["present"][1:] = 1, [0, 1]
    out = {}
    for name, tr in (("plugged", plugged), ("away", away)):
        r = _stream(harness, [1], tr)
        assert r.returncode == 0, r.stderr
        assert r.stdout.startswith(STREAM_READY)
        out[name] = [int(w) for w in np.frombuffer(r.stdout[len(STREAM_READY):], "<u8")]
        assert out[name][len(tr):len(tr) + 2] == [0, 0]  # no mismatched request, no code left
    assert out["plugged"][1] == int.from_bytes(b"BT", "big")
    assert out["away"][1:3] == [0, ERR["nothing_to_resend"]]


@pytest.mark.parametrize("sampling", [False, True], ids=["property-stream", "sampling-command"])
def test_a_sensor_unplugged_with_chip_select_held_on_it_gives_the_same_words_over_the_rtl(harness, sampling):
    """The software bus's unplug in the middle of a property stream, or of a window holding a whole sampling command
    not yet acted on, held open (:func:`emulator.tests.test_spi_model.unplugged_mid_stream`: the idle line, then
    power-on "E_" once plugged back in, then data) gives the same words over the RTL bus: the RTL holds an absent
    sensor in reset, so the chip-select rise its unplugging makes neither prepares nor requests a conversion."""
    from emulator.rtl.harness import RtlBus, RtlSensorPort
    from emulator.tests.test_spi_model import unplugged_mid_stream

    soft_sensors, rtl_sensors = _sensors(), _sensors()
    soft = unplugged_mid_stream(Bus({n: SensorPort(s, n) for n, s in soft_sensors.items()}),
                                lambda bus: SensorPort(soft_sensors[1], 1), sampling=sampling)
    rtl = unplugged_mid_stream(RtlBus(rtl_sensors, harness=harness), lambda bus: RtlSensorPort(rtl_sensors[1], 1, bus),
                               sampling=sampling)
    assert rtl == soft, [(k, hex(a), hex(b)) for k, (a, b) in enumerate(zip(rtl, soft)) if a != b]


def test_a_sensor_plugged_back_in_inside_a_window_held_open_over_the_rtl_is_refused_by_name(harness):
    """Unplugged and plugged back in between two calls inside a chip-select window held open on it, the RTL sensor
    would see no chip-select fall (the software bus's new port does): refused naming the sensor, before anything
    reaches the harness; with a call in between (the sensor away while the window is held) it is taken."""
    from emulator.rtl.harness import RtlBus, RtlSensorPort
    from emulator.spi.model import Transfer

    sensors = _sensors()
    bus = RtlBus(sensors, harness=harness)
    try:
        bus.transfer(Transfer(0.01, SELECT_CODE[1], 0x6115, 16, CLOCK_HZ))
        bus.transfer(Transfer(0.0101, SELECT_CODE[1], 0, 16, CLOCK_HZ, keep_cs=True))
        bus.ports[1] = RtlSensorPort(sensors[1], 1, bus)
        with pytest.raises(ValueError, match=r"sensor 1: unplugged and plugged back in inside a chip-select window"):
            bus.transfer(Transfer(0.0102, SELECT_CODE[1], 0, 16, CLOCK_HZ, keep_cs=True))
        port = bus.ports.pop(1)
        assert bus.transfer(Transfer(0.0103, SELECT_CODE[1], 0, 16, CLOCK_HZ, keep_cs=True)) == 0  # away: idle line
        bus.ports[1] = port
        # plugged in while chip select is held on its code: it sees chip select fall, power-on: nothing prepared
        assert bus.transfer(Transfer(0.0104, SELECT_CODE[1], 0, 16, CLOCK_HZ)) == ERR["nothing_to_resend"]
    finally:
        bus.close()


def test_a_chip_select_window_with_no_clock_edge_counts_on_its_sensors_port_on_either_bus(harness):
    """A glitch (chip select toggled with no clock edge) counts in the selected sensors' ``empty_windows``, over
    the RTL as over the software bus: one on sensor 1, one on sensor 3, one on both (select all), one held on sensor 1
    until the select code moves on; a window held open and then clocked, a clocked word and a glitch selecting
    nobody count nothing.  (The fault campaign's cs_glitch case checks its glitches by this count.)"""
    from emulator.rtl.harness import RtlBus
    from emulator.spi.model import SELECT_ALL, SELECT_NONE, Transfer

    s1, s3 = SELECT_CODE[1], SELECT_CODE[3]
    steps = [(s1, 0, 0, False), (s3, 0, 0, False), (s1, 0x8000, 16, False), (s1, 0, 0, True), (s3, 0, 16, False),
             (s1, 0, 0, True), (s1, 0, 16, False), (SELECT_ALL, 0, 0, False), (SELECT_NONE, 0, 0, False)]
    counts = {}
    for name, bus in (("software", Bus({n: SensorPort(s, n) for n, s in _sensors().items()})),
                      ("RTL", RtlBus(_sensors(), harness=harness))):
        try:
            for k, (cs, mosi, nbits, keep) in enumerate(steps):
                bus.transfer(Transfer(0.01 + 100e-6 * k, cs, mosi, nbits, CLOCK_HZ, keep))
            counts[name] = {n: port.empty_windows for n, port in bus.ports.items()}
        finally:
            bus.close()
    assert counts == {"software": {1: 3, 3: 2}, "RTL": {1: 3, 3: 2}}


def test_a_call_out_of_time_order_or_impossible_is_refused_alike_on_either_bus_and_loses_nothing(harness):
    """A call starting before the last one ended, a transfer overlapping the one before it in its call, a start
    that is not finite and a clock of 0 Hz, NaN or infinite: the same ValueError on both buses (the RTL bus had
    played the first into the harness and failed with a HarnessError about conversions), and nothing reaches the
    RTL — the next valid call gives the software bus's words."""
    from emulator.rtl.harness import RtlBus
    from emulator.spi.model import Transfer

    s1 = SELECT_CODE[1]
    pdc = int(proto.sample_command(1)) << 8  # PDC (channel 1)
    late = ([0.5, 0.5 + 1e-4], [s1, s1], [pdc, 0])
    bad_calls = [(([0.1], [s1], [pdc]), CLOCK_HZ,
                  r"transfer #0 of the call starts at 0\.1 s, before the previous call's last transfer ended "
                  r"\(0\.5001\d* s\): transfers must be in time order"),
                 (([0.6, 0.6 + 1e-6], [s1, s1], [0, 0]), CLOCK_HZ,
                  r"transfer #1 of the call starts at 0\.600001 s, before transfer #0 \(from 0\.6 s\) ends at "
                  r"0\.60000\d* s: transfers must be in time order"),
                 (([np.nan], [s1], [0]), CLOCK_HZ, r"transfer #0 of the call: start_s = nan: must be a finite time"),
                 (([0.7], [s1], [0]), 0.0, r"transfer #0 of the call: SCK 0 Hz: must be a finite frequency > 0"),
                 # (the software bus had raised a bare ValueError about NaN, and a ZeroDivisionError for inf)
                 (([0.7], [s1], [0]), np.nan, r"transfer #0 of the call: SCK nan Hz: must be a finite frequency > 0"),
                 (([0.7], [s1], [0]), np.inf, r"transfer #0 of the call: SCK inf Hz: must be a finite frequency > 0")]
    words = {}
    for name, bus in (("software", Bus({n: SensorPort(s, n) for n, s in _sensors().items()})),
                      ("RTL", RtlBus(_sensors(), harness=harness))):
        try:
            got = list(bus.exchange_words(*late, CLOCK_HZ))
            for args, clock, message in bad_calls:
                with pytest.raises(ValueError, match=message):
                    bus.exchange_words(*args, clock)
                if len(args[0]) == 1:  # and one transfer at a time
                    with pytest.raises(ValueError, match=message):
                        bus.transfer(Transfer(float(args[0][0]), s1, 0, 16, clock))
            got += list(bus.exchange_words([0.8, 0.8 + 1e-4], [s1, s1], [pdc, 0], CLOCK_HZ))
            words[name] = got
        finally:
            bus.close()
    assert words["RTL"] == words["software"]
    assert words["software"][1] != 0 and words["software"][3] != 0  # both reads carry a conversion


def test_a_port_replaced_between_two_calls_comes_up_in_power_on_state_on_either_bus(harness):
    """A sensor's port replaced between two calls with no call while it was away (unplugged and plugged back in at
    once: the RTL's present mask never drops, so only the bus's reset brings its sensor to power-on): asked for its
    serial number just before, the new port's first read is "E_" (nothing prepared: the old one would have served
    "BT") on both buses, then data."""
    from emulator.rtl.harness import RtlBus, RtlSensorPort

    s1 = SELECT_CODE[1]
    pdc = int(proto.sample_command(1)) << 8

    def play(bus, port_of):
        try:
            words = [int(w) for w in bus.exchange_words([0.01], [s1], [0x6115], CLOCK_HZ)]
            bus.ports[1] = port_of(bus)
            words += [int(w) for w in bus.exchange_words([0.02, 0.0201, 0.0202], [s1, s1, s1], [0, pdc, 0],
                                                         CLOCK_HZ)]
            return words
        finally:
            bus.close()

    sensors, rtl_sensors = _sensors(), _sensors()
    soft = play(Bus({n: SensorPort(s, n) for n, s in sensors.items()}), lambda bus: SensorPort(sensors[1], 1))
    rtl = play(RtlBus(rtl_sensors, harness=harness), lambda bus: RtlSensorPort(rtl_sensors[1], 1, bus))
    assert rtl == soft
    assert rtl[1] == ERR["nothing_to_resend"] and proto.decode_response(rtl[3])[1]
