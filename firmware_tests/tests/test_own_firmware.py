"""A firmware team runs its own firmware on the bench (README "Plugging in your own"): FirmwareBench(firmware=...)
and so ``biotac_bridge(firmware=...)`` take C sources or a built library; a header beside the sources is part of the
build's key (editing it rebuilds); a missing source, a library without the bridge's entry points, a refused pattern
leave nothing open; a firmware that hangs is reported by stop() rather than left silently spinning; scheduling on a
stopped bench, and one Sensor object under two sensor numbers, are refused."""

from __future__ import annotations

import os
import time

import pytest

from bench.errors import BuildError, FirmwareError
from bench.hosts import bridge as bridge_module
from bench.hosts.bridge import FirmwareBench
from bench.hosts.cosim import FIRMWARE_DIR, build_firmware, firmware_library
from bench.hosts.driver import BridgeDriver
from bench.hosts.native import compile_c
from bench.pytest_plugin.fixtures import one_sensor

pytestmark = pytest.mark.firmware

REFERENCE = (FIRMWARE_DIR / "bt_bridge.c").read_text()
STEP = "void bt_step(bt_bridge *b) {\n    serve_host(b);\n"
assert STEP in REFERENCE, "the reference firmware's bt_step changed: update these tests' edits"


def own_firmware(tmp_path, extra_step: str = "", header: str = "#define MY_MARK 7\n"):
    """The reference firmware copied into ``tmp_path`` as a user's, with its own header (``my.h``), a marker
    function ``my_mark`` returning MY_MARK, and ``extra_step`` run at the start of every bt_step."""
    (tmp_path / "my.h").write_text(header)
    src = tmp_path / "my_bridge.c"
    src.write_text('#include "my.h"\n' + REFERENCE.replace(STEP, STEP + extra_step)
                   + "\nint my_mark(void);\nint my_mark(void) { return MY_MARK; }\n")
    return src


def test_your_own_firmware_streams_through_the_bench_and_the_driver(tmp_path):
    src = own_firmware(tmp_path)
    with FirmwareBench(n_sensors=1, firmware=[src]) as bench:
        assert bench.sim.lib.my_mark() == 7  # the user's library is the one running
        driver = BridgeDriver(bench.port)
        driver.start()
        assert len(list(driver.frames(max_frames=20, timeout_s=5))) == 20
        driver.close()
    assert firmware_library(str(src)) == firmware_library([src])  # a single .c path too
    assert firmware_library(firmware_library([src])) == firmware_library([src])  # a built .so as it is


def test_a_header_beside_your_sources_is_part_of_the_build(tmp_path):
    src = own_firmware(tmp_path)
    first = build_firmware([src], out_dir=tmp_path / "out")
    (tmp_path / "my.h").write_text("#define MY_MARK 8\n")  # the .c unchanged: had reused the stale library
    second = build_firmware([src], out_dir=tmp_path / "out")
    assert first != second
    import ctypes
    assert ctypes.CDLL(str(second)).my_mark() == 8


def test_what_is_not_a_firmware_is_refused_by_name(tmp_path):
    with pytest.raises(BuildError, match=r"source '.*nope\.c' is not a file"):
        FirmwareBench(firmware=[tmp_path / "nope.c"])
    with pytest.raises(BuildError, match=r"firmware = '.*nope\.so': no such library"):
        FirmwareBench(firmware=str(tmp_path / "nope.so"))
    with pytest.raises(BuildError, match=r"firmware = 42: give None \(the reference firmware\), a list of C source"):
        FirmwareBench(firmware=42)
    empty = tmp_path / "empty.c"
    empty.write_text("int nothing_here(void);\nint nothing_here(void) { return 0; }\n")
    lib = compile_c([empty], tmp_path / "libempty.so", flags=("-shared", "-fPIC"))
    fds = len(os.listdir("/proc/self/fd"))
    with pytest.raises(FirmwareError, match=r"does not export bt_bridge_size, bt_init, bt_step, bt_set_pattern"):
        FirmwareBench(firmware=lib)
    assert len(os.listdir("/proc/self/fd")) == fds, "a refused firmware left its pty open"


def test_a_refused_pattern_leaves_no_pty_open():
    fds = len(os.listdir("/proc/self/fd"))
    with pytest.raises(ValueError, match="refused by the firmware"):
        FirmwareBench(pattern=[99])
    assert len(os.listdir("/proc/self/fd")) == fds


@pytest.mark.parametrize("loop, last_call", [
    ("for (;;) { (void)b->hal->micros(b->hal->ctx); }", "micros"),
    ("for (volatile unsigned long k = 0;; k++) { }", "micros"),  # (its last HAL call: the condition's)
], ids=["a loop calling the HAL", "a loop calling none"])
def test_a_hung_firmware_is_reported_by_stop_and_stopped_without_a_busy_core(tmp_path, monkeypatch, loop, last_call):
    """A bt_step that loops forever once streaming passes 0.1 s of virtual time, calling a HAL function or none:
    stop() reports what hangs and where — bt_step, the wall time waited, the virtual time, the firmware's last HAL
    call and its library — and the watchdog stops the loop: the firmware's thread ends (it spun a core until the
    process ended when it called no HAL) and the process spends no CPU on it after."""
    monkeypatch.setattr(bridge_module, "STOP_TIMEOUT_S", 0.5)
    src = own_firmware(tmp_path, "    if (b->streaming && b->hal->micros(b->hal->ctx) > 100000) {\n"
                                 f"        {loop}\n    }}\n")
    bench = FirmwareBench(firmware=[src]).start()
    driver = BridgeDriver(bench.port)
    driver.start()
    frames = list(driver.frames(max_frames=5, timeout_s=10))  # the first frames may wait on loading the kernels
    frames += list(driver.frames(max_frames=100, timeout_s=0.5))
    assert 5 <= len(frames) < 20  # streamed up to the hang at 0.1 s (10 ms frames), then nothing
    with pytest.raises(FirmwareError, match=r"the firmware did not return from bt_step within 0\.5 s of wall time "
                                            r"after stop\(\) \(virtual time 0\.1\d* s\): it hangs in a loop .*its "
                                            rf"last HAL call: {last_call}; firmware .*libbtbridge\.so\); the "
                                            r"watchdog stopped it \(its thread ended"):
        bench.stop()
    assert not bench._thread.is_alive() and not bench.board.abandoned.is_set()
    cpu = time.process_time()
    time.sleep(0.3)
    assert time.process_time() - cpu < 0.1  # nothing spinning
    bench.stop()  # idempotent: nothing more to say
    driver.close()


def test_a_firmware_held_inside_a_hal_call_is_reported_parked_and_ends_when_the_call_returns(monkeypatch):
    """A step the watchdog's signal cannot end at once — the firmware's thread inside one of the bench's HAL calls
    (here a scheduled action that waits) — is reported as not stopped, its thread parked at its next HAL call; the
    signal waits, blocked, and ends the step as soon as the HAL call returns: the thread ends then."""
    import threading

    monkeypatch.setattr(bridge_module, "STOP_TIMEOUT_S", 0.3)
    release, entered = threading.Event(), threading.Event()

    def wait(board):
        entered.set()
        release.wait(30)

    bench = FirmwareBench(realtime=True).start()  # (paced: the firmware runs without a host's first byte)
    bench.now(lambda board: board.at(board.t, wait))  # applied at the firmware's next HAL call
    assert entered.wait(30)
    with pytest.raises(FirmwareError, match=r"did not return from bt_step within 0\.3 s .*the watchdog could not "
                                            r"stop it \(it is inside the bench's HAL function \w+: its step "
                                            r"is left as that returns\): its port is closed, its SPI bus left open "
                                            r"and its thread parked at its next HAL call"):
        bench.stop()
    assert bench._thread.is_alive() and bench.board.abandoned.is_set()
    release.set()
    bench._thread.join(10)
    assert not bench._thread.is_alive()  # the pending signal ended the step as the HAL call returned
    bench.board.bus.close()


def test_a_firmware_crash_is_reported_by_the_first_call_after_it_naming_the_virtual_time(tmp_path):
    """A firmware that crashes (SIGSEGV) once streaming passes 50 ms of virtual time: the first call on the bench after
    — here at() — raises, naming the virtual time the bench stopped at and the crash; so do now() and virtual_time;
    stop() then closes quietly (the error was told).  Until stop(), the crash went unsaid and at()
    took an action that would never run."""
    src = own_firmware(tmp_path, "    if (b->streaming && b->hal->micros(b->hal->ctx) > 50000) {\n"
                                 "        int *volatile nowhere = 0;\n        *nowhere = 1;\n    }\n")
    bench = FirmwareBench(firmware=[src]).start()
    driver = BridgeDriver(bench.port)
    driver.start()
    bench._thread.join(30)
    assert not bench._thread.is_alive()
    said = (r" the firmware bench on .* stopped at virtual time (0\.05\d+) s with an error: the firmware crashed in "
            r"bt_step at virtual time \1 s: SIGSEGV in libbtbridge\.so \(bt_step\) \(touching address 0x0\)")
    for call, what in ((lambda: bench.at(1.0, lambda board: None), "at"),
                       (lambda: bench.now(lambda board: None), "now"),
                       (lambda: bench.virtual_time, "virtual_time")):
        with pytest.raises(RuntimeError, match=what + ":" + said):
            call()
    bench.stop()
    driver.close()


def test_a_firmware_that_talks_to_the_host_in_bt_init_starts_and_is_heard(tmp_path):
    """A firmware whose bt_init sends the host something (here its status, as a boot message) starts on the bench,
    its message on the line, and streams as usual.  Its bt_init runs inside FirmwareBench's constructor, and its
    UART bytes go through the bench's line: that line's settings were set only after it, so the firmware's first
    byte was an AttributeError blamed on its HAL call (a FirmwareError: the bench could not start it).  (A host
    opening the port later does not read it: pyserial empties the input at open, as after a real bridge's boot.)"""
    from bench.hosts.driver import FrameParser, Status

    end = '    b->finds = 0; /* sensors present at start-up are not "found again" */\n}\n'
    assert REFERENCE.count(end) == 1, "the reference firmware's bt_init changed: update this test's edit"
    src = tmp_path / "boot_status.c"
    src.write_text(REFERENCE.replace(end, end[:-2] + "    send_status(b);\n}\n"))
    with FirmwareBench(n_sensors=1, firmware=[src], keep_arrivals=True) as bench:
        sent = FrameParser().feed(bytes(bench.link.arrivals), now=0.0)
        assert [type(item) for item in sent] == [Status]  # the boot status, on the line before any host spoke
        driver = BridgeDriver(bench.port)
        driver.start()
        assert len(list(driver.frames(max_frames=5, timeout_s=30))) == 5  # (cold: kernels compile first)
        driver.close()


def test_scheduling_on_a_stopped_bench_is_refused():
    bench = FirmwareBench().start()
    bench.at(0.5, lambda board: None)
    bench.stop()
    for schedule in (lambda: bench.at(1.0, lambda board: None), lambda: bench.now(lambda board: None)):
        with pytest.raises(RuntimeError, match=r"the bench on .* is stopped \(stop\(\) was called\): an action given "
                                               r"now would never run"):
            schedule()


def test_one_sensor_object_under_two_numbers_is_refused():
    s = one_sensor()
    with pytest.raises(ValueError, match=r"sensors 1 and 3 are the same Sensor object: each sensor number needs a "
                                         r"sensor of its own"):
        FirmwareBench(sensors={1: s, 2: one_sensor(), 3: s})


def test_the_bridge_command_runs_your_firmware_and_refuses_what_is_not_one(tmp_path, capsys):
    """`biotac-bench bridge --firmware FILE...`: C sources or one built library; a missing file, another kind of file
    and a library beside other files are refused in one line (exit 2), a library without the entry points too."""
    from bench.cli.main import main as run_main

    def main(argv) -> int:
        """The command's exit status (argparse's refusals end in SystemExit)."""
        try:
            return run_main(argv)
        except SystemExit as e:
            return e.code

    src = own_firmware(tmp_path)
    assert main(["bridge", "--firmware", str(src), "--fast", "--seconds", "0.3"]) == 0
    assert f"your firmware ({src}) running with 1 emulated sensor(s) at rest" in capsys.readouterr().out
    lib = firmware_library([src])
    assert main(["bridge", "--firmware", str(lib), "--fast", "--seconds", "0.3"]) == 0
    capsys.readouterr()
    other = tmp_path / "notes.txt"
    other.write_text("x")
    for argv, message in (([str(tmp_path / "nope.c")], "nope.c: no such file"),
                          ([str(other)], "notes.txt: give C sources (.c) or one built library (.so)"),
                          ([str(lib), str(src)], "is a built library, the whole firmware: give it alone")):
        assert main(["bridge", "--firmware", *argv, "--fast", "--seconds", "0.3"]) == 2
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    empty = tmp_path / "empty.c"
    empty.write_text("int nothing_here(void);\nint nothing_here(void) { return 0; }\n")
    bare = compile_c([empty], tmp_path / "libempty.so", flags=("-shared", "-fPIC"))
    assert main(["bridge", "--firmware", str(bare), "--fast", "--seconds", "0.3"]) == 2
    assert "does not export bt_bridge_size, bt_init, bt_step, bt_set_pattern" in capsys.readouterr().err


def test_a_stop_requested_between_two_steps_still_ends_run():
    """The watchdog's signal can arrive while no bt_step runs (between two of run's passes, or before the first):
    the step guard then has no loop to leave and ignores it. The request is kept, so run still raises before its
    next step instead of carrying on."""
    from bench.hosts.cosim import CoSim, VirtualBoard, default_sensors

    board = VirtualBoard(default_sensors(1))
    try:
        sim = CoSim(board)
        sim.run(0.002)  # runs as usual
        assert sim.stop_step() is None  # no step is running to be left
        board.send_to_firmware(b"\x00")
        with pytest.raises(FirmwareError, match="stopped by the bench's watchdog .* make a new one"):
            sim.run(0.002)
        assert list(board.uart_in) == [0]  # the firmware did not run at all: its byte is still waiting
        with pytest.raises(FirmwareError, match="stopped by the bench's watchdog .* make a new one"):
            sim.run(0.002)  # for good: its firmware's state was left midway
        with pytest.raises(FirmwareError, match=r"set_pattern: the firmware's bt_step was stopped by the bench's "
                                                r"watchdog .* make a new one"):
            sim.set_pattern(["PDC"])
    finally:
        board.bus.close()
