"""stop() does not take the emulator's numba kernels compiling for a hung firmware (bench/hosts/compile_clock.py).

In a fresh clone (numba's cache on disk empty) the kernels compile inside the firmware's first steps: seen once, 37 s
on a loaded machine, and ``FirmwareBench.stop()``, which waits :data:`bench.hosts.bridge.STOP_TIMEOUT_S` for the
step to end, reported the firmware as hung.  The case runs in a process of its own with a cache directory of its own
(``NUMBA_CACHE_DIR``), so it starts as a fresh clone does, with a hang timeout of 0.5 s (the first step's work outside
numba's compiler is a tenth of that)."""

import json
import os
import subprocess
import sys

import pytest

from bench.paths import REPO

pytestmark = pytest.mark.firmware

#: a bench whose host sends START, stopped as its first step compiles; what stop() said, and how long (wall s) the
#: process compiled while stop() waited
CHILD = """
import json, os, time
from bench.hosts import bridge
from bench.hosts.compile_clock import compiling_s
from bench.hosts.driver import CMD_START, encode

bridge.STOP_TIMEOUT_S = 0.5
fb = bridge.FirmwareBench(n_sensors=1).start()
host = os.open(fb.port, os.O_RDWR | os.O_NOCTTY)
idle = compiling_s()
os.write(host, encode(CMD_START))
deadline = time.monotonic() + 60
while compiling_s() == idle and time.monotonic() < deadline:  # (until the first step starts compiling)
    time.sleep(0.001)
before = compiling_s()
try:
    fb.stop()
    said = "stopped"
except Exception as e:
    said = f"{type(e).__name__}: {e}"
os.close(host)
print(json.dumps({"said": said, "compiled_while_stopping_s": compiling_s() - before}))
"""


def test_stop_while_the_first_step_compiles_kernels_is_not_a_hung_firmware(tmp_path):
    """stop() asked while the first step compiles (from an empty cache) waits for the compilation beyond its 0.5 s
    timeout and ends as usual, the firmware not reported hung.  It counted the compiler's time: FirmwareError "the
    firmware did not return from bt_step within 0.5 s"."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(REPO)}
    done = subprocess.run([sys.executable, "-c", CHILD], cwd=REPO, env=env, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["compiled_while_stopping_s"] > 0.5, result  # (the compilation outlasted the timeout)
    assert result["said"] == "stopped", result


def test_a_compile_under_way_as_the_clock_starts_listening_leaves_it_counting_right():
    """A compile clock that starts listening while numba's compiler lock is held (bench.hosts.bridge imported as
    another thread compiles) sees that hold end without its start: the clock ignores it, stands still while no
    kernel compiles and counts the next hold.  It used to go below zero holds and from then on count every wall
    second as compiling: a hung firmware's stop() then waited forever.  (numba's real lock, its real events.)"""
    import time

    from numba.core import event
    from numba.core.compiler_lock import global_compiler_lock

    from bench.hosts.compile_clock import _CompileClock

    clock = _CompileClock()
    global_compiler_lock.acquire()  # (a hold under way before the clock listens)
    event.register("numba:compiler_lock", clock)
    try:
        global_compiler_lock.release()
        idle = clock.seconds()
        time.sleep(0.2)
        assert clock.seconds() == idle == 0.0, "the clock counts while nothing compiles"
        with global_compiler_lock:
            time.sleep(0.1)
        held = clock.seconds()
        time.sleep(0.2)
        assert held == clock.seconds() and held >= 0.1
    finally:
        event.unregister("numba:compiler_lock", clock)
