"""A pty that any program can open as a serial port, fed by the firmware's UART.

Both ends are put in raw mode (no line editing or echo).  The slave end stays open on our side so writes
never fail for want of a reader; reading the master after the other side closes raises EIO, which is
reported as a disconnect.  DTR/RTS ioctls are not supported on ptys; open the port with rtscts/dsrdtr off.
"""

from __future__ import annotations

import errno
import os
import select
import termios
import tty


class PtyLink:
    def __init__(self, baudrate: int = 3_000_000):
        self.master, self._slave = os.openpty()
        for fd in (self.master, self._slave):
            tty.setraw(fd)
        attrs = termios.tcgetattr(self._slave)
        speed = getattr(termios, f"B{baudrate}", termios.B115200)
        attrs[4] = attrs[5] = speed
        termios.tcsetattr(self._slave, termios.TCSANOW, attrs)
        self.path = os.ttyname(self._slave)
        self.disconnected = False
        self.bytes_out = 0

    def write(self, data: bytes) -> None:
        """Bytes from the firmware's UART toward whoever opened the port."""
        view = memoryview(data)
        while view:
            try:
                n = os.write(self.master, view)
            except OSError as e:
                if e.errno in (errno.EIO, errno.EBADF):
                    self.disconnected = True
                    return
                raise
            view = view[n:]
            self.bytes_out += n

    def read_available(self) -> bytes:
        """Bytes the host wrote toward the firmware (non-blocking)."""
        out = b""
        while select.select([self.master], [], [], 0)[0]:
            try:
                chunk = os.read(self.master, 4096)
            except OSError as e:
                if e.errno == errno.EIO:
                    self.disconnected = True
                    break
                raise
            if not chunk:
                break
            out += chunk
        return out

    def close(self) -> None:
        for fd in (self.master, self._slave):
            try:
                os.close(fd)
            except OSError:
                pass
