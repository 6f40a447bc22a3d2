"""The bench's command line as users run it, shared by the tests here and in firmware_tests/tests: ``biotac-bench``
(``python -m bench.cli``) in a subprocess from the repository root."""

from __future__ import annotations

import subprocess
import sys

from bench.paths import REPO

CLI = [sys.executable, "-m", "bench.cli"]


def run_cli(*args, timeout: float = 120, **kw) -> subprocess.CompletedProcess:
    """``biotac-bench ARGS`` (each argument str()-ed) to its end: exit status, stdout and stderr as text.
    ``kw`` goes to :func:`subprocess.run` (``env``, ``input``...)."""
    return subprocess.run([*CLI, *map(str, args)], capture_output=True, text=True, timeout=timeout, cwd=REPO, **kw)
