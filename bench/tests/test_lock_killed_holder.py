"""A lock (:func:`bench.atomic.take_lock`: the stage cache's entries, the out folders) whose holder was killed
(SIGKILL, the OOM killer: no chance to remove its lock file) is free at once: the next command takes it without
waiting, though the file is still there and names the dead holder's pid.  While the holder lives it is named."""

import os
import signal
import subprocess
import sys

import pytest

from bench.atomic import LockHeld, take_lock

pytestmark = pytest.mark.unit

HOLD = "import sys; from bench.atomic import take_lock; take_lock(sys.argv[1]); print('held', flush=True); " \
       "sys.stdin.read()"


def test_a_killed_holders_lock_is_taken_at_once_and_a_live_one_is_named(tmp_path):
    lock_path = tmp_path / ".entry.json.lock"
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(lock_path)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline() == "held\n"
        with pytest.raises(LockHeld) as refused:
            take_lock(lock_path)
        assert refused.value.holder == str(holder.pid)
        os.kill(holder.pid, signal.SIGKILL)
        holder.wait(timeout=10)
    finally:
        if holder.poll() is None:
            holder.kill()
            holder.wait()
        holder.stdin.close()
        holder.stdout.close()
    assert lock_path.read_text().strip() == str(holder.pid)  # left behind, naming the dead holder

    def never(who):
        raise AssertionError(f"waited for a dead holder (pid {who})")

    fd = take_lock(lock_path, wait=never)
    try:
        assert lock_path.read_text().strip() == str(os.getpid())
    finally:
        os.close(fd)
