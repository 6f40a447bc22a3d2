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
