"""``rtl vectors --waves``: the simulator dumps its waveform into a hidden folder of its own, renamed into the build
folder only once the simulator has exited cleanly — an error or Ctrl-C mid-dump leaves no half file under the final
name (and the last complete waveform in place), and no hidden folder behind."""

import json
import os

import pytest

pytestmark = pytest.mark.unit


class FakeRunner:
    """cocotb's runner standing in: ``test()`` writes ``dump.vcd`` into its test folder — half of it, then
    ``fail`` raised, if ``fail`` is given — and the bench's result."""

    def __init__(self, fail: BaseException | None = None):
        self.fail = fail
        self.test_dirs = []

    def test(self, test_dir: str, **kw):
        self.test_dirs.append(test_dir)
        with open(os.path.join(test_dir, "dump.vcd"), "w") as f:
            f.write("$timescale 1ps $end\n")
            if self.fail is not None:
                f.flush()
                raise self.fail
            f.write("#0\n$end\n")
        with open(os.environ["BIOTAC_RESULT"], "w") as f:
            json.dump({"ok": True}, f)


def _rtl(tmp_path, runner):
    from emulator.rtl.runner import Rtl

    rtl = Rtl(tmp_path, waves=True)
    rtl.runner = runner
    return rtl


def test_a_complete_waveform_is_renamed_into_the_build_folder(tmp_path):
    runner = FakeRunner()
    rtl = _rtl(tmp_path, runner)
    assert rtl._run("vectors", {}) == {"ok": True}
    (test_dir,) = runner.test_dirs
    assert os.path.dirname(test_dir) == str(tmp_path) and os.path.basename(test_dir).startswith(".vectors.")
    assert (tmp_path / "dump.vcd").read_text() == "$timescale 1ps $end\n#0\n$end\n"
    assert rtl.wave_files() == [tmp_path / "dump.vcd"] and not os.path.exists(test_dir)


@pytest.mark.parametrize("fail", [RuntimeError("Command failed with return code: 134"), KeyboardInterrupt()],
                         ids=["simulator failed", "Ctrl-C"])
def test_a_dump_cut_short_leaves_the_last_complete_waveform_and_no_half_file(tmp_path, fail):
    (tmp_path / "dump.vcd").write_text("the last complete dump")
    runner = FakeRunner(fail)
    with pytest.raises(type(fail)):
        _rtl(tmp_path, runner)._run("vectors", {})
    assert (tmp_path / "dump.vcd").read_text() == "the last complete dump"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dump.vcd"]  # no hidden folder, no half file


#: ``biotac-bench rtl vectors --waves`` with the simulator standing in: it writes half a waveform, then this process
#: is sent SIGTERM (as ``kill PID`` or ``timeout`` sends it) while the simulation runs.
SIGTERM_MID_DUMP = """
import os, signal, sys, time
from pathlib import Path
from emulator.rtl import runner as R
build_dir = Path(sys.argv[1])
R.build_dir_for = lambda sp=0, waves=False: build_dir
R.Rtl.build = lambda self: None

class Simulator:
    def test(self, test_dir, **kw):
        with open(os.path.join(test_dir, "dump.vcd"), "w") as f:
            f.write("$timescale 1ps $end\\n")
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(30)

real_init = R.Rtl.__init__
def init(self, *args, **kwargs):
    real_init(self, *args, **kwargs)
    self.runner = Simulator()
R.Rtl.__init__ = init
from bench.cli.main import main
sys.exit(main(["rtl", "vectors", "fixtures/spi_vectors/properties.json", "--waves"]))
"""


def test_sigterm_during_rtl_vectors_leaves_no_half_waveform_and_says_terminated(tmp_path):
    """SIGTERM mid-dump: the command stops as on Ctrl-C ("terminated", exit status 143), and its build folder holds
    neither the half waveform nor the hidden folder it was written in (SIGTERM had ended the process on the spot,
    leaving the folder behind)."""
    import subprocess
    import sys
    from pathlib import Path

    repo = Path(__file__).resolve().parents[2]
    build_dir = tmp_path / "waves"
    build_dir.mkdir()
    r = subprocess.run([sys.executable, "-c", SIGTERM_MID_DUMP, str(build_dir)], cwd=repo, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 143 and r.stderr.strip().endswith("terminated"), (r.returncode, r.stderr[-2000:])
    assert list(build_dir.iterdir()) == []
