"""The firmware watchdog's step guard (bench/hosts/c/step_guard.c): a hung bt_step is left only from the firmware's
own code — never from inside the C library, where a lock may be held (a jump out of fprintf or malloc used to leave
the process unable to exit) —, a step blocked in the C library is reported with where it is, a stopped
co-simulation refuses to run again, two co-simulations in two threads stop only what was asked, and the guard's
signal is never taken from (or sent behind the back of) another handler in the process.  Each case runs in a
process of its own: a deadlock there fails the test by its timeout instead of hanging the suite, and the handler
installed or replaced stays in that process."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from bench.hosts.cosim import FIRMWARE_DIR

pytestmark = pytest.mark.firmware

STEP = "void bt_step(bt_bridge *b) {\n    serve_host(b);\n"
assert STEP in (FIRMWARE_DIR / "bt_bridge.c").read_text(), "the reference firmware's bt_step changed"
INIT = "void bt_init(bt_bridge *b, const bt_hal *hal) {\n    memset(b, 0, sizeof *b);\n    b->hal = hal;\n"
assert INIT in (FIRMWARE_DIR / "bt_bridge.c").read_text(), "the reference firmware's bt_init changed"
PATTERN = "uint8_t bt_set_pattern(bt_bridge *b, const uint8_t *p, size_t len) {\n"
assert PATTERN in (FIRMWARE_DIR / "bt_bridge.c").read_text(), "the reference firmware's bt_set_pattern changed"

#: C declarations put before the reference firmware's source in every firmware these cases build
HEAD = ("#include <assert.h>\n#include <stdio.h>\n#include <stdlib.h>\n#include <string.h>\n#include <unistd.h>\n"
        "char *volatile sink;\nFILE *out;\nint *volatile nowhere;\nvolatile size_t length;\n"
        "int bt_deep(unsigned depth);\n"  # (a recursion without end, as far as the stack goes)
        "int bt_deep(unsigned depth) { volatile char pad[512]; pad[depth % 512] = 1;\n"
        "    return depth ? bt_deep(depth + 1) + pad[0] : 0; }\n")
#: what every case's process starts with: ``firmware(extra)`` builds the reference firmware running ``extra`` (C) in
#: every bt_step from 20 ms of virtual time on, as fw.c in the folder its last argument names (``in_init=True``: at the
#: start of bt_init instead; ``in_pattern=True``: at the start of bt_set_pattern; ``own``: compiled here with cc and
#: these flags, as a library built without the bench); ``HANG``: a loop calling no HAL function; ``start(sim)`` runs 1
#: s of it in a thread: (the thread, the FirmwareErrors it ended with)
PRELUDE = textwrap.dedent("""
    import ctypes, signal, sys, threading, time
    from pathlib import Path
    from bench.errors import FirmwareError
    from bench.hosts import cosim
    from bench.hosts.cosim import CoSim, VirtualBoard, default_sensors, FIRMWARE_DIR, build_firmware
    folder = Path(sys.argv[-1])
    HANG = "for (volatile unsigned long k = 0;; k++) { }"
    def firmware(extra, in_init=False, own=None, in_pattern=False):
        src = folder / "fw.c"
        code = (FIRMWARE_DIR / "bt_bridge.c").read_text()
        if in_init or in_pattern:
            anchor = INIT if in_init else PATTERN
            code = code.replace(anchor, anchor + "    " + extra + "\\n")
        else:
            code = code.replace(STEP, STEP + "    if (b->hal->micros(b->hal->ctx) > 20000) {\\n" + extra
                                + "\\n    }\\n")
        src.write_text(HEAD + code)
        if own is None:
            return build_firmware([src], out_dir=folder / "out")
        import subprocess
        subprocess.run(["cc", "-O2", "-shared", "-fPIC", *own.split(), f"-I{FIRMWARE_DIR}", str(src), "-o",
                        str(folder / "libown.so")], check=True)
        return folder / "libown.so"
    def start(sim):
        ended = []
        def run():
            try:
                sim.run(1.0)
            except FirmwareError as e:
                ended.append(str(e))
        thread = threading.Thread(target=run, daemon=True)
        thread.start()
        return thread, ended
""").replace("STEP", repr(STEP)).replace("INIT", repr(INIT)).replace("PATTERN", repr(PATTERN)).replace("HEAD",
                                                                                                       repr(HEAD))


def _run(tmp_path, body: str, *args: str, python=(), timeout_s: float = 120) -> subprocess.CompletedProcess:
    """Run :data:`PRELUDE` + ``body`` in a process of its own, with ``args`` then ``tmp_path`` as arguments."""
    return subprocess.run([sys.executable, *python, "-c", PRELUDE + textwrap.dedent(body), *args, str(tmp_path)],
                          capture_output=True, text=True, timeout=timeout_s)


#: a firmware whose bt_step runs its first argument, run in a thread, left to hang for 0.3 s, then stopped by the
#: watchdog (within 10 s), saying what came of it; then a new thread allocates and writes through C stdio, and the
#: process ends (flushing every C stream)
CHILD = """
    sim = CoSim(VirtualBoard(default_sensors(1)), firmware(sys.argv[1]))
    thread, ended = start(sim)
    time.sleep(0.3)
    print("stop_step:", sim.stop_step(within_s=10), flush=True)
    thread.join(10)
    print("thread ended:", not thread.is_alive(), ended, flush=True)
    if not thread.is_alive():
        libc = ctypes.CDLL(None)
        libc.malloc.restype = ctypes.c_void_p
        def use_libc():
            for _ in range(1000):
                libc.free(ctypes.c_void_p(libc.malloc(4000)))
            libc.fputs(b"C stdio still works\\n", ctypes.c_void_p.in_dll(libc, "stderr"))
        after = threading.Thread(target=use_libc)
        after.start()
        after.join()
        print("after: malloc and stdio in a new thread", flush=True)
"""


@pytest.mark.parametrize("loop", [
    'if (!out) { out = fopen("/dev/null", "w"); } for (;;) { fputs("x", out); }',
    "for (;;) { sink = malloc(4000); sink[0] = 1; free(sink); }",
], ids=["writing through stdio", "allocating"])
def test_a_firmware_hung_in_a_c_library_loop_is_stopped_and_the_process_goes_on(tmp_path, loop):
    """A bt_step looping on fputs (its FILE's lock taken and released each pass) or malloc/free (the arena's lock) is
    stopped — the signal taken only when it lands in the firmware's own code — and the process goes on: a new
    thread allocates and writes through C stdio, and the process exits (flushing every C stream, the firmware's
    too).  Jumping wherever the signal landed left the FILE's lock held: the process never exited."""
    r = _run(tmp_path, CHILD, loop)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "stop_step: None\n" in r.stdout
    assert "thread ended: True [\"the firmware's bt_step was stopped by the bench's watchdog at virtual time 0.02" \
           in r.stdout and "make a new one" in r.stdout
    assert "after: malloc and stdio in a new thread" in r.stdout and "C stdio still works" in r.stderr


def test_a_firmware_blocked_in_a_c_library_call_is_reported_where_it_is_not_jumped_out_of(tmp_path):
    """A bt_step blocked for good in read() on a pipe nobody writes: the watchdog never finds it in the firmware's
    code, so does not leave it, and says where it is — the C library, read — within the time it was given."""
    r = _run(tmp_path, CHILD, "int fds[2]; char c; if (pipe(fds) == 0) { (void)read(fds[0], &c, 1); }")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "stop_step: it is outside the firmware's code, in libc.so.6 (read), which the watchdog does not jump out " \
           "of (a lock held there would deadlock the process)\n" in r.stdout, r.stdout
    assert "thread ended: False []" in r.stdout


#: two co-simulations in two threads: one hangs (a loop calling no HAL function), one streams; stopping the first
#: leaves the second's run untouched — its UART output is the same as a run on its own
TWO = """
    from bench.hosts.driver import CMD_START, encode
    def streaming():
        out = bytearray()
        board = VirtualBoard(default_sensors(1), uart_out=out.extend)
        sim = CoSim(board)
        sim.set_pattern(["PDC"])
        board.send_to_firmware(encode(CMD_START))
        return sim, out
    ended = {}
    def run(name, sim, seconds):
        try:
            for _ in range(int(seconds / 0.01)):
                sim.run(0.01)
                time.sleep(0.001)
            ended[name] = "ran"
        except FirmwareError as e:
            ended[name] = str(e)
    alone, alone_out = streaming()
    run("alone", alone, 0.5)
    hung = CoSim(VirtualBoard(default_sensors(1)), firmware(HANG))
    other, other_out = streaming()
    threads = [threading.Thread(target=run, args=("hung", hung, 1.0)),
               threading.Thread(target=run, args=("other", other, 0.5))]
    for t in threads:
        t.start()
    time.sleep(0.2)
    print("stop_step:", hung.stop_step(within_s=10), flush=True)
    for t in threads:
        t.join(60)
    print("hung:", ended.get("hung"))
    print("other:", ended.get("other"), "same output:", bytes(other_out) == bytes(alone_out),
          "streamed:", len(alone_out) > 1000)
    print("stopped:", hung.stopped, other.stopped)
"""


def test_two_co_simulations_in_two_threads_stop_only_what_was_asked(tmp_path):
    """Stopping one co-simulation's hung firmware leaves another, running in another thread at the same time, as it
    was: its run ends as usual with the same bytes streamed as on its own, and only the first is stopped."""
    r = _run(tmp_path, TWO, timeout_s=300)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "stop_step: None\n" in r.stdout
    assert "hung: the firmware's bt_step was stopped by the bench's watchdog" in r.stdout
    assert "other: ran same output: True streamed: True" in r.stdout and "stopped: True False" in r.stdout, r.stdout


#: the guard's signal and another handler in the same process: one installed first is refused by name (never
#: replaced); one installed after the bench's (here the default action back, which would end the process if the
#: signal came) makes the watchdog say so and send nothing
OTHER_HANDLER = """
    mine = lambda *a: None
    signal.signal(cosim.GUARD_SIGNAL, mine)
    try:
        CoSim(VirtualBoard(default_sensors(1)))
    except FirmwareError as e:
        print("refused:", e)
    print("kept:", signal.getsignal(cosim.GUARD_SIGNAL) is mine)
    signal.signal(cosim.GUARD_SIGNAL, signal.SIG_DFL)
    sim = CoSim(VirtualBoard(default_sensors(1)), firmware(HANG))
    start(sim)
    time.sleep(0.3)
    signal.signal(cosim.GUARD_SIGNAL, signal.SIG_DFL)
    print("stop_step:", sim.stop_step(within_s=1), flush=True)
    time.sleep(0.3)
    print("alive", flush=True)
"""


def test_a_handler_of_the_guards_signal_elsewhere_in_the_process_is_never_taken_over(tmp_path):
    r = _run(tmp_path, OTHER_HANDLER)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "refused: signal SIGRTMIN+3 (" in r.stdout and ") already has a handler in this process (installed by " \
           "signal.signal or by a library): the firmware watchdog needs a signal of its own; set " \
           "bench.hosts.cosim.GUARD_SIGNAL to a free real-time signal" in r.stdout, r.stdout
    assert "kept: True" in r.stdout
    assert "stop_step: the handler of signal SIGRTMIN+3 (" in r.stdout and ") was replaced after the bench " \
           "installed it (by signal.signal or a library): the watchdog sends no signal\n" in r.stdout, r.stdout
    assert r.stdout.endswith("alive\n")  # (the default action of a real-time signal ends the process)


#: a firmware that writes "!" on its UART (a HAL call the bench holds until told) then loops calling no HAL function:
#: the watchdog gives up while the call is held, then the call is let go
IN_HAL = """
    release, entered = threading.Event(), threading.Event()
    def uart_out(data):
        if data == b"!":
            entered.set()
            release.wait(30)
    sim = CoSim(VirtualBoard(default_sensors(1), uart_out=uart_out),
                firmware('b->hal->uart_write(b->hal->ctx, (const uint8_t *)"!", 1);' + HANG))
    thread, ended = start(sim)
    print("entered:", entered.wait(30), flush=True)
    print("stop_step:", sim.stop_step(within_s=0.2), flush=True)
    release.set()
    thread.join(10)
    print("thread ended:", not thread.is_alive(), ended, flush=True)
    print("stop_step:", sim.stop_step(), flush=True)
"""


def test_a_step_stopped_inside_a_hal_call_is_left_as_the_call_returns(tmp_path):
    """The watchdog gives up on a step inside one of the bench's HAL calls (uart_write, held by the bench): it says so
    and sends nothing then.  As that call returns the step is left — before the firmware's next instruction, here a
    loop that calls no HAL function and would spin for good."""
    r = _run(tmp_path, IN_HAL)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.startswith("entered: True\nstop_step: it is inside the bench's HAL function uart_write: its step "
                               "is left as that returns\nthread ended: True [\"the firmware's bt_step was stopped by "
                               "the bench's watchdog"), r.stdout
    assert r.stdout.endswith("stop_step: None\n")


#: a firmware whose bt_step runs its first argument (a fault, an exit), run twice; then a new co-simulation
CRASH = """
    sim = CoSim(VirtualBoard(default_sensors(1)), firmware(sys.argv[1]))
    for _ in range(2):
        try:
            sim.run(0.1)
        except FirmwareError as e:
            print("error:", e, flush=True)
    CoSim(VirtualBoard(default_sensors(1))).run(0.05)
    print("a new co-simulation runs", flush=True)
"""


def test_a_firmware_that_crashes_in_its_own_code_is_an_error_naming_the_fault_and_the_process_goes_on(tmp_path):
    """A bt_step writing through a null pointer: SIGSEGV in the firmware's own code ends its step, not the process —
    run raises a FirmwareError naming the signal, the library and function, the address touched and the virtual
    time (also on the next run: the co-simulation is stopped), and a new co-simulation runs."""
    r = _run(tmp_path, CRASH, "*nowhere = 1;")
    assert r.returncode == 0, r.stdout + r.stderr
    error = ("error: the firmware crashed in bt_step at virtual time 0.020425 s: SIGSEGV in libbtbridge.so (bt_step) "
             "(touching address 0x0); the bench left its bt_step and goes on; this co-simulation does not run again: "
             "make a new one\n")
    assert r.stdout == 2 * error + "a new co-simulation runs\n", r.stdout


def test_a_crash_outside_the_firmwares_code_goes_to_the_handler_that_was_there_before(tmp_path):
    """strlen(NULL) from the firmware faults inside the C library, not the firmware's code: the bench does not leave
    the step from there; the handler that was there before takes the fault — here Python's faulthandler, which
    names it and ends the process — rather than the process hanging or carrying on with a corrupt C library."""
    r = _run(tmp_path, CRASH, "length = strlen((const char *)nowhere);", python=("-X", "faulthandler"))
    assert r.returncode < 0 and "Fatal Python error: Segmentation fault" in r.stderr, r.stdout + r.stderr
    assert "a new co-simulation runs" not in r.stdout


@pytest.mark.parametrize("call, said", [
    ("exit(3);", "exit(3)"), ("_exit(4);", "_exit(4)"), ("abort();", "abort()"),
    ("assert(b->hal == 0);", r"assert(b->hal == 0), which failed at {src}:{line} in bt_step()"),
], ids=["exit", "_exit", "abort", "assert"])
def test_a_firmware_calling_exit_abort_or_failing_an_assert_ends_its_step_not_the_process(tmp_path, call, said):
    """A firmware built by the bench that calls exit, _exit or abort, or fails an assert, in bt_step: the process
    (a user's pytest run) goes on; run raises a FirmwareError saying what was called (the assert's condition and
    place) and when, and a new co-simulation runs.  It ended the process, with nothing said."""
    r = _run(tmp_path, CRASH, call)
    assert r.returncode == 0, r.stdout + r.stderr
    source = (tmp_path / "fw.c").read_text().splitlines()
    said = said.format(src=tmp_path / "fw.c", line=1 + next(k for k, text in enumerate(source) if call in text))
    error = (f"error: the firmware called {said} in bt_step at virtual time 0.020425 s, which would have ended the "
             f"process: the bench left its bt_step and goes on; this co-simulation does not run again: make a new "
             f"one\n")
    assert r.stdout == 2 * error + "a new co-simulation runs\n", r.stdout


#: a firmware running its first argument at the start of bt_init (its second: "own" when built with cc here, not by
#: the bench), made into a co-simulation; the virtual time then; then a new co-simulation of the reference firmware
INIT_CRASH = """
    board = VirtualBoard(default_sensors(1))
    try:
        CoSim(board, firmware(sys.argv[1], in_init=True, own="" if sys.argv[2] == "own" else None))
    except FirmwareError as e:
        print("error:", e, flush=True)
    print(f"t: {board.t:.6f}", flush=True)
    CoSim(VirtualBoard(default_sensors(1))).run(0.05)
    print("a new co-simulation runs", flush=True)
"""


@pytest.mark.parametrize("built", ["bench", "own"], ids=["built by the bench", "a library built elsewhere"])
@pytest.mark.parametrize("call, said", [
    ("*nowhere = 1;", "crashed in bt_init at virtual time {t} s: SIGSEGV in {lib} (bt_init) (touching address 0x0);"),
    ("exit(3);", "called exit(3) in bt_init at virtual time {t} s, which would have ended the process:"),
    ("_exit(4);", "called _exit(4) in bt_init at virtual time {t} s, which would have ended the process:"),
    ("abort();", "called abort() in bt_init at virtual time {t} s, which would have ended the process:"),
    ("assert(hal == 0);", "called assert(hal == 0), which failed at {src}:{line} in bt_init() in bt_init at virtual "
                          "time {t} s, which would have ended the process:"),
], ids=["SIGSEGV", "exit", "_exit", "abort", "assert"])
def test_a_firmware_that_crashes_or_exits_in_bt_init_is_an_error_naming_it_and_the_process_goes_on(
        tmp_path, call, said, built):
    """A fault, exit, _exit, abort or failed assert in bt_init — in a firmware the bench built, or in a library built
    without it (with cc here, as a user's --firmware .so) — ends bt_init, not the process: making the co-simulation
    raises a FirmwareError naming bt_init, the signal or the call, where, and the virtual time; a new co-simulation
    runs.  They ended the whole process, with nothing said (a library built elsewhere ended it in bt_step too)."""
    r = _run(tmp_path, INIT_CRASH, call, built)
    assert r.returncode == 0, r.stdout + r.stderr
    t = r.stdout.split("t: ")[1].split("\n")[0]
    source = (tmp_path / "fw.c").read_text().splitlines()
    said = said.format(t=t, lib="libown.so" if built == "own" else "libbtbridge.so", src=tmp_path / "fw.c",
                       line=1 + next(k for k, text in enumerate(source) if call in text))
    assert r.stdout == (f"error: the firmware {said} the bench left its bt_init and goes on; this co-simulation does "
                        f"not run again: make a new one\nt: {t}\na new co-simulation runs\n"), r.stdout


@pytest.mark.parametrize("flags", ["", "-Wl,-z,relro,-z,now", "-fno-plt"],
                         ids=["linked as cc does", "full RELRO", "no PLT"])
@pytest.mark.parametrize("call", ["exit(3);", "abort();"])
def test_a_library_built_elsewhere_that_exits_in_bt_step_is_an_error_not_the_end_of_the_process(tmp_path, call,
                                                                                                  flags):
    """A library built without the bench (cc here) calling exit or abort in bt_step — linked as cc links it, with
    its offset table read-only (full RELRO, a common hardening), or calling through the table without a PLT: its
    step is left and run raises naming the call, as for a firmware the bench builds.  It ended the process."""
    body = CRASH.replace("firmware(sys.argv[1])", "firmware(sys.argv[1], own=sys.argv[2])")
    r = _run(tmp_path, body, call, flags)
    assert r.returncode == 0, r.stdout + r.stderr
    error = (f"error: the firmware called {call[:-1]} in bt_step at virtual time 0.020425 s, which would have ended "
             f"the process: the bench left its bt_step and goes on; this co-simulation does not run again: make a new "
             f"one\n")
    assert r.stdout == 2 * error + "a new co-simulation runs\n", r.stdout


#: a firmware whose bt_step recurses without end, run in the main thread and in a thread of its own
OVERFLOW = """
    sim = CoSim(VirtualBoard(default_sensors(1)), firmware("length = (size_t)bt_deep(1);"))
    try:
        sim.run(0.1)
    except FirmwareError as e:
        print("main thread:", e, flush=True)
    thread, ended = start(CoSim(VirtualBoard(default_sensors(1)), firmware("length = (size_t)bt_deep(1);")))
    thread.join(60)
    print("thread:", *ended, flush=True)
    CoSim(VirtualBoard(default_sensors(1))).run(0.05)
    print("a new co-simulation runs", flush=True)
"""


def test_a_stack_overflow_in_the_firmware_is_an_error_saying_so_and_the_process_goes_on(tmp_path):
    """A bt_step recursing until its stack runs out, in the main thread and in another: a FirmwareError saying it was
    a stack overflow, in which function, at what virtual time; the process goes on.  With no alternate signal
    stack the fault's handler had no stack to run on: the process ended."""
    r = _run(tmp_path, OVERFLOW)
    assert r.returncode == 0, r.stdout + r.stderr
    lines = r.stdout.splitlines()
    assert [line.split(":")[0] for line in lines] == ["main thread", "thread", "a new co-simulation runs"], r.stdout
    for line in lines[:2]:
        assert ": the firmware crashed in bt_step at virtual time 0.020425 s: a stack overflow in libbtbridge.so " \
               "(bt_deep) (touching address 0x" in line and line.endswith(
                   "); the bench left its bt_step and goes on; this co-simulation does not run again: make a new one")


#: a firmware running its first argument at the start of bt_set_pattern: a co-simulation's set_pattern, twice (the
#: co-simulation stopped), then its run; then a bridge bench given the pattern (its constructor); then a new
#: co-simulation
PATTERN_CRASH = """
    from bench.hosts.bridge import FirmwareBench
    library = firmware(sys.argv[1], in_pattern=True)
    sim = CoSim(VirtualBoard(default_sensors(1)), library)
    sim.run(0.01)
    for _ in range(2):
        try:
            sim.set_pattern(["PDC"])
        except FirmwareError as e:
            print("error:", e, flush=True)
    try:
        sim.run(0.01)
    except FirmwareError as e:
        print("run:", e, flush=True)
    print("stopped:", sim.stopped, flush=True)
    try:
        FirmwareBench(firmware=library, pattern=["PDC"])
    except FirmwareError as e:
        print("bench:", e, flush=True)
    CoSim(VirtualBoard(default_sensors(1))).run(0.05)
    print("a new co-simulation runs", flush=True)
"""


@pytest.mark.parametrize("call, said", [
    ("*nowhere = 1;", "crashed in bt_set_pattern at virtual time {t} s: SIGSEGV in libbtbridge.so (bt_set_pattern) "
                      "(touching address 0x0);"),
    ("exit(3);", "called exit(3) in bt_set_pattern at virtual time {t} s, which would have ended the process:"),
    ("abort();", "called abort() in bt_set_pattern at virtual time {t} s, which would have ended the process:"),
    ("assert(len == 0);", "called assert(len == 0), which failed at {src}:{line} in bt_set_pattern() in "
                          "bt_set_pattern at virtual time {t} s, which would have ended the process:"),
], ids=["SIGSEGV", "exit", "abort", "assert"])
def test_a_firmware_that_crashes_or_exits_in_bt_set_pattern_is_an_error_naming_it_and_the_process_goes_on(
        tmp_path, call, said):
    """A fault, exit, abort or failed assert in bt_set_pattern ends that call, not the process: CoSim.set_pattern
    raises a FirmwareError naming bt_set_pattern, the signal or the call, where and the virtual time (again at the
    next call, and run says the same: the co-simulation is stopped, where it was left), FirmwareBench(pattern=...)
    raises the same from its constructor, and a new co-simulation runs.  bt_set_pattern ran outside the guard: the
    process ended, with nothing said."""
    r = _run(tmp_path, PATTERN_CRASH, call)
    assert r.returncode == 0, r.stdout + r.stderr
    source = (tmp_path / "fw.c").read_text().splitlines()
    line = 1 + next(k for k, text in enumerate(source) if call in text)
    tail = "the bench left its bt_set_pattern and goes on; this co-simulation does not run again: make a new one\n"
    error = "the firmware " + said.format(t="0.011425", src=tmp_path / "fw.c", line=line) + " " + tail
    bench = "the firmware " + said.format(t="0.001425", src=tmp_path / "fw.c", line=line) + " " + tail
    assert r.stdout == ("error: " + error + "error: set_pattern: " + error + "run: " + error + "stopped: True\nbench: "
                        + bench
                        + "a new co-simulation runs\n"), r.stdout


#: a firmware whose bt_set_pattern hangs (a loop calling no HAL function), called in a thread; the watchdog stops it
PATTERN_HANG = """
    sim = CoSim(VirtualBoard(default_sensors(1)), firmware(HANG, in_pattern=True))
    ended = []
    def set_pattern():
        try:
            sim.set_pattern(["PDC"])
        except FirmwareError as e:
            ended.append(str(e))
    thread = threading.Thread(target=set_pattern, daemon=True)
    thread.start()
    time.sleep(0.3)
    print("stop_step:", sim.stop_step(within_s=10), flush=True)
    thread.join(10)
    print("thread ended:", not thread.is_alive(), *ended, flush=True)
"""


def test_a_firmware_hung_in_bt_set_pattern_is_stopped_by_the_watchdog(tmp_path):
    """A bt_set_pattern that never returns is left by the watchdog (stop_step, from another thread) as a hung bt_step
    is: set_pattern raises a FirmwareError naming bt_set_pattern.  Outside the guard nothing could leave it: its
    thread spun for good."""
    r = _run(tmp_path, PATTERN_HANG)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout == ("stop_step: None\nthread ended: True the firmware's bt_set_pattern was stopped by the bench's "
                        "watchdog at virtual time 0.001425 s (it hung); this co-simulation does not run again: make a "
                        "new one\n"), r.stdout
