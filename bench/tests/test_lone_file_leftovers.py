"""A lone output file (``campaign --junit``, ``record --out``) is written under a temporary name beside it and
renamed into place, under a lock beside it (:class:`bench.reporting.outdir.OutFile`): a command killed as it writes
(SIGKILL, the OOM killer, a power cut) leaves no half-written file under the final name, only ``.NAME.<random>.part``;
the next command writing that file removes those and names them on stderr, and never removes anything else (a
recording kept on purpose, another file's temporary file, a link)."""

import os
import signal
import subprocess
import sys

import pytest

from bench.paths import REPO
from bench.reporting.outdir import OutDirError, OutFile
from bench.tests.test_record_race import FRAMES, _assert_a_whole_recording, _record

pytestmark = pytest.mark.unit

#: a process writing a report as the campaign does (its lock, then the file under its temporary name), stopped
#: halfway: what a campaign killed while it wrote its --junit report leaves
_HALF_WRITTEN = """
import sys, time
from bench.atomic import atomic_write
from bench.reporting.outdir import OutFile

with OutFile.open(sys.argv[1], "--junit", "campaign", "this report") as out, atomic_write(out.path) as tmp:
    tmp.write_bytes(b'<?xml version="1.0" encoding="utf-8"?>\\n<testsuite name="biotac-fault-campaign" tests="3"')
    print("writing", flush=True)
    time.sleep(600)
"""


def _temps(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".part"))


def _killed_while_writing(report) -> list[str]:
    """Run :data:`_HALF_WRITTEN` for ``report`` in a process of its own and SIGKILL it mid-write; the temporary
    files it left."""
    env = dict(os.environ, PYTHONPATH=str(REPO))
    with subprocess.Popen([sys.executable, "-c", _HALF_WRITTEN, str(report)], stdout=subprocess.PIPE, text=True,
                          env=env) as proc:  # (leaving it closes the pipe and waits for the process)
        try:
            assert proc.stdout.readline() == "writing\n"
        finally:
            proc.send_signal(signal.SIGKILL)
    return _temps(report.parent)


def test_a_campaign_killed_as_it_wrote_its_report_leaves_none_and_the_next_removes_what_it_left(tmp_path, capsys):
    from bench.cli import main as cli

    report = tmp_path / "c.xml"
    left = _killed_while_writing(report)
    assert len(left) == 1 and left[0].startswith(".c.xml.") and not report.exists()
    assert (tmp_path / ".c.xml.lock").exists()  # (its holder's flock went with it)
    status = cli.main(["campaign", "--faults", "none", "--scenes", "rest", "--junit", str(report),
                       "--scheduler", "tcp://127.0.0.1:9"])  # no scheduler there: the report says it could not run
    err = capsys.readouterr().err
    assert status == 2 and "Traceback" not in err
    assert (f"note: --junit {report}: removed 1 temporary file that an interrupted campaign left, killed (or the "
            f"machine down) before it could clean up, partial writes and never results: {left[0]}") in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.xml"]  # the leftover and the lock gone
    assert b"the campaign could not run" in report.read_bytes()


def test_a_second_writer_is_refused_while_the_first_writes(tmp_path):
    """The lock makes "another command's temporary file" impossible while the leftovers are removed."""
    report = tmp_path / "c.xml"
    with OutFile.open(report, "--junit", "campaign", "this report") as first:
        tmp = first.path.parent / ".c.xml.abcd1234.part"
        tmp.write_text("being written")
        with pytest.raises(OutDirError, match=r"--junit .*c\.xml: another campaign \(pid \d+\) is writing this "
                                              r"report; wait for it to end or choose another --junit"):
            OutFile.open(report, "--junit", "campaign", "this report")
        assert tmp.read_text() == "being written"
    assert sorted(p.name for p in tmp_path.iterdir()) == [".c.xml.abcd1234.part"]  # (not its leftover: kept)


def test_a_folder_made_for_the_file_is_removed_again_when_nothing_was_written(tmp_path):
    with OutFile.open(tmp_path / "a" / "b" / "c.xml", "--junit", "campaign", "this report"):
        assert (tmp_path / "a" / "b").is_dir()
    assert list(tmp_path.iterdir()) == []


def test_the_next_record_removes_a_killed_records_partial_files_and_keeps_everything_else(tmp_path, monkeypatch,
                                                                                           capsys):
    """Only regular files named as this file's (or its CSV's) temporary files are leftovers; a recording kept on
    purpose (``r.kept-….npz``), another file's temporary file, a link named as a leftover and the target it points
    at stay as they were."""
    out = tmp_path / "r.npz"
    partial = [".r.csv.0a1b2c3d.part", ".r.npz.9vq5khgi.part"]
    for name in partial:
        (tmp_path / name).write_bytes(b"PK\x03\x04 half written")
    theirs = {"r.kept-0123abcd.npz": "a recording kept on purpose", ".notes.txt.abcdefgh.part": "not ours",
              "precious.txt": "keep me"}
    for name, text in theirs.items():
        (tmp_path / name).write_text(text)
    (tmp_path / ".r.npz.zzzzzzzz.part").symlink_to(tmp_path / "precious.txt")
    assert _record(monkeypatch, out, "--csv") == 0
    captured = capsys.readouterr()
    assert (f"note: --out {out}: removed 2 temporary files that an interrupted record left, killed (or the machine "
            f"down) before it could clean up, partial writes and never results: {', '.join(partial)}") in captured.err
    assert f"wrote {out}" in captured.out and f"{FRAMES} frames" in captured.out
    _assert_a_whole_recording(out)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([*theirs, ".r.npz.zzzzzzzz.part", "r.csv", "r.npz"])
    assert all((tmp_path / name).read_text() == text for name, text in theirs.items())


def test_a_record_with_nothing_left_says_nothing_and_leaves_no_lock(tmp_path, monkeypatch, capsys):
    out = tmp_path / "r.npz"
    assert _record(monkeypatch, out) == 0
    assert "note:" not in capsys.readouterr().err
    assert [p.name for p in tmp_path.iterdir()] == ["r.npz"]


@pytest.mark.parametrize("stop", [OSError(28, "No space left on device"), KeyboardInterrupt()], ids=["full", "ctrl-c"])
def test_a_temporary_file_whose_writing_fails_or_is_stopped_is_removed(tmp_path, stop):
    """:func:`bench.atomic.written_temp` (record's NPZ and CSV): a full disk or a Ctrl-C halfway leaves nothing."""
    from bench.atomic import written_temp

    def write(fh):
        fh.write(b"half")
        raise stop

    with pytest.raises(type(stop)):
        written_temp(tmp_path / "r.npz", write)
    assert list(tmp_path.iterdir()) == []
    tmp = written_temp(tmp_path / "r.npz", lambda fh: fh.write(b"whole"))
    assert tmp.read_bytes() == b"whole" and tmp.name.startswith(".r.npz.") and tmp.name.endswith(".part")
