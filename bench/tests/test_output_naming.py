"""Messages name an output as the user gave it: ``claims --plots DIR`` names DIR (the folder typed), not the plot's
file in it; an output a command chose itself because its flag was not typed (``campaign``'s out/campaign.xml,
``record``'s out/recording.npz) is named as the default file, not as a flag the user never gave; the same path
typed is named with its flag.  The refusals here are real: another command's lock held (``take_lock``), an earlier
file in the way."""

import os

import pytest

from bench.atomic import release_lock, take_lock
from bench.cli.main import main

pytestmark = pytest.mark.unit


@pytest.fixture
def held(tmp_path):
    """``held(lock_path)``: the lock taken as another command holds it (released at the end)."""
    taken = []

    def hold(lock_path):
        lock_path.parent.mkdir(parents=True, exist_ok=True)
        taken.append((take_lock(lock_path), lock_path))

    yield hold
    for fd, path in taken:
        release_lock(fd, path)


def test_claims_plots_names_the_folder_typed_when_its_plot_is_being_written(tmp_path, held, capsys):
    plots = tmp_path / "plots"
    held(plots / ".frequency_sensitivity.png.lock")
    assert main(["claims", "--only", "vibration", "--quick", "--plots", str(plots)]) == 2
    assert capsys.readouterr().err == (f"error: --plots {plots}: another claims run (pid {os.getpid()}) is writing "
                                       f"this plot; wait for it to end or choose another --plots\n")


@pytest.mark.parametrize("typed", [False, True])
def test_campaign_names_its_default_report_as_the_default_not_as_junit(tmp_path, monkeypatch, held, capsys, typed):
    monkeypatch.chdir(tmp_path)
    held(tmp_path / "out" / ".campaign.xml.lock")
    assert main(["campaign", "--faults", "serial_loss", "--scenes", "rest", "--quiet",
                 *(["--junit", "out/campaign.xml"] if typed else [])]) == 2
    named = "--junit out/campaign.xml" if typed else "out/campaign.xml (the default file; --junit chooses another)"
    assert capsys.readouterr().err == (f"error: {named}: another campaign (pid {os.getpid()}) is writing this report; "
                                       f"wait for it to end or choose another --junit\n")


@pytest.mark.parametrize("typed", [False, True])
def test_record_names_its_default_file_as_the_default_not_as_out(tmp_path, monkeypatch, capsys, typed):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "recording.npz").write_text("an earlier recording")
    assert main(["record", "bridge", *(["--out", "out/recording.npz"] if typed else [])]) == 2
    named = "--out out/recording.npz" if typed else "out/recording.npz (the default file; --out chooses another)"
    assert capsys.readouterr().err == (f"error: {named}: out/recording.npz already there (an earlier recording?); "
                                       f"give another --out, or --force to replace it\n")


def test_explore_names_its_default_cache_as_the_default_not_as_cache(tmp_path, monkeypatch, capsys):
    from bench.paths import REPO

    monkeypatch.chdir(tmp_path)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "cache").write_text("not a folder")
    assert main(["explore", str(REPO / "fixtures" / "experiments" / "quick.toml"), "--quiet"]) == 2
    assert capsys.readouterr().err == ("error: out/cache (the default folder; --cache chooses another): is a file, not "
                                       "a folder\n")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["cache"]  # (the --out folder it made: removed)


def test_explore_and_run_show_the_paths_they_name_escaped(tmp_path, capsys):
    """A path with a line break: one line each, the break shown as \\n (as every message shows a path)."""
    from bench.paths import REPO, SCENES_DIR

    odd = tmp_path / "a\nb"
    assert main(["explore", str(REPO / "fixtures" / "experiments" / "quick.toml"), "--cache", str(odd), "--out",
                 str(odd)]) == 2
    shown = str(odd).replace("\n", "\\n")
    assert capsys.readouterr().err == (f"error: --cache {shown} is --out: the results and the stage cache need "
                                       f"folders of their own (the cache's entries would make a later --force refuse "
                                       f"the folder); the cache may sit inside --out, e.g. --cache {shown}/cache\n")
    scene = tmp_path / "short.toml"
    scene.write_text((SCENES_DIR / "rest.toml").read_text().replace("duration_s = 10.0", "duration_s = 0.05"))
    assert main(["run", str(scene), "--out", str(odd), "--quiet"]) == 0
    assert f"wrote {shown}/ (" in capsys.readouterr().out


def test_record_shows_the_port_it_names_escaped(tmp_path, capsys):
    """The port as typed (a device, a link to one), a line break in its name shown as \\n: one line each."""
    missing = tmp_path / "no\nport"
    assert main(["record", str(missing), "--out", str(tmp_path / "r.npz")]) == 2
    shown = str(missing).replace("\n", "\\n")
    assert capsys.readouterr().err == f"error: argument port: cannot open {shown}: No such file or directory\n"
    controller, device = os.openpty()  # a serial line nothing answers on
    try:
        port = tmp_path / "silent\nline"
        port.symlink_to(os.ttyname(device))
        assert main(["record", str(port), "--out", str(tmp_path / "r.npz"), "--quiet"]) == 2
    finally:
        os.close(controller)
        os.close(device)
    shown = str(port).replace("\n", "\\n")
    assert capsys.readouterr().err == (f"error: {shown}: no answer to START within 5 s (is the bridge running?)\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["silent\nline"]  # nothing written
