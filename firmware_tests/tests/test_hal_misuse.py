"""A firmware misusing the bench's HAL (bt_hal.h), as a driver author's first attempts do: each misuse is a
FirmwareError from run() naming the HAL function, the virtual time, the word and the value — never an internal
error of the bench's — and an empty SPI sequence is no misuse (nothing is clocked)."""

from __future__ import annotations

import pytest

from bench.errors import FirmwareError
from bench.hosts.cosim import FIRMWARE_DIR, CoSim, VirtualBoard, build_firmware, default_sensors

pytestmark = pytest.mark.firmware

STEP = "void bt_step(bt_bridge *b) {\n    serve_host(b);\n"
REFERENCE = (FIRMWARE_DIR / "bt_bridge.c").read_text()
assert STEP in REFERENCE and "#include <string.h>\n" in REFERENCE, "the reference firmware changed"
SELECT = r"a select code is 0 to 7 \(bt_hal\.h: 1, 2, 4, 5, 6 = sensors 1\.\.5, 7 = all, 0 = none\)"


def _sim(tmp_path, misuse: str) -> CoSim:
    """The reference firmware doing ``misuse`` (C, with globals tx, rx, w, mi at hand) in every bt_step from 20 ms
    of virtual time on."""
    src = tmp_path / "fw.c"
    src.write_text(REFERENCE.replace("#include <string.h>\n", "#include <string.h>\nuint8_t tx[4], rx[4];\n"
                                     "bt_word w[2];\nuint16_t mi[2];\n")
                   .replace(STEP, STEP + "    if (b->hal->micros(b->hal->ctx) > 20000) {\n" + misuse + "\n    }\n"))
    return CoSim(VirtualBoard(default_sensors(1)), build_firmware([src], out_dir=tmp_path / "out"))


@pytest.mark.parametrize("misuse, error", [
    ("w[0].cs = 99; b->hal->spi_sequence(b->hal->ctx, w, mi, 1);",
     r"the firmware's HAL call spi_sequence at virtual time 0\.020425 s: word #0 of 1: cs = 99: " + SELECT),
    ("b->hal->spi_bytes(b->hal->ctx, 200, 0, tx, rx, 2);",
     r"the firmware's HAL call spi_bytes at virtual time 0\.020425 s: cs = 200: " + SELECT),
    ("w[0].offset_ns = 1000; w[1].offset_ns = 10; w[0].cs = w[1].cs = 1; b->hal->spi_sequence(b->hal->ctx, w, mi, 2);",
     r"the firmware's HAL call spi_sequence at virtual time 0\.020425 s: transfer #1 of the call starts at "
     r"0\.02042539\d* s, before transfer #0 \(from 0\.0204263\d* s\) ends"),
], ids=["a select code out of range in a sequence", "a select code out of range in bytes", "words out of time order"])
def test_a_hal_call_the_bench_cannot_take_is_an_error_naming_the_call_the_time_and_the_value(tmp_path, misuse, error):
    """... and, refused before anything changed, it leaves the co-simulation as it was: not stopped."""
    sim = _sim(tmp_path, misuse)
    try:
        with pytest.raises(FirmwareError, match=error):
            sim.run(0.1)
        assert not sim.stopped
    finally:
        sim.board.bus.close()


def test_an_empty_spi_sequence_clocks_nothing(tmp_path):
    """spi_sequence with no words (an empty DMA list): nothing happens and no time passes — it was an IndexError
    from inside the bench."""
    sim = _sim(tmp_path, "b->hal->spi_sequence(b->hal->ctx, w, mi, 0);")
    try:
        sim.run(0.1)
        assert 0.1 <= sim.board.t < 0.11
    finally:
        sim.board.bus.close()


def test_ctrl_c_during_a_hal_call_is_a_keyboard_interrupt_from_run(tmp_path):
    """Ctrl-C while the firmware is inside one of the bench's HAL calls (a SPI transfer, a delay: where a run spends
    its time) reaches run's caller as the KeyboardInterrupt it is — it was a FirmwareError wrapping it, which a
    program ending on Ctrl-C with its usual status took for a firmware fault."""
    import signal

    board = VirtualBoard(default_sensors(1))
    sim = CoSim(board)
    board.at(0.05, lambda board: signal.raise_signal(signal.SIGINT))  # (here: inside the HAL call at 0.05 s)
    try:
        with pytest.raises(KeyboardInterrupt):
            sim.run(0.1)
        assert 0.05 <= board.t < 0.1
    finally:
        board.bus.close()


@pytest.mark.parametrize("cut", ["ctrl-c", "raise"], ids=["Ctrl-C in an action", "a sensor raising"])
def test_a_hal_call_cut_short_ends_the_step_there_and_the_co_simulation_for_good(tmp_path, cut):
    """A real Ctrl-C (SIGINT, arriving as a scheduled action runs: before the HAL call's SPI transfers are sent), or
    a sensor raising as the bus has it convert (midway through the transfers), inside a HAL call of a streaming
    firmware: the firmware's step is left as the call returns (it wrote nothing more on its UART: no frame built on
    MISO words the call never produced), run raises the interrupt as it came (the exception in a FirmwareError
    naming the call), and every later run and set_pattern refuse, saying which call was cut short, when and by
    what; so does a new co-simulation on that board.  The step went on with the zeros, and the next run on a board
    whose record was half-updated."""
    import signal

    from bench.hosts.driver import CMD_START, encode

    out = bytearray()
    board = VirtualBoard(default_sensors(1), uart_out=out.extend)
    sim = CoSim(board)
    sim.set_pattern(["PDC"])
    board.send_to_firmware(encode(CMD_START))
    sent_then = []

    def ctrl_c(board):
        sent_then.append(len(out))
        signal.raise_signal(signal.SIGINT)  # (Python raises KeyboardInterrupt here, as the handler returns)

    def sensor_fails(*args, **kw):
        sent_then.append(len(out))
        raise RuntimeError("the stimulus went away")

    def cut_short(board):
        board.sensors[1].sample = sensor_fails

    board.at(0.05, ctrl_c if cut == "ctrl-c" else cut_short)
    try:
        with pytest.raises(KeyboardInterrupt if cut == "ctrl-c" else FirmwareError):
            sim.run(0.1)
        assert len(out) == sent_then[0] > 1000  # streamed until the cut, nothing after
        said = (rf"the HAL call \w+ at virtual time 0\.050\d+ s was cut short by "
                rf"{'KeyboardInterrupt' if cut == 'ctrl-c' else 'RuntimeError'}\(.*\): the board's record of time and "
                rf"of its sensors may be half-updated; the bench left the firmware's bt_step as that call returned; "
                rf"this co-simulation does not run again: make a new one")
        assert sim.stopped
        with pytest.raises(FirmwareError, match=said):
            sim.run(0.1)
        with pytest.raises(FirmwareError, match="set_pattern: " + said):
            sim.set_pattern(["PDC"])
        assert len(out) == sent_then[0]
        with pytest.raises(FirmwareError, match=r"the board: the HAL call \w+ at virtual time 0\.050\d+ s was cut "
                                                r"short by .*: its record of time and of its sensors may be "
                                                r"half-updated; make a new VirtualBoard for a new co-simulation"):
            CoSim(board)  # (a firmware started on it would build on that record)
    finally:
        board.bus.close()


def test_ctrl_c_after_a_refused_hal_call_in_the_same_step_is_still_a_keyboard_interrupt(tmp_path):
    """A refused HAL call (a select code out of range: its ValueError kept, the step going on) and then, in the same
    step, Ctrl-C: run's caller gets the KeyboardInterrupt — the earlier refusal must not hide it (a program stopped
    with Ctrl-C would have reported a firmware fault and gone on)."""
    import signal

    sim = _sim(tmp_path, "b->hal->spi_bytes(b->hal->ctx, 200, 0, tx, rx, 2);")
    sim.board.at(0.0205, lambda board: signal.raise_signal(signal.SIGINT))  # after the refusal at 0.020425 s
    try:
        with pytest.raises(KeyboardInterrupt):
            sim.run(0.1)
        assert sim.board.t < 0.03  # (the step of the refusal)
    finally:
        sim.board.bus.close()
