"""What keeps the end of a run (its plots, where the peak memory falls) small: each figure's memory is gone before
the next is drawn, one Agg canvas per figure, the traces' zig-zags rasterized in pieces, the spectrogram drawn as
an image — each drawing what it drew before."""

import gc
import weakref

import matplotlib
import numpy as np
import pytest
from matplotlib.backends import backend_agg
from matplotlib.figure import Figure

from bench.reporting import figures, plots
from bench.reporting.figures import figure_file


def test_a_drawn_figure_is_freed_before_the_next_one_is_made(tmp_path):
    """A closed figure is cyclic garbage holding its canvas's pixels: it must be gone when the next figure starts,
    not whenever the collector next runs."""
    gc.disable()  # a collection between the two figures would hide a missing one
    try:
        with figure_file(tmp_path / "a.png", figsize=(4, 2)) as (fig, ax):
            ax.plot([0, 1], [1, 0])
            ax.set_title("first")
        first = weakref.ref(fig)
        del fig, ax
        assert first() is not None  # still there: only a collection frees it
        with figure_file(tmp_path / "b.png", figsize=(4, 2)) as (_, ax):
            assert first() is None
            ax.plot([0, 1], [0, 1])
    finally:
        gc.enable()


def test_laying_out_and_saving_share_one_canvas(tmp_path, monkeypatch):
    """The figure is made at the PNG's resolution: tight_layout's renderer is the one savefig draws on (at another
    dpi savefig would allocate a second full-size canvas while the first is still held)."""
    made = []
    real = backend_agg.RendererAgg

    class Counting(real):
        def __init__(self, *a, **kw):
            made.append(a)
            super().__init__(*a, **kw)

    monkeypatch.setattr(backend_agg, "RendererAgg", Counting)
    with figure_file(tmp_path / "one.png", figsize=(4, 2)) as (fig, ax):
        ax.plot([0, 1], [1, 0])
        assert fig.dpi == figures.DPI
    assert len(made) == 1, made


def _line_data(ax) -> tuple[np.ndarray, np.ndarray]:
    return (np.concatenate([ln.get_xdata() for ln in ax.lines]), np.concatenate([ln.get_ydata() for ln in ax.lines]))


@pytest.mark.parametrize("bins", [0, 1, 7, plots.ZIGZAG_PIECE_BINS, plots.ZIGZAG_PIECE_BINS + 1, 1000])
def test_the_zigzag_is_drawn_in_pieces_that_join_into_the_whole_line(bins):
    """Each piece holds at most ZIGZAG_PIECE_BINS bins and starts at the vertex where the last one ended; joined,
    the pieces are the one zig-zag (low → high per bin) in one colour, with one legend entry."""
    c = np.arange(bins) + 0.5
    lo, hi = -np.arange(bins, dtype=float), np.arange(bins, dtype=float) + 1
    fig = Figure()
    ax = fig.add_subplot()
    plots._zigzag(ax, c, lo, hi, lw=0.7, label="E3")
    lines = ax.lines
    assert len(lines) == max(1, -(-bins // plots.ZIGZAG_PIECE_BINS))
    assert all(ln.get_xdata().size <= 2 * plots.ZIGZAG_PIECE_BINS + 1 for ln in lines)
    for a, b in zip(lines[:-1], lines[1:]):
        assert (a.get_xdata()[-1], a.get_ydata()[-1]) == (b.get_xdata()[0], b.get_ydata()[0])
    x = np.concatenate([lines[0].get_xdata()] + [ln.get_xdata()[1:] for ln in lines[1:]])
    y = np.concatenate([lines[0].get_ydata()] + [ln.get_ydata()[1:] for ln in lines[1:]])
    assert np.array_equal(x, np.repeat(c, 2)) and np.array_equal(y, np.column_stack([lo, hi]).ravel())
    assert len({ln.get_color() for ln in lines}) == 1 and {ln.get_linewidth() for ln in lines} == {0.7}
    assert [h.get_label() for h in ax.get_legend_handles_labels()[0]] == ["E3"]


def test_the_zigzag_pieces_take_the_next_colour_of_the_cycle_once():
    fig = Figure()
    ax = fig.add_subplot()
    c = np.arange(3 * plots.ZIGZAG_PIECE_BINS) + 0.5
    plots._zigzag(ax, c, c, c + 1, label="E1")
    plots._zigzag(ax, c, c, c + 1, label="E2")
    colours = [ln.get_color() for ln in ax.lines]
    assert len(set(colours[:3])) == 1 and len(set(colours[3:])) == 1 and colours[0] != colours[3]


@pytest.mark.parametrize("n_columns", [1000, 3])
def test_the_spectrogram_image_draws_what_pcolormesh_drew(tmp_path, n_columns):
    """Nearest cells as an image (bytes of the figure's pixels, not a polygon per cell): the same limits as
    pcolormesh(shading="nearest"), and the same picture to one level of rounding in the colour map."""
    from PIL import Image

    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.9, 1.1, n_columns))  # not quite uniform: a last column averaged over fewer windows
    f = np.linspace(0, 1100, 89)
    db = rng.normal(-40, 6, (f.size, t.size))
    limits, pixels = {}, {}
    for how in ("mesh", "image"):
        with figure_file(tmp_path / f"{how}.png", figsize=(6, 3)) as (fig, ax):
            if how == "mesh":
                art = ax.pcolormesh(t, f, db, shading="nearest", cmap="magma")
            else:
                art = plots._nearest_cells(ax, t, f, db, cmap="magma")
            fig.colorbar(art, ax=ax)
            limits[how] = (*ax.get_xlim(), *ax.get_ylim(), art.norm.vmin, art.norm.vmax)
        pixels[how] = np.asarray(Image.open(tmp_path / f"{how}.png").convert("RGB")).astype(int)
    assert limits["image"] == pytest.approx(limits["mesh"])
    rows, cols = np.nonzero(np.abs(pixels["image"] - pixels["mesh"]).max(axis=2) > 1)
    # beyond rounding, at most the one pixel row (or column) an edge of the axes cuts: the image fills it, the mesh
    # leaves it when its cells cover less than half of it
    assert len(set(rows)) <= 1 or len(set(cols)) <= 1, (sorted(set(rows)), sorted(set(cols)))


def test_a_one_column_spectrogram_still_draws(tmp_path, recwarn):
    with figure_file(tmp_path / "one.png", figsize=(6, 3)) as (fig, ax):
        fig.colorbar(plots._nearest_cells(ax, np.array([0.04]), np.linspace(0, 1100, 89), np.ones((89, 1))), ax=ax)
    assert (tmp_path / "one.png").read_bytes()[:4] == b"\x89PNG"
    assert not [w for w in recwarn if "singular" in str(w.message) or "identical" in str(w.message)]


def test_matplotlib_stays_headless():
    assert matplotlib.get_backend().lower() == "agg"
