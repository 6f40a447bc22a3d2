"""The counters a sensor's port keeps (``incomplete``, ``unprovided_requests``, ``coupled_conversions``,
``empty_windows``) over the RTL bus (:class:`emulator.rtl.harness.RtlBus`) as over the software bus, the reference."""

import numpy as np
import pytest

from emulator.spi import protocol as proto
from emulator.spi.model import SELECT_ALL, SELECT_CODE, Bus, Faults, SensorPort, Transfer

pytestmark = pytest.mark.rtl

CLOCK_HZ = 10e6  # a 16-bit transfer lasts 1.65 µs: the next one can start inside a 5 µs conversion
COUNTERS = ("incomplete", "unprovided_requests", "coupled_conversions", "empty_windows")
S1, S3 = SELECT_CODE[1], SELECT_CODE[3]


@pytest.fixture(scope="module")
def harness():
    from emulator.rtl.harness import Harness

    h = Harness()
    h.ensure_built()
    return h


def _cmd(name: str) -> int:
    """The 16-bit sampling command of channel ``name``."""
    from emulator.channels import channel_index

    return int(proto.sample_command(channel_index(name))) << 8


def _sensors():
    """Sensor 1 provides PDC and E1 only (PAC and TAC: recognised, not provided); sensor 3 the default frame."""
    from emulator.channels import DEFAULT_FRAME_NAMES
    from emulator.sensor import Sensor

    return {1: Sensor(channels_read=["PDC", "E1"], seed=5), 3: Sensor(channels_read=list(DEFAULT_FRAME_NAMES), seed=7)}


def _at(us: float) -> float:
    return 0.01 + us * 1e-6


#: The traffic: ("words", [(µs, select, MOSI word)]) a call of 16-bit words; ("bits", µs, select, MOSI, bits, keep)
#: one transfer; ("faults", sensor, Faults) set between calls.
TRAFFIC = [
    # PDC on 1, coupled by sensor 3's read 2 µs later; PAC and TAC on 1: not provided; a call ending on E1 on 1
    ("words", [(0, S1, _cmd("PDC")), (2, S3, 0), (60, S1, 0), (100, S1, _cmd("PAC")), (200, S3, _cmd("PAC")),
               (260, S3, 0), (280, S1, _cmd("TAC")), (300, S1, _cmd("E1"))]),
    ("bits", 302, S3, 0b00000, 5, False),  # inside E1's conversion (coupled, judged at this call); 5 bits on 3
    ("bits", 360, S1, 0x000, 12, False),  # 12 bits, first byte 0: a read, not incomplete
    ("bits", 400, S1, 0xA50, 12, False),  # 12 bits, first byte 0xA5: incomplete
    ("bits", 440, S3, 0x0, 4, True), ("bits", 442, S3, 0x0F, 8, False),  # one window of 12 bits, a read
    ("bits", 480, S3, 0x8, 4, True), ("bits", 482, S3, 0x01, 8, False),  # 12 bits, first byte 0x80: incomplete
    ("bits", 520, S1, 0, 0, False),  # a glitch: an empty window
    ("faults", 1, Faults(mosi_flip_bit=3)),
    ("bits", 560, S1, 0x000, 12, False),  # received as 0x100: first byte 0x10, incomplete
    ("bits", 600, S1, 0x0, 4, True), ("bits", 602, S1, 0x00, 8, False),  # held: received 0x100 too, incomplete
    ("faults", 1, Faults()),
    ("words", [(700, SELECT_ALL, _cmd("PDC")), (703, S3, 0), (760, S1, 0), (770, S3, 0),
               (800, S1, _cmd("PAC")), (802, S1, _cmd("PAC")), (900, S3, _cmd("E1"))]),  # busy PAC: E-, not counted
    ("words", [(903, S1, 0), (960, S3, 0)]),  # sensor 3's E1 coupled by this call's first transfer
]


def _drive(bus) -> tuple[dict, list]:
    """Play :data:`TRAFFIC` on ``bus`` (closed after): each port's counters and the MISO the host got."""
    miso = []
    try:
        for step in TRAFFIC:
            if step[0] == "words":
                us, cs, mosi = zip(*step[1])
                miso += list(bus.exchange_words(np.array([_at(u) for u in us]), np.array(cs),
                                                np.array(mosi, np.uint16), CLOCK_HZ))
            elif step[0] == "bits":
                _, us, cs, mosi, nbits, keep = step
                miso.append(bus.transfer(Transfer(_at(us), cs, mosi, nbits, CLOCK_HZ, keep)))
            else:
                bus.ports[step[1]].faults = step[2]
        return {n: {c: getattr(p, c) for c in COUNTERS} for n, p in bus.ports.items()}, [int(m) for m in miso]
    finally:
        bus.close()


def test_the_rtl_bus_counts_what_the_software_bus_counts(harness):
    """The same traffic — windows of 5 and 12 bits (one held over two transfers), reads of fewer than 16 bits, a
    MOSI bit flip turning a short read into a short command (on a window of one transfer and on a held one), a
    glitch, commands for channels a sensor recognises but does not provide, conversions the bus clocks into within
    5 µs (also one a call ends on, judged by the next call's first transfer), a busy command — gives the same MISO
    and the same counters over the RTL as over the software bus, and those counts are the ones the traffic was made
    of (sensor 1: three short commands, three unprovided channels, three coupled conversions, one glitch)."""
    from emulator.rtl.harness import RtlBus

    software, soft_miso = _drive(Bus({n: SensorPort(s, n) for n, s in _sensors().items()}))
    rtl, rtl_miso = _drive(RtlBus(_sensors(), harness=harness))
    assert rtl_miso == soft_miso
    expected = {1: {"incomplete": 3, "unprovided_requests": 3, "coupled_conversions": 3, "empty_windows": 1},
                3: {"incomplete": 2, "unprovided_requests": 0, "coupled_conversions": 2, "empty_windows": 0}}
    assert software == expected  # (the reference counts what the traffic was made of)
    assert rtl == software


@pytest.mark.parametrize("miscount,ends_on_command", [(+1, False), (-1, True)],
                         ids=["a request reported waiting that the emulator left none for",
                              "none reported waiting where the emulator left one"])
def test_a_harness_reporting_another_number_of_waiting_requests_stops_the_bus_with_a_clear_error(
        harness, miscount, ends_on_command):
    """The RTL bus checks, after each call, that the harness has as many conversion requests waiting for a code as
    the emulator left conversions for the next call (one per sensor whose call ended on a sampling command): a
    harness reporting one more (the call ends on a read) or one fewer (the call ends on a command) is a
    HarnessError saying which call, both counts and the sensors the emulator left, and that the bus cannot go on;
    the bus still closes."""
    from emulator.rtl.harness import HarnessError, RtlBus

    class MiscountingBus(RtlBus):
        def _read(self, n: int) -> bytes:  # the harness's last word of a call: requests waiting for a code
            raw = bytearray(super()._read(n))
            raw[-8:] = (int.from_bytes(raw[-8:], "little") + miscount).to_bytes(8, "little")
            return bytes(raw)

    bus = MiscountingBus(_sensors(), harness=harness)
    try:
        last = _cmd("PDC") if ends_on_command else 0
        expected = (r"RTL bus after the call of 2 transfers from 0\.010000000 s to 0\.010060000 s: "
                    + (r"0 RTL conversion request\(s\) wait for a code, where the emulator left 1 conversion\(s\) for "
                       r"the next call \(sensors \[1\]\)" if ends_on_command else
                       r"1 RTL conversion request\(s\) wait for a code, where the emulator left 0 conversion\(s\) for "
                       r"the next call \(sensors \[\]\)")
                    + r".* close this bus")
        with pytest.raises(HarnessError, match=expected):
            bus.exchange_words(np.array([_at(0), _at(60)]), np.array([S1, S1]), np.array([0, last], np.uint16),
                               CLOCK_HZ)
    finally:
        bus.close()
    assert bus.proc.poll() is not None


#: Out-of-spec traffic: (µs, select, MOSI word, SCK Hz) — words at 20 MHz (the host samples MISO a bit late), one at
#: 450 kHz, and the range's own edges, 10 MHz and 500 kHz (in spec).
OUT_OF_SPEC = [(0, S1, _cmd("PDC"), 20e6), (100, S1, 0, 20e6), (200, S3, _cmd("PAC"), 450e3), (300, S3, 0, 10e6),
               (400, S1, _cmd("E1"), 500e3), (500, S1, 0, 10e6)]


def _software_bus(harness):
    return Bus({n: SensorPort(s, n) for n, s in _sensors().items()})


def _rtl_bus(harness):
    from emulator.rtl.harness import RtlBus

    return RtlBus(_sensors(), harness=harness)


@pytest.mark.parametrize("make", [_software_bus, _rtl_bus], ids=["software bus", "RTL bus"])
def test_every_bus_counts_transfers_clocked_out_of_spec_alike(harness, make):
    """Transfers clocked outside 500 kHz–10 MHz (20 MHz, 450 kHz; the edges themselves are in spec) are served and
    counted in ``out_of_spec_transfers`` — 3 here, on every bus, by the word path and transfer by transfer — and
    the 20 MHz read arrives one bit late (PDC's word shifted right), the same words on every bus."""
    words = {}
    for path in ("words", "transfers"):
        bus = make(harness)
        try:
            if path == "words":
                us, cs, mosi, clock = (np.array(c) for c in zip(*OUT_OF_SPEC))
                got = bus.exchange_words(np.array([_at(u) for u in us]), cs, mosi.astype(np.uint16), clock)
            else:
                got = [bus.transfer(Transfer(_at(u), c, m, 16, f)) for u, c, m, f in OUT_OF_SPEC]
            words[path] = [int(w) for w in got]
            assert bus.out_of_spec_transfers == 3, path
        finally:
            bus.close()
    reference = _software_bus(harness)
    expected = [int(w) for w in reference.exchange_words(*(np.array(c) for c in (
        [_at(u) for u, *_ in OUT_OF_SPEC], [c for _, c, _, _ in OUT_OF_SPEC], [m for _, _, m, _ in OUT_OF_SPEC],
        [f for *_, f in OUT_OF_SPEC])))]
    assert words["words"] == words["transfers"] == expected
    from emulator.spi.peripheral import TransferBatch

    good = SensorPort(_sensors()[1], 1).exchange(  # what PDC's read carries at 10 MHz, sampled on time
        TransferBatch(np.array([_at(0), _at(100)]), np.array([_cmd("PDC"), 0], np.uint16), CLOCK_HZ))
    assert expected[1] == int(good[1]) >> 1 and not proto.is_error_word(good[1])


def _software_port(sensor, harness):
    return SensorPort(sensor, 1)


def _rtl_port(sensor, harness):
    from emulator.rtl.harness import HarnessPeripheral

    return HarnessPeripheral(sensor, harness)


@pytest.mark.parametrize("make", [_software_port, _rtl_port], ids=["software port", "RTL port"])
def test_every_lone_sensor_route_refuses_out_of_spec_clocks_alike_and_counts_as_its_port(harness, make):
    """A sensor alone on its bus (a scene's host: SensorPort.exchange, or the RTL's HarnessPeripheral) serves only
    clocks within 500 kHz–10 MHz: 20 MHz and 450 kHz are refused with the same message naming the transfer, the
    clock and the range, and nothing is played; in-spec traffic then counts on either route what the software port
    counts: a channel not provided (PAC), two conversions clocked into within 5 µs."""
    from emulator.spi.model import PORT_COUNTERS
    from emulator.spi.peripheral import TransferBatch

    port = make(_sensors()[1], harness)
    try:
        for bad in (20e6, 450e3):
            with pytest.raises(ValueError, match=rf"transfer #1 of the call: SCK {bad:.0f} Hz: must be "
                                                 rf"500000–10000000 Hz"):
                port.exchange(TransferBatch(np.array([_at(0), _at(100)]), np.array([_cmd("PDC"), 0], np.uint16),
                                            np.array([CLOCK_HZ, bad])))
        words = port.exchange(TransferBatch(np.array([_at(u) for u in (0, 2, 60, 100, 160, 300, 302, 360)]),
                                            np.array([_cmd("PDC"), 0, 0, _cmd("PAC"), 0, _cmd("E1"), 0, 0],
                                                     np.uint16), CLOCK_HZ))
        counts = {c: getattr(port, c) for c in PORT_COUNTERS}
    finally:
        getattr(port, "close", lambda: None)()
    err = proto.ERROR_WORDS
    assert words[0] == err["nothing_to_resend"]  # (the refused calls played nothing: no word prepared before)
    assert words[4] == err["channel_not_recognized"] and not proto.is_error_word(words[2])
    assert counts == {"incomplete": 0, "empty_windows": 0, "unprovided_requests": 1, "coupled_conversions": 2}


def test_a_clock_too_slow_for_the_harness_is_refused_by_name_and_plays_nothing(harness):
    """The harness takes an SCK half period in a signed 32-bit count of ps: a clock below about 233 Hz (here 100 Hz)
    would wrap it; the RTL bus refuses it naming the transfer, the clock and the least it clocks, counts nothing and
    plays on (the software bus serves it, out of spec)."""
    from emulator.rtl.harness import MIN_CLOCK_HZ, RtlBus

    bus = RtlBus(_sensors(), harness=harness)
    try:
        with pytest.raises(ValueError, match=r"transfer #0 of the call: SCK 100 Hz: the RTL harness clocks at least "
                                             r"233 Hz"):
            bus.transfer(Transfer(_at(0), S1, 0, 16, 100.0))
        assert bus.out_of_spec_transfers == 0
        assert bus.transfer(Transfer(_at(0), S1, 0, 16, MIN_CLOCK_HZ * 1.001)) == proto.ERROR_WORDS["nothing_to_resend"]
        assert bus.out_of_spec_transfers == 1
    finally:
        bus.close()
