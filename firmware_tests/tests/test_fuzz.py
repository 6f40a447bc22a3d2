"""The driver's frame parser and the firmware's command parser survive random bytes (100 000+ inputs each):
no crash, no hang, errors counted, and good frames after the garbage are still decoded."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bench.hosts.cosim import CoSim, VirtualBoard, default_sensors
from bench.hosts.driver import CMD_START, CMD_STATUS, DataFrame, FrameParser, Status, encode

pytestmark = pytest.mark.firmware


def good_data_frame(seq: int) -> bytes:
    payload = bytes([seq & 0xFF, seq >> 8, 0b1, 2]) + bytes([0, 0x00, 0x08, 1, 0x34, 0x02])
    return encode(0x10, payload)


def test_parser_survives_100000_random_inputs_and_then_decodes_good_frames():
    rng = np.random.default_rng(7)
    parser = FrameParser()
    for k in range(100_000):
        n = int(rng.integers(0, 40))
        junk = rng.integers(0, 256, n, dtype=np.uint8).tobytes()
        if k % 97 == 0:  # sometimes a plausible header with a wild length or a broken CRC
            junk = b"\xaa\x55" + bytes([0x10]) + rng.integers(0, 256, 4, dtype=np.uint8).tobytes()
        parser.feed(junk)
    got = parser.feed(b"".join(good_data_frame(s) for s in range(5)))
    frames = [f for f in got if isinstance(f, DataFrame)]
    assert [f.seq for f in frames][-3:] == [2, 3, 4]  # the first may be swallowed by a pending partial frame
    assert frames[-1].codes.tolist() == [[2048], [0x234]]
    assert parser.stats.bytes_skipped > 1_000_000


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=300), st.integers(0, 4))
def test_any_bytes_then_a_good_frame_decode_it(junk, n_good):
    parser = FrameParser()
    parser.feed(junk)
    got = parser.feed(b"\x00" * 300 + b"".join(good_data_frame(s) for s in range(n_good + 2)))
    seqs = [f.seq for f in got if isinstance(f, DataFrame)]
    assert seqs[-1] == n_good + 1


def test_firmware_command_parser_survives_100000_random_bytes():
    out = bytearray()
    board = VirtualBoard(default_sensors(1), uart_out=out.extend)
    sim = CoSim(board)
    rng = np.random.default_rng(11)
    garbage = rng.integers(0, 256, 100_000, dtype=np.uint8).tobytes().replace(b"\xaa\x55\x01", b"\xaa\x54\x01")
    board.send_to_firmware(garbage)
    sim.run(0.5, max_steps=100_000)  # bounded: a hang would raise instead of blocking
    assert len(board.uart_in) == 0  # everything was consumed
    board.send_to_firmware(encode(CMD_STATUS))
    sim.run(0.01, max_steps=1000)
    items = FrameParser().feed(bytes(out))
    status = [i for i in items if isinstance(i, Status)][-1]
    assert status.command_errors > 1000 and not status.streaming
    board.send_to_firmware(encode(CMD_START))
    sim.run(0.1, max_steps=1000)
    assert any(isinstance(i, DataFrame) for i in FrameParser().feed(bytes(out)))


_CHANNEL = st.sampled_from([0, 1, 2, 3, *range(17, 36)])
_COMMAND = st.one_of(
    st.sampled_from([(0x01, b""), (0x02, b""), (0x04, b"")]),
    st.lists(_CHANNEL, min_size=1, max_size=64).map(lambda c: (0x03, bytes(c))),
    st.lists(_CHANNEL, min_size=65, max_size=100).map(lambda c: (0x03, bytes(c))),  # too long: ACK 1
)
_GARBAGE = st.one_of(
    st.binary(max_size=40),
    # a header whose length is wild (up to 65 535) or just within the buffer, cut short or left to the next bytes
    st.tuples(st.integers(0, 255), st.one_of(st.integers(0, 64), st.integers(65, 0xFFFF)), st.binary(max_size=8))
    .map(lambda h: b"\xaa\x55" + bytes([h[0], h[1] & 0xFF, h[1] >> 8]) + h[2]),
)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(_GARBAGE, _COMMAND), min_size=1, max_size=6), st.integers(1, 80))
def test_every_command_behind_any_garbage_is_answered_in_order(traffic, chunk):
    """Commands with garbage before each (random bytes, or a header announcing any length, cut short), arriving in
    pieces of ``chunk`` bytes: the firmware answers every command, in order, each as it must (ACK 0, ACK 1 for a
    pattern too long, or STATUS)."""
    out = bytearray()
    board = VirtualBoard(default_sensors(1), uart_out=out.extend)
    sim = CoSim(board)
    data = b"".join(garbage + encode(ctype, payload) for garbage, (ctype, payload) in traffic)
    for k in range(0, len(data), chunk):
        board.send_to_firmware(data[k:k + chunk])
        sim.run(0.0005, max_steps=1000)
    sim.run(0.002, max_steps=1000)
    replies = [i for i in FrameParser().feed(bytes(out), now=0.0) if not isinstance(i, DataFrame)]
    expected = [Status if ctype == CMD_STATUS else ("ack", ctype, int(len(payload) > 64))
                for _, (ctype, payload) in traffic]
    assert [Status if isinstance(r, Status) else r for r in replies] == expected
