"""Unpaced, nothing is lost while the host reads, even when the pty's fill count lags the kernel.

Bytes written to the pty's master reach the count the link reads (``FIONREAD`` on the slave) only once a kernel
worker has moved them through: for µs on an idle machine, for ms on a busy one.  Until then the link sees more room
than there is, and when the bytes show up, the room it found while deciding is gone.  The unpaced bench used to
drop what no longer fitted (a dropped frame on a clean line, now and then, on a busy machine); it now keeps it in
the link's FIFO and hands it over as the host reads.  Paced, a host that stops reading still loses what does not
fit, as a real UART does.  Here the lag is made deterministic, at its worst timing (:class:`LateKernelWorker`).
"""

import os
import time

import pytest

from bench.hosts.bridge import HOST_GONE_S, FirmwareBench
from bench.hosts.driver import CMD_START, FrameParser, encode
from bench.hosts.serial_link import RX_BUFFER_BYTES, PtyLink

pytestmark = pytest.mark.firmware
#: The slow host's pauses (wall s).
STALL_S = 0.03
#: How long the bench waits for the slow host (wall s): long against STALL_S and against the few hundred ms a loaded
#: machine may stall this process, so the host is never taken as gone (with the default HOST_GONE_S, 0.2 s, it
#: once was, under heavy load).
PATIENCE_S = 5.0


class LateKernelWorker:
    """Makes the link's fill count (``unread_in_pty``) miss every byte written to the pty until the next bytes
    arrive from the line (``deliver``): the worst timing of the kernel worker that moves them through.  The count
    never exceeds what the pty holds, only falls short of it, as the real one does while bytes are in flight."""

    def __init__(self, link: PtyLink):
        self.in_flight = 0  # bytes written to the pty that the count does not show yet
        self._write, self._unread, self._deliver = link._write, link.unread_in_pty, link.deliver
        link._write, link.unread_in_pty, link.deliver = self.write, self.unread, self.deliver

    def write(self, data: bytes) -> int:
        n = self._write(data)
        self.in_flight += max(n, 0)
        return n

    def unread(self) -> int:
        return max(0, self._unread() - self.in_flight)

    def deliver(self, *args, **kwargs) -> int:
        self.in_flight = 0  # the worker has run: the count shows them now
        return self._deliver(*args, **kwargs)


def _slow_host(fb: FirmwareBench, frames: int, bite: int = 50) -> tuple[FrameParser, list]:
    """A host that reads ``bite`` bytes every ms (50 kB/s, slower than the unpaced firmware sends) and pauses
    :data:`STALL_S` every 100 reads, until it has ``frames`` frames (or 60 s passed): the receive buffer stays
    full, and the bench waits for room and finds it a few bytes at a time, again and again.  Returns the host's parser and the link's overruns
    before the host closes the port (a closed port is a host gone, which may lose bytes)."""
    fd = os.open(fb.port, os.O_RDWR | os.O_NOCTTY)
    parser = FrameParser()
    try:
        os.write(fd, encode(CMD_START))
        end, reads = time.monotonic() + 60, 0
        while parser.stats.frames < frames and time.monotonic() < end:
            parser.feed(os.read(fd, bite))
            reads += 1
            time.sleep(STALL_S if reads % 100 == 0 else 0.001)
        return parser, list(fb.link.overruns)
    finally:
        os.close(fd)


def test_an_overrun_starts_after_the_bytes_that_fit_and_grows_while_the_buffer_stays_full():
    """The receive buffer keeps what fits of a delivery and loses the rest: the overrun's offset (bytes since the
    link opened) is where the loss starts, after the bytes kept, and losses that follow each other are one range
    (the module's docstring: "merged when adjacent").  ``overrun_frames()`` finds the frames hit from these offsets.
    (A mutation hunt: an offset at the delivery's first byte, and a list that never merged, passed.)"""
    link = PtyLink(rx_buffer=RX_BUFFER_BYTES)  # nobody reads: the buffer fills
    try:
        assert link.deliver(bytes(RX_BUFFER_BYTES - 10)) == RX_BUFFER_BYTES - 10
        deadline = time.monotonic() + 5
        while link.room() != 10 and time.monotonic() < deadline:  # the kernel moves the bytes through the pty
            time.sleep(0.001)
        assert link.room() == 10
        assert link.deliver(bytes(14)) == 10  # 10 fit, the last 4 are lost
        assert link.overruns == [(RX_BUFFER_BYTES, 4)]
        assert link.deliver(bytes(6)) == 0
        assert link.overruns == [(RX_BUFFER_BYTES, 10)] and link.bytes_overrun == 10
    finally:
        link.close()


def test_the_link_keeps_every_byte_of_a_sender_that_waited_and_drops_the_excess_otherwise():
    link = PtyLink(rx_buffer=RX_BUFFER_BYTES)
    host = os.open(link.path, os.O_RDWR | os.O_NOCTTY)
    try:
        os.set_blocking(host, False)
        sent = bytes(range(256)) * (RX_BUFFER_BYTES // 256)
        assert link.deliver(sent) == RX_BUFFER_BYTES
        deadline = time.monotonic() + 5
        while link.room() and time.monotonic() < deadline:  # the kernel moves the bytes through the pty
            time.sleep(0.001)
        assert link.room() == 0
        assert link.deliver(b"late", keep_all=True) == 4  # the sender waited: kept although the count says full
        assert link.bytes_overrun == 0
        assert link.deliver(b"lost") == 0  # no waiting (paced): an overrun
        assert link.overruns == [(RX_BUFFER_BYTES + 4, 4)]
        got = b""
        deadline = time.monotonic() + 5
        while len(got) < len(sent) + 4 and time.monotonic() < deadline:
            link.pump()
            try:
                got += os.read(host, 4096)
            except BlockingIOError:
                time.sleep(0.001)
        assert got == sent + b"late"  # in order, nothing lost or repeated
    finally:
        os.close(host)
        link.close()


def test_unpaced_a_slow_host_loses_no_frame_while_the_fill_count_lags():
    fb = FirmwareBench(1, keep_arrivals=True, host_gone_s=PATIENCE_S)
    LateKernelWorker(fb.link)
    with fb:
        parser, overruns = _slow_host(fb, frames=300)
    st = parser.stats
    assert overruns == [], f"bytes dropped while the host was reading: {overruns}"
    assert st.frames >= 300, "the host read too little to exercise the buffer"
    assert (st.dropped_frames, st.crc_errors, st.bytes_skipped) == (0, 0, 0)
    assert STALL_S < HOST_GONE_S < PATIENCE_S


def test_paced_a_host_that_stops_reading_still_loses_what_does_not_fit():
    """The fix is unpaced only: paced, the firmware does not wait, and a stalled host overruns the buffer (with
    the lagging count too), exactly in the frames ``overrun_frames()`` lists."""
    fb = FirmwareBench(1, realtime=True, keep_arrivals=True)
    LateKernelWorker(fb.link)
    with fb:
        fd = os.open(fb.port, os.O_RDWR | os.O_NOCTTY)
        parser = FrameParser()
        try:
            os.write(fd, encode(CMD_START))
            while parser.stats.frames < 20:
                parser.feed(os.read(fd, 4096))
            time.sleep(1.0)  # 100 frames of 143 bytes (14.3 kB) against a 4096-byte buffer
            while parser.stats.frames < 150:
                parser.feed(os.read(fd, 4096))
        finally:
            os.close(fd)
        lost = fb.overrun_frames()
    assert fb.link.bytes_overrun > 5000 and len(lost) > 30
    assert parser.stats.dropped_frames == len([s for s in lost if s <= parser.stats.last_seq])


def test_a_sender_with_more_than_the_buffer_waits_only_until_the_buffer_is_empty():
    """More bytes than the receive buffer holds can never all find room: ``wait_for_room`` then waits for the
    buffer to be empty (all the room there is) and says so, rather than waiting out ``give_up_s`` and reporting no
    room — which the unpaced bench would take for a host that is gone, and drop bytes."""
    link = PtyLink(rx_buffer=RX_BUFFER_BYTES)
    try:
        t0 = time.monotonic()
        assert link.wait_for_room(3 * RX_BUFFER_BYTES, give_up_s=5.0)
        assert time.monotonic() - t0 < 1.0
    finally:
        link.close()

