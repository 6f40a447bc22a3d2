"""Building the C parts of the bench (bridge firmware, cheetah.so, the example client) with the system compiler.

Builds are cached in folders named after a hash of their inputs, and each output is written under a temporary
name of its own (per process and thread) and moved into place, so an interrupted build never leaves a half-written
library behind, and builds of the same output at once (the threads of a Dask worker running fault-campaign cases)
each finish, the last one's rename winning with identical contents.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import threading
from pathlib import Path

from bench.errors import BuildError

C_FLAGS = ("-std=c11", "-O2", "-Wall", "-Wextra", "-Werror")


def build_folder(root: Path, inputs) -> Path:
    """``root/<hash>``: one folder per distinct set of input files (their contents, in order)."""
    digest = hashlib.sha256()
    for path in inputs:
        digest.update(Path(path).read_bytes())
    return Path(root) / digest.hexdigest()[:12]


def compile_c(sources, output: Path, flags=(), libs=(), what: str = "C code") -> Path:
    """Compile C11 ``sources`` into ``output`` (an executable, or a library with ``-shared -fPIC`` in flags).

    Does nothing if ``output`` exists: callers put it in a :func:`build_folder` so changed inputs get a new one.
    """
    output = Path(output)
    if output.exists():
        return output
    output.parent.mkdir(parents=True, exist_ok=True)
    partial = output.with_name(f".{output.name}.{os.getpid()}.{threading.get_ident()}.partial")
    cmd = ["cc", *C_FLAGS, *flags, *map(str, sources), *libs, "-o", str(partial)]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True)
    except FileNotFoundError as e:
        raise BuildError(f"{what}: no C compiler ('cc') on the PATH") from e
    if r.returncode != 0:
        partial.unlink(missing_ok=True)
        raise BuildError(f"{what} does not compile:\n{r.stderr}")
    os.replace(partial, output)
    return output
