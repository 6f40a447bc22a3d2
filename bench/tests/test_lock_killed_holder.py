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


#: a holder driven line by line on stdin: "take" the lock; "swap": remove the lock file and take a new one before
#: letting go of the old (a holder that releases the lock and takes it again before a waiter can); "unlink" the
#: file, keeping the lock; "close" the lock; "release" it (release_lock).  Says "done" after each.
DRIVEN = """
import os, sys
from bench.atomic import release_lock, take_lock
path, fd = sys.argv[1], None
for line in sys.stdin:
    what = line.strip()
    if what == "take":
        fd = take_lock(path)
    elif what == "swap":
        os.unlink(path)
        new = take_lock(path)
        os.close(fd)
        fd = new
    elif what == "unlink":
        os.unlink(path)
    elif what == "close":
        os.close(fd)
    elif what == "release":
        release_lock(fd, path)
    print("done", flush=True)
"""


def _blocked_on(path) -> bool:
    """Whether a process waits for the flock of the file now at ``path`` (/proc/locks: "->" marks a waiter)."""
    inode = str(os.stat(path).st_ino)
    with open("/proc/locks") as f:
        return any("->" in line and line.split()[-3].split(":")[-1] == inode for line in f.read().splitlines())


def test_a_waiter_says_whom_it_waits_for_once_and_again_only_when_the_holder_changes(tmp_path):
    """take_lock(wait=...) tells its caller once per holder: holder A taking the lock again (a new lock file) before
    the waiter gets it is not news (it was said again each time); the lock passing to B is, and B is named."""
    import threading
    import time

    lock_path = tmp_path / ".entry.json.lock"
    holders = [subprocess.Popen([sys.executable, "-c", DRIVEN, str(lock_path)], stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, text=True) for _ in range(2)]
    a, b = holders

    def do(holder, what: str) -> None:
        holder.stdin.write(what + "\n")
        holder.stdin.flush()
        assert holder.stdout.readline() == "done\n"

    def until(condition) -> None:
        deadline = time.monotonic() + 20
        while not condition():
            assert time.monotonic() < deadline, "the waiter never got there"
            time.sleep(0.005)

    told, got = [], []
    waiter = threading.Thread(target=lambda: got.append(take_lock(lock_path, wait=told.append)), daemon=True)
    try:
        do(a, "take")
        waiter.start()
        until(lambda: _blocked_on(lock_path))
        assert told == [str(a.pid)]
        for _ in range(2):  # A lets go and takes it again, twice: the waiter keeps waiting, silently
            do(a, "swap")
            until(lambda: _blocked_on(lock_path))
        assert told == [str(a.pid)]
        do(a, "unlink")  # now B takes a new lock file before A lets go: the waiter waits for B, and says so
        do(b, "take")
        do(a, "close")
        until(lambda: _blocked_on(lock_path))
        assert told == [str(a.pid), str(b.pid)]
        do(b, "release")
        waiter.join(20)
        assert got and lock_path.read_text().strip() == str(os.getpid())
        os.close(got[0])
    finally:
        for holder in holders:
            holder.stdin.close()
            holder.wait(timeout=10)
            holder.stdout.close()
