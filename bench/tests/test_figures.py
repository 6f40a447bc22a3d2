"""The one figure writer (bench.reporting.figures): a PNG whole or nothing, and never a figure left open."""

import matplotlib.pyplot as plt
import pytest

from bench.reporting.figures import figure_file


def test_a_drawn_figure_is_saved_whole_and_closed(tmp_path):
    path = tmp_path / "line.png"
    with figure_file(path, 1, 2, figsize=(4, 2)) as (fig, axes):
        axes[0].plot([0, 1], [1, 0])
        assert plt.fignum_exists(fig.number)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not plt.fignum_exists(fig.number)
    assert [p.name for p in tmp_path.iterdir()] == ["line.png"]


@pytest.mark.parametrize("error", [RuntimeError("drawing failed"), KeyboardInterrupt()])
def test_a_failed_drawing_leaves_no_file_and_no_open_figure(tmp_path, error):
    path = tmp_path / "broken.png"
    path_before = tmp_path / "kept.png"
    path_before.write_bytes(b"old")
    with pytest.raises(type(error)):
        with figure_file(path, figsize=(4, 2)) as (fig, _):
            raise error
    assert not plt.fignum_exists(fig.number)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.png"]
    assert path_before.read_bytes() == b"old"


def test_the_sensitivity_plot_draws_d_min_and_names_what_it_needs(tmp_path):
    from types import SimpleNamespace

    from bench.reporting.plots import sensitivity_plot

    claims = [SimpleNamespace(details={"d_min_m": {100.0: 1e-7, 330.0: 5e-9, 800.0: 2e-8}})]
    path = sensitivity_plot(claims, tmp_path / "plots")
    assert path.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(ValueError, match="claims --only vibration"):
        sensitivity_plot([SimpleNamespace(details={})], tmp_path / "none")


def test_figures_is_the_only_module_that_saves_a_figure():
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    writers = sorted(str(p.relative_to(root)) for d in ("bench", "emulator") for p in (root / d).rglob("*.py")
                     if "tests" not in p.parts and ".savefig(" in p.read_text(encoding="utf-8"))
    assert writers == ["bench/reporting/figures.py"]


def test_a_folder_in_a_files_way_leaves_no_temporary_file(tmp_path):
    """atomic_write's rename onto a folder fails after the file was written: the error is raised and the temporary
    .part goes too (it was left beside the folder)."""
    from bench.atomic import atomic_write

    (tmp_path / "x.png").mkdir()
    with pytest.raises(IsADirectoryError):
        with atomic_write(tmp_path / "x.png") as tmp:
            tmp.write_bytes(b"\x89PNG...")
    assert [p.name for p in tmp_path.iterdir()] == ["x.png"] and (tmp_path / "x.png").is_dir()


@pytest.mark.parametrize("in_the_way", ["a file", "a folder"])
def test_claims_plots_refuses_what_it_did_not_write_before_running(tmp_path, capsys, in_the_way):
    """--plots DIR holding a frequency_sensitivity.png the command did not write (notes, a folder): exit 2 before
    any claim runs, the thing untouched; an earlier plot is replaced."""
    from bench.cli import main as cli

    target = tmp_path / "frequency_sensitivity.png"
    if in_the_way == "a file":
        target.write_text("my notes")
    else:
        target.mkdir()
    assert cli.main(["claims", "--only", "vibration", "--quick", "--plots", str(tmp_path)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and f"--plots {tmp_path}: {target}" in err and "Traceback" not in err, err
    assert target.read_text() == "my notes" if in_the_way == "a file" else target.is_dir()
    assert [p.name for p in tmp_path.iterdir()] == [target.name]


def test_claims_plots_replaces_its_own_earlier_plot(tmp_path, capsys):
    """... and removes, and names, the temporary plot a claims killed as it saved the plot left there (no other
    file, and no lock file, stays)."""
    from bench.cli import main as cli

    target = tmp_path / "frequency_sensitivity.png"
    target.write_bytes(b"\x89PNG earlier")
    left = tmp_path / ".frequency_sensitivity.png.0a1b2c3d.part"
    left.write_bytes(b"\x89PNG half written")
    assert cli.main(["claims", "--only", "vibration", "--quick", "--plots", str(tmp_path)]) == 0
    assert target.read_bytes()[:4] == b"\x89PNG" and len(target.read_bytes()) > 1000
    err = capsys.readouterr().err
    assert f"wrote {target}" in err
    assert (f"note: --plots {tmp_path}: removed 1 temporary file that an interrupted claims run left, killed (or the "
            f"machine down) before it could clean up, partial writes and never results: {left.name}") in err, err
    assert [p.name for p in tmp_path.iterdir()] == [target.name]
