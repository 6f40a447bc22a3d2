"""A pty that any program can open as a serial port, fed by the firmware's UART through a finite receive buffer.

Both ends are put in raw mode (no line editing or echo).  The slave end stays open on our side so writes never
fail for want of a reader; reading the master after the other side closes raises EIO, which is reported as a
disconnect.  DTR/RTS ioctls are not supported on ptys; open the port with rtscts/dsrdtr off.

**The receive buffer.**  A real UART link has no flow control here (the bridge firmware uses none): bytes the
host has not read wait in a finite receive buffer, and when it is full, further bytes are lost (an overrun)
while the sender carries on.  :class:`PtyLink` models that buffer: :data:`RX_BUFFER_BYTES` = 4096 bytes (a
model choice, the size of Linux's N_TTY read buffer; ``rx_buffer=`` changes it) hold whatever the host has not
read yet — the bytes waiting in our FIFO plus those already handed to the pty and not read (``FIONREAD`` on the
pty; at most :data:`PTY_WINDOW` bytes are handed over at a time, so the kernel's own, larger, pty buffer does
not add capacity).  :meth:`deliver` takes the bytes arriving from the line: what fits is kept, the rest is
dropped and recorded (``bytes_overrun``, ``overruns`` as (stream offset, length)).  :meth:`pump` moves kept
bytes on to the pty as the host reads.

**The fill count lags.**  Bytes written to the pty's master wait in the kernel's flip buffer until a kernel
worker moves them into the slave's read buffer, and ``FIONREAD`` counts only the latter: right after a write it
misses those bytes (measured: in 43 % of writes; for µs on an idle machine, for ms when the worker is late, with
up to 5 kB in flight while ``FIONREAD`` read 0).  So :meth:`room` can shrink with no new byte arriving, and the
window can briefly hold more than :data:`PTY_WINDOW`.  A sender that waited for room (the unpaced bench, which
waits for a host that reads) therefore delivers with ``keep_all=True``: the bytes the lag made not fit wait in
the FIFO (which may then briefly exceed the buffer) and go to the pty as the host reads; nothing is dropped.
Paced (no waiting, as a real UART), what does not fit is an overrun.
"""

from __future__ import annotations

import errno
import fcntl
import os
import select
import struct
import termios
import time
import tty
from collections import deque

#: The receive buffer (bytes): what the host may leave unread before the UART overruns.
RX_BUFFER_BYTES = 4096
#: At most this many bytes sit in the pty unread (the rest of the receive buffer waits in our FIFO).
PTY_WINDOW = 1024


class PtyLink:
    def __init__(self, baudrate: int = 3_000_000, rx_buffer: int = RX_BUFFER_BYTES, keep_arrivals: bool = False):
        if rx_buffer < PTY_WINDOW:
            raise ValueError(f"rx_buffer = {rx_buffer}: at least {PTY_WINDOW} bytes")
        self.master, self._slave = os.openpty()
        for fd in (self.master, self._slave):
            tty.setraw(fd)
        attrs = termios.tcgetattr(self._slave)
        speed = getattr(termios, f"B{baudrate}", termios.B115200)
        attrs[4] = attrs[5] = speed
        termios.tcsetattr(self._slave, termios.TCSANOW, attrs)
        os.set_blocking(self.master, False)
        self.path = os.ttyname(self._slave)
        self.rx_buffer = rx_buffer
        self.closed = False
        self.bytes_out = 0  # handed to the pty (the host can read them)
        self.bytes_in = 0  # arrived from the line (kept or not): offsets in ``overruns`` count these
        self.bytes_overrun = 0
        self.overruns: list[tuple[int, int]] = []  # (offset of the first lost byte, how many), merged when adjacent
        self.arrivals = bytearray() if keep_arrivals else None  # every arriving byte, for tests that count losses
        self._fifo: deque[bytes] = deque()
        self._fifo_len = 0

    # --- the receive buffer ----------------------------------------------------------------------------------
    def unread_in_pty(self) -> int:
        """Bytes handed to the pty that the host has not read (0 once the link is closed)."""
        if self.closed:
            return 0
        try:
            return struct.unpack("i", fcntl.ioctl(self._slave, termios.FIONREAD, b"\0\0\0\0"))[0]
        except OSError:
            return 0

    def occupancy(self) -> int:
        """Bytes in the receive buffer: not yet read by the host."""
        return self._fifo_len + self.unread_in_pty()

    def room(self) -> int:
        return max(0, self.rx_buffer - self.occupancy())

    def deliver(self, data: bytes, keep_all: bool = False) -> int:
        """Bytes arriving from the line: keep what fits in the receive buffer, drop (and record) the rest — or,
        with ``keep_all`` (a sender that waited for room: see the module's docstring), keep every byte.
        Returns how many were kept."""
        if not data:
            return 0
        if self.arrivals is not None:
            self.arrivals += data
        self.pump()
        keep = len(data) if keep_all else min(len(data), self.room())
        if keep:
            self._fifo.append(bytes(data[:keep]))
            self._fifo_len += keep
        lost = len(data) - keep
        if lost:
            start = self.bytes_in + keep
            if self.overruns and sum(self.overruns[-1]) == start:
                self.overruns[-1] = (self.overruns[-1][0], self.overruns[-1][1] + lost)
            else:
                self.overruns.append((start, lost))
            self.bytes_overrun += lost
        self.bytes_in += len(data)
        self.pump()
        return keep

    def pump(self) -> None:
        """Hand buffered bytes to the pty while the host has room for them in the window."""
        if self.closed or not self._fifo:
            return
        space = PTY_WINDOW - self.unread_in_pty()
        while self._fifo and space > 0:
            chunk = self._fifo[0]
            n = self._write(chunk[:space])
            if n <= 0:
                return
            if n < len(chunk):
                self._fifo[0] = chunk[n:]
            else:
                self._fifo.popleft()
            self._fifo_len -= n
            space -= n

    def _write(self, data: bytes) -> int:
        try:
            n = os.write(self.master, data)
        except BlockingIOError:
            return 0
        except OSError as e:
            if e.errno in (errno.EIO, errno.EBADF):  # the pty is going away (the link is closing)
                return 0
            raise
        self.bytes_out += n
        return n

    def write(self, data: bytes) -> None:
        """Bytes toward whoever opened the port (through the receive buffer)."""
        self.deliver(data)

    def wait_for_room(self, n: int, give_up_s: float, stop=None) -> bool:
        """Pump until ``n`` bytes fit (True), or ``give_up_s`` passes or ``stop`` is set (False)."""
        deadline = time.monotonic() + give_up_s
        n = min(n, self.rx_buffer)
        while self.room() < n:
            if self.closed or time.monotonic() >= deadline or (stop is not None and stop.is_set()):
                return False
            self.pump()
            if self.room() >= n:
                break
            time.sleep(0.0005)
        return True

    # --- the other direction ---------------------------------------------------------------------------------
    def read_available(self) -> bytes:
        """Bytes the host wrote toward the firmware (non-blocking)."""
        out = b""
        while not self.closed and select.select([self.master], [], [], 0)[0]:
            try:
                chunk = os.read(self.master, 4096)
            except BlockingIOError:
                break
            except OSError as e:
                if e.errno == errno.EIO:  # the pty is going away (the link is closing)
                    break
                raise
            if not chunk:
                break
            out += chunk
        return out

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        for fd in (self.master, self._slave):
            try:
                os.close(fd)
            except OSError:
                pass
