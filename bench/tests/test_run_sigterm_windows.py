"""SIGTERM reaching `run` outside the run's own signal guard ends it as Ctrl-C there does: before the guard (the out
folder made and locked, nothing run), "terminated", exit status 143 and the folder the command made removed; after
it (every file written, the summary printing), a line saying the folder holds them all, exit status 143 — never a
silent death by the signal (a folder holding only the lock left behind, or a finished run told as nothing)."""

import subprocess
import sys

import pytest

from bench.paths import REPO
from bench.tests.test_outputs import check_consistent

pytestmark = pytest.mark.unit

#: `run` in a process of its own that sends itself SIGTERM at one moment: argv[1] says which, the rest is run's
SIGTERM_AT = """
import os, signal, sys
from bench.cli import scenes
from bench.reporting.outdir import OutFolder

def sigterm_after(owner, name):
    original = getattr(owner, name)

    def call(*a, **kw):
        result = original(*a, **kw)
        os.kill(os.getpid(), signal.SIGTERM)
        return result

    setattr(owner, name, call)

if sys.argv[1] == "folder-locked":  # the out folder made, locked and checked; the run not started
    sigterm_after(OutFolder, "_prepare")
else:  # "summary": every file written, the summary being printed
    sigterm_after(scenes, "_print_run")
from bench.cli.main import main
sys.exit(main(sys.argv[2:]))
"""


def _run_with_sigterm_at(moment: str, out) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", SIGTERM_AT, moment, "run", "rest", "--out", str(out), "--quiet",
                           "--no-plots"], capture_output=True, text=True, cwd=REPO, timeout=300)


def test_sigterm_before_the_run_starts_says_terminated_and_removes_the_folder_it_made(tmp_path):
    out = tmp_path / "o"
    proc = _run_with_sigterm_at("folder-locked", out)
    assert "Traceback" not in proc.stderr
    assert (proc.returncode, proc.stderr.strip()) == (143, "terminated")
    assert not out.exists()  # made by the command, held only its lock


def test_sigterm_after_every_file_is_written_says_the_folder_holds_them_all(tmp_path):
    out = tmp_path / "o"
    proc = _run_with_sigterm_at("summary", out)
    assert "Traceback" not in proc.stderr and proc.returncode == 143, proc.stderr
    assert (f"SIGTERM after the run's files were written: {out}/ holds them all (record.json status \"ok\")"
            in proc.stderr)
    check_consistent(out, "ok")
