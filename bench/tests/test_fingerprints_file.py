"""``python -m bench.verification.benchmark OUT.json [OLD.json]`` writes OUT.json whole or not at all: a write that
fails (a full disk, here the file-size limit RLIMIT_FSIZE in the child process, whose writes past it fail with
EFBIG) leaves an earlier OUT.json as it was and no temporary file, and says so in one line naming OUT.json; an
OLD.json that cannot be read is one line naming it, not a traceback."""

import json
import os
import resource
import subprocess
import sys

import pytest

from bench.paths import REPO, SCENES_DIR

pytestmark = pytest.mark.unit

#: a tenth of a second of the shipped rest scene: 3 profiles × 4 seeds of it, about 800 bytes of fingerprints
_SHORT_REST = (SCENES_DIR / "rest.toml").read_text(encoding="utf-8").replace("duration_s = 10.0", "duration_s = 0.1")


def _fingerprints(tmp_path, *argv, file_size_limit=None) -> subprocess.CompletedProcess:
    """The fingerprints module run in a child process over a folder holding the short rest scene; with
    ``file_size_limit`` (bytes) no file the child writes grows past it (no bytecode is written: CPython would
    place a .pyc cut short by the limit, which later imports fail to read)."""
    scenes = tmp_path / "scenes"
    scenes.mkdir(exist_ok=True)
    (scenes / "rest.toml").write_text(_SHORT_REST, encoding="utf-8")

    def limit():
        if file_size_limit is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (file_size_limit, file_size_limit))

    return subprocess.run([sys.executable, "-m", "bench.verification.benchmark", *map(str, argv), "--scenes",
                           str(scenes)], cwd=REPO, capture_output=True, text=True, preexec_fn=limit, timeout=600,
                          env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})


def test_a_write_that_fails_leaves_the_earlier_file_whole_and_says_so_in_one_line(tmp_path):
    warm = tmp_path / "warm" / "prints.json"  # numba's caches written first (the limit would refuse them)
    assert _fingerprints(tmp_path, warm).returncode == 0
    out = tmp_path / "prints.json"
    out.write_text('{"rest/fast/seed+0": "earlier"}\n')
    r = _fingerprints(tmp_path, out, file_size_limit=200)
    assert r.returncode == 2, r.stderr
    assert out.read_text() == '{"rest/fast/seed+0": "earlier"}\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["prints.json", "scenes", "warm"]  # no temporary file left
    assert r.stderr == (f"error: OUT.json {out}: not written (File too large); an earlier file there is left as it "
                        f"was\n")


def test_the_written_file_and_a_comparison_with_an_unreadable_old_file(tmp_path):
    out, old = tmp_path / "new" / "prints.json", tmp_path / "old.json"
    old.write_text("[1, 2]")
    r = _fingerprints(tmp_path, out, old)
    assert r.returncode == 2 and r.stderr == (f"error: OLD.json {old}: not fingerprints (a JSON object of run -> "
                                              f"fingerprint)\n")

    prints = json.loads(out.read_text(encoding="utf-8"))
    assert sorted(prints) == sorted(f"rest/{p}/seed+{k}" for p in ("fast", "default", "reference")
                                    for k in (0, 1, 5, 11))
    r = _fingerprints(tmp_path, tmp_path / "again.json", tmp_path / "missing\n.json")
    assert r.returncode == 2
    assert r.stderr == (f"error: OLD.json {tmp_path}/missing\\n.json: cannot be read as JSON (No such file or "
                        f"directory)\n")
    r = _fingerprints(tmp_path, tmp_path / "again.json", out)
    assert r.returncode == 0 and r.stdout.endswith("12 runs, 0 with different codes\n")


def test_ctrl_c_while_fingerprinting_writes_nothing_and_says_so(tmp_path):
    import signal

    scenes = tmp_path / "scenes"
    scenes.mkdir()
    (scenes / "rest.toml").write_text(_SHORT_REST, encoding="utf-8")
    out = tmp_path / "prints.json"
    out.write_text("earlier\n")
    p = subprocess.Popen([sys.executable, "-m", "bench.verification.benchmark", str(out), "--scenes", str(scenes)],
                         cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline().startswith("rest/fast/seed+0")  # working: the first run fingerprinted
    p.send_signal(signal.SIGINT)
    rest, err = p.communicate(timeout=120)
    assert p.returncode == 130
    assert err == "interrupted (Ctrl-C): no file written; an earlier one is left as it was\n"
    assert out.read_text() == "earlier\n" and sorted(p.name for p in tmp_path.iterdir()) == ["prints.json", "scenes"]


def test_a_second_command_writing_the_same_file_is_refused_while_the_first_writes_it(tmp_path):
    """Two real processes on one OUT.json: the first holds the lock beside it (.prints.json.lock) from start to end,
    so the second is refused at once — exit status 2, one line naming the first's pid, the file untouched — rather
    than both writing it and the last silently replacing the other's.  The first is held still (SIGSTOP) while the
    second runs, so the two overlap however fast the machine.  A temporary file a killed writer left beside it is
    removed by the next command, and named."""
    import signal

    scenes = tmp_path / "scenes"
    scenes.mkdir()
    (scenes / "rest.toml").write_text(_SHORT_REST, encoding="utf-8")
    out = tmp_path / "prints.json"
    out.write_text("earlier\n")
    left = tmp_path / ".prints.json.k1ll3d00.part"  # (as bench.atomic.temp_path names them)
    left.write_text('{"rest/fast/seed+0": "half')
    first = subprocess.Popen([sys.executable, "-m", "bench.verification.benchmark", str(out), "--scenes",
                              str(scenes)], cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert first.stdout.readline().startswith("rest/fast/seed+0")  # working, the lock held
        first.send_signal(signal.SIGSTOP)
        try:
            second = _fingerprints(tmp_path, out)
        finally:
            first.send_signal(signal.SIGCONT)
        assert second.returncode == 2, second.stderr
        assert second.stderr == (f"error: OUT.json {out}: another fingerprint run (pid {first.pid}) is writing this "
                                 f"file; wait for it to end or choose another OUT.json\n")
        assert out.read_text() == "earlier\n"
        rest, err = first.communicate(timeout=600)
    finally:
        if first.poll() is None:  # (a failed check above: the first is not left running)
            first.kill()
            first.communicate()
    assert first.returncode == 0, err
    assert err == (f"note: OUT.json {out}: removed 1 temporary file that an interrupted fingerprint run left, killed "
                   f"(or the machine down) before it could clean up, partial writes and never results: {left.name}\n")
    assert len(json.loads(out.read_text(encoding="utf-8"))) == 12
    assert sorted(p.name for p in tmp_path.iterdir()) == ["prints.json", "scenes"]  # the lock file removed

