"""biotac-bench: run scenes against the emulated BioTac, check the published figures, measure costs.

Each command group lives in its own module with an ``add_commands(sub, fmt)`` function; :func:`command_groups`
joins them into one parser, in the order ``--help`` lists them.  They are imported inside :func:`main` (numpy
and the emulator take a tenth of a second): a Ctrl-C that early is "interrupted", not a traceback.
"""

from __future__ import annotations

import argparse
import os
import select
import signal
import sys

from bench.errors import OutputNotWritten


MAIN_HELP = """\
An emulated BioTac fingertip — pressure (PDC, PAC), temperature (TDC, TAC) and 19 impedance electrodes at
sample level — behind its SPI protocol (software model or Verilog RTL), driven by scene files.

typical session:
  biotac-bench scenes                 # what ships: each scene's name, file and what it does
  biotac-bench run sphere_drops       # run one (a shipped scene's name or any scene file): samples.h5,
                                      #   codes.npz, record.json, report.md, plots in out/sphere-drops/
                                      #   (the folder is the scene's [scene] name)
  biotac-bench claims                 # check every published figure (PASS/FAIL table)
  biotac-bench noise-budget           # where the 1.4 bits of PAC noise come from
  biotac-bench benchmark              # what each fidelity profile costs and how wrong it is

Every subcommand has its own --help.  Exit status: 0 done, 1 a check failed (or results could not be written),
2 bad input (one line on stderr), 130 / 143 stopped by Ctrl-C / SIGTERM (the servers, bridge and cheetah serve,
whose normal end that is: 0), 141 the reader of the output went away (`biotac-bench params | head`).
"""


def command_groups() -> tuple:
    """The command groups' modules, in the order ``--help`` lists them."""
    from bench.cli import campaigns, cheetah, experiments, hosts, rtl, scenes, textures, units, verification

    return (scenes, units, textures, experiments, verification, rtl, hosts, cheetah, campaigns)


#: What a bare value after these commands was probably meant to be (``biotac-bench units 17``)
BARE_VALUE_HINTS = {"units": "a unit is chosen with --seed N or --serial BT... (biotac-bench units --seed 17)",
                    "textures": "one texture is shown with --show N (biotac-bench textures --show 30)"}

#: Exit status when the program reading our output has gone (``biotac-bench params | head -1``): 128 + SIGPIPE,
#: what a shell reports for a standard tool stopped by SIGPIPE.
READER_GONE = 128 + signal.SIGPIPE


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("biotac-bench")
    except PackageNotFoundError:  # run from a checkout that was not installed
        return "unknown (not installed)"


def build_parser() -> argparse.ArgumentParser:
    from bench.cli.args import HelpFormatter, OneLineErrorParser

    p = OneLineErrorParser(prog="biotac-bench", description=MAIN_HELP, formatter_class=HelpFormatter)
    p.add_argument("--version", action="version", version=f"biotac-bench {_version()}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for group in command_groups():
        group.add_commands(sub, HelpFormatter)
    return p


def _bad_input_errors() -> tuple[type[Exception], ...]:
    """The errors reported as one line on stderr with exit status 2.  The emulator's NumericalError (a NaN or Inf
    reached the ADC) is among them only once its module is loaded: it cannot have been raised before, and
    importing it would load numba for every command (even --help)."""
    from bench.errors import BenchError

    adc = sys.modules.get("emulator.adc")
    return (BenchError, ValueError, OSError) + ((adc.NumericalError,) if adc is not None else ())


def main(argv=None) -> int:
    """The command line (``argv``: its arguments; None: this process's own, as the ``biotac-bench`` script)."""
    if argv is None:
        sys.stdout = _StdoutThatSaysItFailed(sys.stdout)
    code = _main(argv)
    if argv is None:  # a process of its own: what remains is the interpreter's shutdown (~0.5 s after a run)
        _finish_on_a_late_signal()
    return code


class StdoutNotWritten(OutputNotWritten):
    """The command's output to stdout could not be written (exit status 1, as any output not written)."""


class _StdoutThatSaysItFailed:
    """The process's stdout, whose failed write (a full disk behind ``> results.json``, an I/O error) is raised as
    :class:`StdoutNotWritten`, so the command ends with exit status 1 and one line, not
    "error: [Errno 28]" under the bad-input status.  A reader that has gone (BrokenPipeError) passes through as it
    is: that has its own quiet ending."""

    def __init__(self, stream):
        self._stream = stream

    def _failed(self, e: OSError) -> StdoutNotWritten:
        return StdoutNotWritten(f"stdout: the output could not be written ({e.strerror or e}): what reached it is "
                                "cut short")

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            raise
        except OSError as e:
            raise self._failed(e) from e

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            raise
        except OSError as e:
            raise self._failed(e) from e

    def __getattr__(self, name):
        return getattr(self._stream, name)


def _finish_on_a_late_signal() -> None:
    """From here on a Ctrl-C or SIGTERM ends the exit at once, saying the command had finished (its outputs are
    complete and flushed), instead of a silent death by the signal in the middle of the interpreter's shutdown."""

    def finished(signum, frame):
        os.write(2, f"{signal.Signals(signum).name} after the command had finished: its outputs are complete\n"
                 .encode())
        os._exit(128 + signum)

    for s in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(s) is not signal.SIG_IGN:
            signal.signal(s, finished)


def _main(argv) -> int:
    try:
        try:
            parser = build_parser()
            argv = sys.argv[1:] if argv is None else list(argv)
            if not argv:  # no command: the help, which lists them, and the error
                parser.print_help()
                print("biotac-bench: error: the following arguments are required: COMMAND", file=sys.stderr)
                return 2
            args, extra = parser.parse_known_args(argv)
            if extra:
                hint = BARE_VALUE_HINTS.get(args.command, f"see {args.command_prog} --help")
                print(f"{args.command_prog}: error: unrecognized arguments: {' '.join(extra)}; {hint}",
                      file=sys.stderr)
                return 2
            from bench.paths import source_tree_problem

            problem = source_tree_problem()  # a copy installed without its source tree's files
            if problem:
                print(f"{args.command_prog}: error: {problem}", file=sys.stderr)
                return 2
            return args.func(args)
        finally:
            sys.stdout.flush()  # output still buffered meets a reader that has gone here, not in Python's exit
    except BrokenPipeError as e:
        if _stdout_reader_gone():
            _discard_stdout()
            return READER_GONE
        print(f"error: {e}", file=sys.stderr)
        return 2
    except _bad_input_errors() as e:  # evaluated when an exception arrives here, after the command ran
        print(f"error: {e}", file=sys.stderr)
        return getattr(e, "exit_status", 2)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


def _stdout_reader_gone() -> bool:
    """Whether stdout is a pipe (or socket) whose reader has closed it: poll reports an error on its write end.
    A broken pipe elsewhere (a child process, a socket) is a real error and reported as one."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, ValueError, OSError):  # not a file (captured output)
        return False
    poller = select.poll()
    poller.register(fd, select.POLLOUT)
    return any(events & (select.POLLERR | select.POLLHUP) for _, events in poller.poll(0))


def _discard_stdout() -> None:
    """Point stdout at /dev/null, so that what is still buffered is dropped quietly at exit (the Python
    documentation's recipe for SIGPIPE) instead of raising again."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)


if __name__ == "__main__":
    sys.exit(main())
