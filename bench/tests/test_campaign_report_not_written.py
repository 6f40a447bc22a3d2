"""A campaign whose JUnit report cannot be written (a full disk or a quota; here the file-size limit RLIMIT_FSIZE in
the child process, whose writes past it fail with EFBIG): exit status 1 (the work was done, its report not
written), one error line naming the file and saying what is there, the summary of the results printed, no
half-written XML and no temporary file left, an earlier campaign's report there kept whole.  The campaign is real
(one case on Dask, the firmware and driver through a pty); the children write no bytecode, which the limit would
cut short."""

import os
import resource
import subprocess
import sys

import pytest

from bench.paths import REPO

pytestmark = pytest.mark.firmware

#: below the smallest report a campaign writes (one case: about 750 bytes; one error, about 600), above its lock
#: file (a pid)
REPORT_TOO_LARGE_B = 300


def _campaign(report, *extra, file_size_limit=None) -> subprocess.CompletedProcess:
    """``biotac-bench campaign`` in a child process, one case (fault none in scene rest, seed 0) on one worker
    (unless ``extra`` names a scheduler); with ``file_size_limit`` (bytes) no file it or its workers write grows past it."""

    def limit():
        if file_size_limit is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (file_size_limit, file_size_limit))

    return subprocess.run([sys.executable, "-m", "bench.cli", "campaign", "--faults", "none", "--scenes", "rest",
                           "--quiet", "--junit", str(report),
                           *(extra if "--scheduler" in extra else ["--workers", "1", *extra])],
                          cwd=REPO, capture_output=True, text=True, preexec_fn=limit, timeout=600,
                          env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})


def _errors(stderr: str) -> list[str]:
    assert "Traceback" not in stderr, stderr
    return [line for line in stderr.splitlines() if line.startswith("error:")]


def test_a_report_that_cannot_be_written_keeps_the_earlier_one_and_says_so(tmp_path):
    report = tmp_path / "c.xml"
    first = _campaign(report)  # the earlier campaign's report (and the firmware and numba caches, made unlimited)
    assert first.returncode == 0, first.stderr
    earlier = report.read_bytes()
    assert len(earlier) > REPORT_TOO_LARGE_B

    r = _campaign(report, file_size_limit=REPORT_TOO_LARGE_B)
    assert r.returncode == 1, r.stderr
    assert _errors(r.stderr) == [f"error: --junit {report}: the JUnit XML could not be written (File too large); "
                                 f"the file there is an earlier campaign's report, left as it was; the summary "
                                 f"above holds the results"], r.stderr
    assert r.stdout.splitlines()[-1] == "1 passed, 0 failed" and "JUnit XML:" not in r.stdout, r.stdout
    assert report.read_bytes() == earlier
    assert [p.name for p in tmp_path.iterdir()] == ["c.xml"]  # no temporary file; the lock file removed


def test_a_stopped_campaigns_report_that_cannot_be_written_says_no_file_is_there(tmp_path):
    """A campaign that could not run (no scheduler at the address) whose report saying so cannot be written: exit
    status 2, one line, and no file left at all (neither half an XML nor the folder it made for it)."""
    report = tmp_path / "out" / "c.xml"
    r = _campaign(report, "--scheduler", "tcp://127.0.0.1:9", file_size_limit=REPORT_TOO_LARGE_B)
    assert r.returncode == 2, r.stderr
    errors = _errors(r.stderr)
    assert f"error: --junit {report}: the report saying so could not be written (File too large)" in errors, r.stderr
    assert not any("earlier campaign" in line for line in errors), errors
    assert list(tmp_path.iterdir()) == []
