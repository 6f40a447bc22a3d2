"""Wall time this process spends preparing the emulator's numba kernels, kept out of the bench's hang timers.

The kernels compile on their first call — inside the firmware's first steps, when numba's cache on disk is empty (a
fresh clone): seen once, 37 s on a loaded machine, long past :data:`bench.hosts.bridge.STOP_TIMEOUT_S`, and
``FirmwareBench.stop()`` reported the firmware as hung.  A timer that waits on the firmware counts only time no kernel
was being prepared (:func:`join_outside_compiles`), whatever kernel a scene needs and whenever it first runs.  numba
says when: it holds its compiler lock while it compiles a kernel or loads one from its cache, and announces each hold
as a ``numba:compiler_lock`` event.  (Measured here: a first step of 4.1 s from an empty cache, 0.04 s of it outside
the lock; 0.47 s with the cache filled, 0.05 s outside.)  Campaigns compile before their cases instead
(:func:`bench.campaigns.faults.compile_kernels`), so that their workers load the kernels from the cache and no host's
wait for a frame includes a compiler.
"""

from __future__ import annotations

import threading
import time

from numba.core import event


class _CompileClock(event.Listener):
    """Adds up the wall time (s) numba holds its compiler lock in this process (one thread at a time; a hold nested
    in another counts once; one under way when the clock began to listen — this module imported as another thread
    compiles — is not counted, and its end leaves the count as it was)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._depth = 0
        self._since = 0.0  # (monotonic s) when the hold under way began
        self._total_s = 0.0

    def on_start(self, ev) -> None:
        with self._lock:
            if not self._depth:
                self._since = time.monotonic()
            self._depth += 1

    def on_end(self, ev) -> None:
        with self._lock:
            if not self._depth:  # the end of a hold that began before this clock listened: not counted
                return
            self._depth -= 1
            if not self._depth:
                self._total_s += time.monotonic() - self._since

    def seconds(self) -> float:
        with self._lock:
            return self._total_s + (time.monotonic() - self._since if self._depth else 0.0)


_CLOCK = _CompileClock()
event.register("numba:compiler_lock", _CLOCK)


def compiling_s() -> float:
    """Wall time (s) this process has spent compiling numba kernels or loading them from the cache since this module
    was imported, counting one under way."""
    return _CLOCK.seconds()


def join_outside_compiles(thread: threading.Thread, timeout_s: float) -> None:
    """Wait for ``thread`` to end for at most ``timeout_s`` wall seconds not spent compiling or loading numba kernels
    (in any thread: numba's lock is held meanwhile, which the waited-on thread may be waiting for)."""
    began, compiled = time.monotonic(), compiling_s()
    while thread.is_alive():
        left = timeout_s - (time.monotonic() - began) + (compiling_s() - compiled)
        if left <= 0:
            return
        thread.join(left)
