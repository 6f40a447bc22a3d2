"""Hostile input: every scene file and command line of the corpus in ``fixtures/hostile/`` ends in a clear error
naming the file (or the flag) and the value — no traceback, no hang — and the few files that are valid on purpose
load, run and are recorded whole.

The corpus is data: ``scenes.json`` says what :func:`load_scene` must do with each file of ``scenes/`` (and with
a few paths that are not files), ``cli.json`` lists argument vectors for :func:`bench.cli.main.main` with the exit
status and the words their error must hold.  Entries marked ``known_open`` are holes in commands outside the
scene tools; they are reported as expected failures and not run (they would run for minutes).
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from bench.cli import main as cli
from bench.errors import SceneError
from bench.paths import REPO
from bench.scenes.scene import MAX_SCENE_BYTES, load_scene

pytestmark = pytest.mark.unit

HOSTILE = REPO / "fixtures" / "hostile"
SCENE_FILES = HOSTILE / "scenes"
SCENES = json.loads((HOSTILE / "scenes.json").read_text(encoding="utf-8"))["scenes"]
INVOCATIONS = json.loads((HOSTILE / "cli.json").read_text(encoding="utf-8"))["invocations"]
CASE_LIMIT_S = 20.0  # no case may take longer: a hang fails the test instead of wedging the suite
COMPILE_LIMIT_S = 300.0  # the first slide of a process compiles the sliding kernels (numba, cold cache)
HEADLINE = re.compile(r"^(error: |biotac-bench[\w -]*: error: )")


class Hang(BaseException):
    """Raised by the alarm when a case runs past its limit (a BaseException: nothing in the bench catches it)."""


@contextlib.contextmanager
def time_limit(seconds: float, what: str):
    def on_alarm(signum, frame):
        raise Hang(f"{what}: still running after {seconds:g} s")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def _fill(text: str, tmp: Path) -> str:
    return text.replace("{repo}", str(REPO)).replace("{scenes}", str(SCENE_FILES)).replace("{tmp}", str(tmp))


def _scene_id(e: dict) -> str:
    return e.get("file") or e.get("make") or e["note"].replace(" ", "-")


def _scene_path(e: dict, tmp: Path) -> str:
    if "file" in e:
        return str(SCENE_FILES / e["file"])
    if "path" in e:
        return _fill(e["path"], tmp)
    if e["make"] == "huge":  # a valid scene padded past the limit: too big to commit
        p = tmp / "huge.toml"
        pad = ("# " + "x" * 97 + "\n") * (int(1.2 * MAX_SCENE_BYTES) // 100)
        p.write_text('[scene]\nname = "huge"\nduration_s = 1.0\n' + pad)
        return str(p)
    if e["make"] == "fifo":  # a named pipe nobody writes to: opening it would block
        p = tmp / "pipe.toml"
        os.mkfifo(p)
        return str(p)
    raise AssertionError(f"unknown corpus entry {e}")


# --- the corpus itself -----------------------------------------------------------------------------------------


def test_the_corpus_is_large_and_every_file_is_described():
    described = {e["file"] for e in SCENES if "file" in e}
    on_disk = {p.name for p in SCENE_FILES.iterdir()}
    assert described == on_disk, (f"undescribed: {sorted(on_disk - described)}, "
                                  f"missing: {sorted(described - on_disk)}")
    hostile = [e for e in SCENES if not e.get("valid")]
    assert len(hostile) + len(INVOCATIONS) >= 200 and len(hostile) >= 200
    for e in SCENES:
        assert e.get("valid") or e["expect"], f"{_scene_id(e)}: say what its error must contain"
    kinds = {c["argv"][0] for c in INVOCATIONS if c["argv"]}
    assert kinds >= {"run", "validate", "scenes", "params", "textures", "claims", "benchmark", "texture-sweep",
                     "explore"}
    assert sum(1 for c in INVOCATIONS if c.get("subprocess") and not c.get("known_open")) >= 5


def test_the_validator_knows_the_impact_rule_the_analysis_applies():
    from bench.scenes import scene
    from bench.verification.analysis import DetectionRule

    rule = DetectionRule()
    assert (scene.IMPACT_RULE_MIN_POINTS, scene.IMPACT_RULE_WINDOW_S) == (rule.min_points, rule.window_s)


# --- scene files ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("entry", [e for e in SCENES if not e.get("valid")], ids=_scene_id)
def test_a_hostile_scene_is_refused_with_the_file_field_and_value(entry, tmp_path):
    path = _scene_path(entry, tmp_path)
    with time_limit(CASE_LIMIT_S, _scene_id(entry)), pytest.raises(SceneError) as e:
        load_scene(path)
    message = str(e.value)
    first = message.splitlines()[0]
    assert "\0" in path or first.startswith(f"{path}: "), f"the message must name the file: {first[:200]!r}"
    for needle in entry["expect"]:
        assert needle in message, f"{needle!r} not in: {message[:1000]}"
    assert all(len(p) <= 4000 for p in e.value.problems), "a problem line must stay readable (values shortened)"


@pytest.fixture(scope="module")
def sliding_kernels_compiled():
    """Compile the sliding model's numba kernels once, outside :data:`CASE_LIMIT_S`: on a clean checkout the first
    slide of a process compiles them (about 10 s idle, more on a loaded machine), which the case limit — there to
    catch hangs — is not meant to measure."""
    from bench.running.runner import run_scene

    path = SCENE_FILES / "valid-slide-at-the-edges.toml"
    with time_limit(COMPILE_LIMIT_S, f"{path.name} (compiling the sliding kernels)"):
        assert run_scene(load_scene(path), progress=False, chunk_s=0.25).status == "ok"


# no numpy overflow or invalid value on the way (a NaN or Inf on its way to a code): the steepest sweep the validator
# accepts once overflowed past its end (emulator.stimuli.Vibration now evaluates its phase within its duration only)
@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("entry", [e for e in SCENES if e.get("valid")], ids=_scene_id)
def test_a_scene_valid_on_purpose_loads_runs_and_is_recorded_whole(entry, tmp_path, sliding_kernels_compiled):
    from bench.reporting.report import write_outputs
    from bench.running.runner import run_scene

    path = _scene_path(entry, tmp_path)
    with time_limit(CASE_LIMIT_S, _scene_id(entry)):
        scene = load_scene(path)
        if "stimuli" in entry:  # every instant of every list is a stimulus of its own
            assert len(scene.stimuli) == entry["stimuli"]
        rec = run_scene(scene, progress=False, chunk_s=0.25)
        assert rec.status == "ok" and rec.error is None, rec.error
        record = write_outputs(rec, tmp_path / "out", plots=False)
    assert record["status"] == "ok", record["error"]
    text = Path(path).read_bytes().decode("utf-8-sig")
    assert record["scene"]["text"] == text and record["faults"] == scene.faults
    assert record["host"]["spi"] == scene.spi and record["analysis"]["impact_detection"] == scene.impact_detection
    if scene.impact_detection:
        assert sum(d["drops"] for d in record["impact_detection"]["spheres"].values()) == sum(
            1 for s in scene.stimuli if type(s).__name__ == "SphereDrop")
    if "sliding" in record:
        assert len(record["sliding"]["trials"]) == sum(1 for s in scene.stimuli if type(s).__name__ == "Slide")


# --- command lines ----------------------------------------------------------------------------------------------


def _cli_id(c: dict) -> str:
    return " ".join(a if len(a) < 40 else a[:20] + "..." for a in c["argv"]).replace("\0", "\\0") or "(none)"


def _cli_params(subprocess_only=False):
    out = []
    for c in INVOCATIONS:
        if subprocess_only and (not c.get("subprocess") or c.get("known_open")):
            continue
        marks = [pytest.mark.xfail(reason=c["known_open"], run=False)] if c.get("known_open") else []
        out.append(pytest.param(c, marks=marks, id=_cli_id(c)))
    return out


def _check_output(c: dict, status, err: str):
    assert "Traceback" not in err, err[-3000:]
    assert status == c["status"], f"exit status {status}, expected {c['status']}; stderr: {err[-1500:]}"
    for needle in c["expect"]:
        assert needle in err, f"{needle!r} not in stderr: {err[-1500:]}"
    if c["status"] == 2:
        headlines = [line for line in err.splitlines() if HEADLINE.match(line)]
        assert len(headlines) == 1, f"one error line expected: {err[-1500:]}"


@pytest.mark.parametrize("case", _cli_params())
def test_a_hostile_command_line_ends_in_one_clear_error(case, tmp_path, monkeypatch, capsys):
    argv = [_fill(a, tmp_path) for a in case["argv"]]
    monkeypatch.chdir(tmp_path)  # a default out/ folder, if anything made one, lands here
    with time_limit(CASE_LIMIT_S, _cli_id(case)):
        try:
            status = cli.main(argv)
        except SystemExit as e:  # argparse
            status = e.code
    _check_output(case, status, capsys.readouterr().err)


@pytest.mark.parametrize("case", _cli_params(subprocess_only=True))
def test_no_traceback_escapes_a_real_process(case, tmp_path):
    argv = [_fill(a, tmp_path) for a in case["argv"]]
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-m", "bench.cli", *argv], capture_output=True, text=True, cwd=tmp_path,
                         env=env, timeout=60)
    _check_output(case, out.returncode, out.stderr)
    assert not (tmp_path / "out").exists(), "a refused command must not write anything"


def test_command_line_overrides_are_validated_run_and_recorded(tmp_path, capsys):
    scene = SCENE_FILES / "valid-faults-combined.toml"
    out = tmp_path / "o"
    with time_limit(CASE_LIMIT_S, "run with overrides"):
        status = cli.main(["run", str(scene), "--seed", "7", "--fidelity", "fast", "--out", str(out), "--quiet",
                           "--no-plots"])
    assert status == 0, capsys.readouterr().err
    record = json.loads((out / "record.json").read_text())
    assert record["scene"]["seed"] == 7 and record["scene"]["fidelity"] == "fast"
    assert record["scene"]["overrides"] == {"scene.fidelity": "fast", "scene.seed": 7}
    assert record["scene"]["text"] == scene.read_text(encoding="utf-8")
    assert record["faults"] == {"electrode_open": [3], "electrode_short": [4], "mux_stuck": 5, "thermistor": "short",
                                "heater_failed": True}
    assert record["host"]["spi"] == "software"


@pytest.mark.parametrize("levels, refused", [(16, False), (17, True)])
def test_a_scene_may_nest_16_tables_deep_and_no_more(tmp_path, levels, refused):
    """README: a scene file is nested at most 16 levels: a key inside 16 tables is read (and then refused only as
    an unknown table), one inside 17 is refused for its depth, naming the field."""
    f = tmp_path / "deep.toml"
    path = ".".join(f"t{i}" for i in range(1, levels + 1))
    f.write_text(f'[scene]\nname = "deep"\nduration_s = 1.0\n[{path}]\nk = 1\n')
    with pytest.raises(SceneError) as e:
        load_scene(f)
    problems = "\n".join(e.value.problems)
    assert ("nested more than 16 arrays or tables deep" in problems) == refused, problems
    assert (f"{path}: nested" in problems) if refused else 'unknown field "t1"' in problems


def test_a_field_without_a_unit_is_named_without_an_empty_one():
    """A number without a unit (the seed) is refused in plain words: no "in  (", no ", 0 to" left from an empty
    unit."""
    with pytest.raises(SceneError) as e:
        from bench.scenes.scene import parse_scene

        parse_scene({"scene": {"name": "x", "duration_s": 1.0, "seed": "a"}})
    assert e.value.problems == ['scene.seed = "a": must be a whole number (0 to 9223372036854775807)']
