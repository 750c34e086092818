"""Writing a figure: laid out so that its labels fit, and drawn once."""

from __future__ import annotations

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from casadi_posture.output.saving import save_figure


def _labelled() -> Figure:
    """Two panels whose large y labels stick out of the figure unless it is laid out."""
    fig = Figure(figsize=(4, 3), dpi=100)
    for k in (1, 2):
        ax = fig.add_subplot(1, 2, k)
        ax.plot([0, 1], [1e5, 2e5])
        ax.set_ylabel("a long label\non two lines", fontsize=16)
    return fig


def test_saved_figure_is_laid_out_and_drawn_once(tmp_path, monkeypatch):
    """``save_figure`` places the labels inside the figure (without a layout, the left one
    starts outside it) and draws the figure once: ``Figure.tight_layout`` left a layout
    engine behind, and saving then drew the whole figure a second time first."""
    bare = _labelled()
    left = bare.axes[0].yaxis.label.get_window_extent(FigureCanvasAgg(bare).get_renderer())
    assert left.x0 < 0

    draws = []
    draw = Figure.draw

    def counted(fig: Figure, renderer) -> None:
        draws.append(fig)
        draw(fig, renderer)

    monkeypatch.setattr(Figure, "draw", counted)
    fig = _labelled()
    path = save_figure(fig, tmp_path / "sub" / "labelled.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(draws) == 1
    assert fig.get_layout_engine() is None
    drawn = fig.get_tightbbox(fig.canvas.get_renderer())  # [in]
    width, height = fig.get_size_inches()
    assert min(drawn.x0, drawn.y0) >= 0 and drawn.x1 <= width and drawn.y1 <= height
