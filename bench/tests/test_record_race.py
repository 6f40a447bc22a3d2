"""``record`` checks --out at the start, and a file that appears there during a (long) recording is not replaced at
the end either unless --force: the recording is refused in one line naming the path, exit status 2, and kept beside
--out under a name of its own (``NAME.kept-<8 hex digits>.npz``, never a temporary name, which the next record would
take for an interrupted one's leftover), which the error names, so nothing is lost.  The placement replaces nothing by
construction (bench.atomic.commit_new: hard links, all or none), not by a check before a rename."""

import re

import numpy as np
import pytest

from bench.atomic import TEMP_SUFFIX, commit_new
from bench.cli import hosts
from bench.cli.main import main
from bench.hosts.driver import SLOT_RATE_HZ, DataFrame, FrameParser

pytestmark = pytest.mark.unit
FRAMES = 20
CHANNELS = np.array([0, 17, 40])  # PAC, E1, E24
SECONDS = FRAMES * len(CHANNELS) / SLOT_RATE_HZ  # the recording asked for: exactly FRAMES frames


class _Bridge:
    """A bridge streaming FRAMES frames of one sensor; ``meanwhile()`` runs halfway (another program at work)."""

    def __init__(self, meanwhile):
        self.meanwhile, self.disconnected = meanwhile, False
        self.parser = FrameParser()

    def start(self):
        pass

    def wait_for(self, command, timeout_s):
        return command

    def count_afresh(self, after_reply_to=None):
        self.parser.count_afresh()

    def frames(self, timeout_s):
        for seq in range(FRAMES):
            if seq == FRAMES // 2:
                self.meanwhile()
            yield DataFrame(seq, 0b1, CHANNELS, np.array([[seq], [20], [30]], np.uint16), np.zeros((3, 1), np.uint8))

    def stop(self):
        pass

    def close(self):
        pass


def _record(monkeypatch, out, *flags, meanwhile=lambda: None) -> int:
    """``biotac-bench record`` of FRAMES frames into ``out`` from a bridge that runs ``meanwhile`` halfway."""
    monkeypatch.setattr(hosts, "_open_driver", lambda port, baud: _Bridge(meanwhile))
    return main(["record", "bridge", "--out", str(out), "--seconds", repr(SECONDS), "--quiet", *flags])


def _kept(folder):
    """The files a refused recording was kept as in ``folder``, by the final name they were for; none of them a
    temporary file (nor any other temporary file left)."""
    assert not [p for p in folder.iterdir() if p.name.endswith(TEMP_SUFFIX)]
    kept = {m.group(1) + m.group(2): p for p in folder.iterdir()
            if (m := re.fullmatch(r"(.+)\.kept-[0-9a-f]{8}(\.npz|\.csv)", p.name))}
    assert len({p.name.split(".")[1] for p in kept.values()}) <= 1, kept  # an NPZ and its CSV: the same digits
    return kept


def _assert_a_whole_recording(npz):
    assert np.load(npz)["seq"].tolist() == list(range(FRAMES))


def test_an_npz_written_at_out_during_the_recording_is_not_replaced(tmp_path, monkeypatch, capsys):
    out = tmp_path / "r.npz"
    assert _record(monkeypatch, out, meanwhile=lambda: out.write_text("theirs")) == 2
    err = capsys.readouterr().err
    kept = _kept(tmp_path)
    assert list(kept) == ["r.npz"] and out.read_text() == "theirs"
    assert err == (f"error: --out {out}: {out} appeared during the recording (written by another program?) and is "
                   f"not replaced without --force; the recording is kept as {kept['r.npz']} (rename it to use it)\n")
    _assert_a_whole_recording(kept["r.npz"])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["r.npz", kept["r.npz"].name])


def test_an_npz_written_at_the_last_moment_is_not_replaced_either(tmp_path, monkeypatch, capsys):
    """The other program writes --out after every check record makes, as the finished file is flushed just before
    it takes its name: still not replaced (no check-then-rename)."""
    import bench.atomic as atomic

    out = tmp_path / "r.npz"
    flush = atomic._fsync_file

    def flush_then_another_program_writes(path):
        flush(path)
        out.write_text("theirs")

    monkeypatch.setattr(atomic, "_fsync_file", flush_then_another_program_writes)
    assert _record(monkeypatch, out) == 2
    assert f"{out} appeared during the recording" in capsys.readouterr().err
    assert out.read_text() == "theirs"
    _assert_a_whole_recording(_kept(tmp_path)["r.npz"])


def test_with_csv_neither_file_is_placed_when_the_csv_path_was_taken_meanwhile(tmp_path, monkeypatch, capsys):
    """All or none: the NPZ is not left in place without its CSV (nor the other program's CSV beside it)."""
    out, beside = tmp_path / "r.npz", tmp_path / "r.csv"
    assert _record(monkeypatch, out, "--csv", meanwhile=lambda: beside.write_text("theirs\n")) == 2
    err = capsys.readouterr().err
    kept = _kept(tmp_path)
    assert f"{beside} appeared during the recording" in err and "Traceback" not in err
    assert f"kept as {kept['r.npz']} and {kept['r.csv']}" in err
    assert not out.exists() and beside.read_text() == "theirs\n"
    _assert_a_whole_recording(kept["r.npz"])
    assert kept["r.csv"].read_text().startswith(hosts.RECORDING_CSV_HEADER + "\n0,0,PAC,1,0,0\n")


def test_a_csv_come_beside_out_meanwhile_is_not_left_beside_a_recording_it_does_not_match(tmp_path, monkeypatch,
                                                                                          capsys):
    out, beside = tmp_path / "r.npz", tmp_path / "r.csv"
    header = hosts.RECORDING_CSV_HEADER + "\n"  # another recording's CSV, even: neither removed nor mismatched
    assert _record(monkeypatch, out, meanwhile=lambda: beside.write_text(header)) == 2
    assert f"{beside} appeared during the recording" in capsys.readouterr().err
    assert not out.exists() and beside.read_text() == header and list(_kept(tmp_path)) == ["r.npz"]


def test_force_replaces_a_recording_that_appeared_meanwhile(tmp_path, monkeypatch, capsys):
    import numpy as np

    out = tmp_path / "r.npz"
    assert _record(monkeypatch, out, "--force",
                   meanwhile=lambda: np.savez(out, codes=np.zeros(1), layout=np.array("compact"))) == 0
    assert f"wrote {out}: {FRAMES} frames" in capsys.readouterr().out
    _assert_a_whole_recording(out)
    assert [p.name for p in tmp_path.iterdir()] == ["r.npz"]


def test_force_refuses_any_other_file_at_out_before_or_come_meanwhile(tmp_path, monkeypatch, capsys):
    """--force replaces only a recording: a file of the user's at --out is refused before the port opens, or when
    it appears during the recording (which is then kept under its temporary name)."""
    out = tmp_path / "r.npz"
    assert _record(monkeypatch, out, "--force", meanwhile=lambda: out.write_text("theirs")) == 2
    assert f"{out} appeared during the recording" in capsys.readouterr().err
    assert out.read_text() == "theirs" and list(_kept(tmp_path)) == ["r.npz"]
    _assert_a_whole_recording(_kept(tmp_path)["r.npz"])
    mine = tmp_path / "mine.npz"
    mine.write_text("my notes")
    assert _record(monkeypatch, mine, "--force") == 2
    assert "not a recording" in capsys.readouterr().err and mine.read_text() == "my notes"


def test_force_still_refuses_a_csv_that_is_not_a_recordings_come_meanwhile(tmp_path, monkeypatch, capsys):
    out, beside = tmp_path / "r.npz", tmp_path / "r.csv"
    assert _record(monkeypatch, out, "--csv", "--force", meanwhile=lambda: beside.write_text("my data\n")) == 2
    err = capsys.readouterr().err
    assert f"{beside} appeared during the recording (written by another program?) and is not replaced;" in err
    assert beside.read_text() == "my data\n" and not out.exists() and sorted(_kept(tmp_path)) == ["r.csv", "r.npz"]


def test_without_anything_in_the_way_the_files_go_in_place_and_no_temporary_file_stays(tmp_path, monkeypatch):
    out = tmp_path / "sub" / "r.npz"
    assert _record(monkeypatch, out, "--csv") == 0
    _assert_a_whole_recording(out)
    assert sorted(p.name for p in out.parent.iterdir()) == ["r.csv", "r.npz"]


# --- the primitive: bench.atomic.commit_new ------------------------------------------------------------------------


def _temps(tmp_path, *names):
    temps = {}
    for name in names:
        temps[tmp_path / name] = tmp_path / f".{name}.x{TEMP_SUFFIX}"
        temps[tmp_path / name].write_text(f"new {name}")
    return temps


def test_commit_new_places_every_file_and_removes_the_temporary_names(tmp_path):
    temps = _temps(tmp_path, "a.npz", "a.csv")
    assert commit_new(temps) == list(temps)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "a.npz"]
    assert (tmp_path / "a.npz").read_text() == "new a.npz"


def test_commit_new_does_not_replace_a_file_that_appears_after_every_check(tmp_path, monkeypatch):
    """The file appears at the last moment before the name is taken (as the data is flushed): still not replaced,
    and the file placed before it is taken back out: all or none, the temporary files as they were."""
    import bench.atomic as atomic

    temps = _temps(tmp_path, "a.npz", "a.csv")
    flush = atomic._fsync_file

    def flush_then_another_program_writes(path):
        flush(path)
        if path == temps[tmp_path / "a.csv"]:
            (tmp_path / "a.csv").write_text("theirs")

    monkeypatch.setattr(atomic, "_fsync_file", flush_then_another_program_writes)
    with pytest.raises(FileExistsError) as e:
        commit_new(temps)
    assert e.value.filename == str(tmp_path / "a.csv")
    assert (tmp_path / "a.csv").read_text() == "theirs" and not (tmp_path / "a.npz").exists()
    assert all(tmp.read_text() == f"new {final.name}" for final, tmp in temps.items())


def test_commit_new_counts_a_dangling_symlink_as_taken(tmp_path):
    temps = _temps(tmp_path, "a.npz")
    (tmp_path / "a.npz").symlink_to(tmp_path / "nowhere")
    with pytest.raises(FileExistsError):
        commit_new(temps)
    assert (tmp_path / "a.npz").is_symlink() and not (tmp_path / "nowhere").exists()
    assert temps[tmp_path / "a.npz"].read_text() == "new a.npz"
