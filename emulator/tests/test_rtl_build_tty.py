"""A build step runs in a process group of its own (:func:`emulator.rtl.build.run_build`), which is not the
terminal's foreground group: under ``stty tostop`` a process of a background group that writes to the terminal is
stopped (SIGTTOU), and the build waited for it for ever.  Its output goes through a pipe and this process writes it:
the step says what it says and ends, also on a terminal with ``tostop``."""

import contextlib
import os
import re
import select
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit

REPO = Path(__file__).resolve().parents[2]

#: The process under test, on a terminal (a pty) of its own as its foreground job, with ``tostop`` set: runs a
#: step that writes to its stdout and stderr.
HOST = textwrap.dedent("""
    import fcntl, sys, termios
    fcntl.ioctl(0, termios.TIOCSCTTY, 0)  # the pty becomes this session's terminal, this process its foreground job
    attrs = termios.tcgetattr(0)
    attrs[3] |= termios.TOSTOP
    termios.tcsetattr(0, termios.TCSANOW, attrs)
    from emulator.rtl.build import run_build
    r = run_build([sys.executable, "-c", "import sys; print('step out'); print('step err', file=sys.stderr)"])
    print("returncode", r.returncode, flush=True)
""")


def test_a_build_step_on_a_terminal_with_tostop_is_not_stopped_and_its_output_is_shown():
    master, slave = os.openpty()
    host = subprocess.Popen([sys.executable, "-c", HOST], cwd=REPO, stdin=slave, stdout=slave, stderr=slave,
                            start_new_session=True)
    os.close(slave)
    out, deadline = b"", time.monotonic() + 30
    try:
        while not re.search(rb"returncode -?\d+\r?\n", out) and time.monotonic() < deadline:
            if select.select([master], [], [], 0.2)[0]:
                try:
                    out += os.read(master, 4096)
                except OSError:  # (EIO: every writer has closed the pty)
                    break
    finally:
        if host.poll() is None:
            os.killpg(host.pid, 9)  # (a step stopped by SIGTTOU is orphaned: the kernel hangs it up)
        host.wait()
        os.close(master)
    text = out.decode(errors="replace")
    assert "returncode 0" in text, f"the build step never ended (stopped writing to the terminal?): {text!r}"
    assert "step out" in text and "step err" in text, text


def test_a_step_that_leaves_a_background_process_holding_its_output_ends_with_the_step(capfd):
    """The copying ends when the step ends, not when the last holder of its output does: a step leaving a process
    behind that keeps the output open (a daemon it started) returns at once (< 3 s wall, against the helper's
    20 s), what the step wrote before it ended still shown."""
    from emulator.rtl.build import run_build

    t0 = time.monotonic()
    r = run_build(["sh", "-c", "sleep 20 & echo helper $!; echo step done"])
    took = time.monotonic() - t0
    out = capfd.readouterr().out
    helper = re.search(r"helper (\d+)", out)
    if helper:
        with contextlib.suppress(ProcessLookupError):
            os.kill(int(helper.group(1)), 9)
    assert r.returncode == 0 and "step done" in out and helper, out
    assert took < 3.0, f"run_build waited {took:.1f} s for a process the step left behind"
