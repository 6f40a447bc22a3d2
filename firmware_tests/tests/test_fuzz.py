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
