"""Set-ups the host-stack tests share (here and in firmware_tests/tests): the bridge firmware run in virtual time
against given sensors and read through the driver's parser, and the Cheetah adapter opened from this process the
way a vendor-style program opens it.  Each test then states only what differs: its sensors, pattern, duration,
bus, what it asks of the adapter."""

from __future__ import annotations

import ctypes as C
from contextlib import contextmanager
from dataclasses import dataclass


@dataclass
class FirmwareRun:
    """What the host received from one run of the bridge firmware (:func:`run_firmware`)."""

    frames: list  # every data frame received, in order
    n_streamed: int  # how many of them came during the ``seconds`` asked for (before the STATUS request)
    status: object  # the last STATUS reply (a driver ``Status``; None when not asked for or none came)
    stats: object  # the driver parser's counters over everything received
    t_end: float  # virtual time (s) when the ``seconds`` asked for had passed


def run_firmware(sensors: dict, seconds: float, pattern=None, spi: str = "software", status: bool = True,
                 prepare=None) -> FirmwareRun:
    """The bridge firmware against ``sensors`` (number -> emulated sensor) in virtual time, in-memory UART, no
    threads (deterministic): start-up (it detects the sensors by their serial numbers), ``prepare(board)`` if given
    (faults, hooks on the bus), the sampling ``pattern`` if given (channel indices or names), START, ``seconds`` of
    streaming, then with ``status`` a STATUS request and 20 ms more.  ``spi``: "software" or "rtl"; the bus is
    closed at the end.  Everything the firmware sent goes through one driver parser."""
    from bench.hosts.cosim import CoSim, VirtualBoard
    from bench.hosts.driver import CMD_START, CMD_STATUS, DataFrame, FrameParser, Status, encode

    out = bytearray()
    board = VirtualBoard(sensors, uart_out=out.extend, spi=spi)
    try:
        sim = CoSim(board)
        if prepare is not None:
            prepare(board)
        if pattern is not None:
            sim.set_pattern(pattern)
        board.send_to_firmware(encode(CMD_START))
        sim.run(seconds)
        t_end, streamed = board.t, len(out)
        if status:
            board.send_to_firmware(encode(CMD_STATUS))
            sim.run(0.02)
    finally:
        board.bus.close()
    parser = FrameParser()
    before, after = parser.feed(bytes(out[:streamed]), now=0.0), parser.feed(bytes(out[streamed:]), now=0.0)
    frames = [x for x in before if isinstance(x, DataFrame)]
    replies = [x for x in before + after if isinstance(x, Status)]
    return FirmwareRun(frames + [x for x in after if isinstance(x, DataFrame)], len(frames),
                       replies[-1] if replies else None, parser.stats, t_end)


def open_adapter(lib, monkeypatch, cb, bitrate_khz: int | None = 4400) -> int:
    """Open the adapter ``cb`` (a CheetahBench) serves with cheetah.so ``lib`` loaded in this process: its socket
    in the environment, port 0 opened (handle 1, as on the device), the SPI clock set (None: left at the library's
    default).  Returns the handle."""
    monkeypatch.setenv("BIOTAC_CHEETAH_SOCKET", cb.socket_path)
    h = lib.c_ch_open(0)
    assert h == 1
    if bitrate_khz is not None:
        lib.c_ch_spi_bitrate(h, bitrate_khz)
    return h


@contextmanager
def cheetah_adapter(monkeypatch, *bench_args, bitrate_khz: int | None = 4400, **bench_kw):
    """A running ``CheetahBench(*bench_args, **bench_kw)`` and its adapter opened from this process
    (:func:`open_adapter`): yields (bench, library, handle); closes the handle, then stops the bench."""
    from bench.hosts.cheetah_server import CheetahBench

    with CheetahBench(*bench_args, **bench_kw) as cb:
        lib = C.CDLL(str(cb.library))
        h = open_adapter(lib, monkeypatch, cb, bitrate_khz)
        try:
            yield cb, lib, h
        finally:
            lib.c_ch_close(h)


def _command_then_read(lib, h, select: int, command: tuple[int, int], wait_ns: int, n_read: int) -> bytes:
    """The vendor library's exchange: the two command bytes, ``wait_ns``, then ``n_read`` bytes with select held;
    returns the bytes read."""
    buf = (C.c_uint8 * (2 + n_read))()
    lib.c_ch_spi_queue_clear(h)
    lib.c_ch_spi_queue_ss(h, select)
    lib.c_ch_spi_queue_array(h, 2, (C.c_uint8 * 2)(*command))
    lib.c_ch_spi_queue_ss(h, 0)
    lib.c_ch_spi_queue_delay_ns(h, wait_ns)
    lib.c_ch_spi_queue_ss(h, select)
    lib.c_ch_spi_queue_byte(h, n_read, 0x00)
    lib.c_ch_spi_queue_ss(h, 0)
    assert lib.c_ch_spi_batch_shift(h, 2 + n_read, buf) == 2 + n_read
    return bytes(buf[2:])


def read_serial(lib, h, select: int = 1) -> bytes:
    """The serial-number property (0x15) of the sensor at chip-select code ``select`` as the vendor library reads
    it: command, 60 µs, then 18 bytes with select held; returns those 18 bytes (the serial, then padding)."""
    from emulator.spi.model import PROP_SERIAL

    return _command_then_read(lib, h, select, (0x61, PROP_SERIAL), 60000, 18)


def read_sample(lib, h, channel: str, select: int = 1) -> int:
    """One sample of ``channel`` from the sensor at chip-select code ``select`` (0x01, 0x02, 0x04 for sensors 1..3)
    as vendor host code reads it: the sampling command, 50 µs, the 16-bit read; its parity must hold."""
    import numpy as np

    from emulator.channels import channel_index
    from emulator.spi import protocol as proto

    word = _command_then_read(lib, h, select, (int(proto.sample_command(channel_index(channel))), 0x00), 50000, 2)
    value, ok = proto.decode_response(np.array([int.from_bytes(word, "big")], np.uint16))
    assert ok.all()
    return int(value[0])
