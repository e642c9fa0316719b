"""Depth-map images: coloured height map, colour bar in mm, scale bar."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._checks import check_array

__all__ = ["depth_figure", "nice_scale_bar_mm", "save_depth_image"]


def nice_scale_bar_mm(width_mm: float) -> float:
    """A round scale-bar length, about a fifth of the image width.

    Parameters
    ----------
    width_mm : float
        Image width, mm.

    Returns
    -------
    length_mm : float
        1, 2 or 5 times a power of ten.
    """
    target = width_mm / 5.0
    p = 10.0 ** np.floor(np.log10(target))
    for m in (5.0, 2.0, 1.0):
        if m * p <= target:
            return float(m * p)
    return float(p)


def _scale_bar(ax, shape: tuple[int, int], mm_per_px: float, colour: str) -> None:
    h, w = shape
    length_mm = nice_scale_bar_mm(w * mm_per_px)
    length_px = length_mm / mm_per_px
    x0, y0 = 0.05 * w, 0.92 * h
    ax.plot([x0, x0 + length_px], [y0, y0], color=colour, lw=3, solid_capstyle="butt")
    label = f"{length_mm:g} mm"
    ax.text(x0 + length_px / 2, y0 - 0.025 * h, label, color=colour, ha="center", va="bottom",
            fontsize=9)


def _frame_panel(ax, frame: np.ndarray, shape: tuple[int, int], mm_per_px: float) -> None:
    """The tactile frame (BGR) with a scale bar, no ticks."""
    ax.imshow(frame[..., ::-1])
    ax.set_title("tactile frame")
    _scale_bar(ax, shape, mm_per_px, "white")
    ax.set_xticks([])
    ax.set_yticks([])


def _title_and_credit(fig, title: str | None, credit: str | None) -> None:
    if title:
        fig.suptitle(title)
    if credit:
        fig.text(0.5, 0.005, credit, ha="center", va="bottom", fontsize=7, color="0.35")


def _save(fig, path: str | Path, dpi: int) -> Path:
    """Write `fig` to `path` (folders created), close it, return the path."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def depth_figure(height_mm: np.ndarray, *, mm_per_px: float, frame: np.ndarray | None = None,
                 title: str | None = None, vmax_mm: float | None = None,
                 credit: str | None = None):
    """Figure of a height map (and optionally the frame it came from).

    Parameters
    ----------
    height_mm : (H, W) float ndarray
        Depth into the gel, mm.
    mm_per_px : float
        Image scale, mm per px (for the scale bar).
    frame : (H, W, 3) uint8 ndarray, optional
        The tactile frame (BGR), shown on the left.
    title : str, optional
        Figure title.
    vmax_mm : float, optional
        Upper end of the colour scale; default the 99.9th percentile.
    credit : str, optional
        Attribution line under the figure (e.g. the frames' licence).

    Returns
    -------
    fig : matplotlib.figure.Figure
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    height_mm = check_array(height_mm, "height_mm", [("H", "W")], dtype=np.floating)
    panels = 2 if frame is not None else 1
    fig, axes = plt.subplots(1, panels, figsize=(5.2 * panels, 4.3), squeeze=False,
                             layout="constrained")
    axes = axes[0]
    if frame is not None:
        frame = check_array(frame, "frame", [(*height_mm.shape, 3)], dtype=np.uint8)
        _frame_panel(axes[0], frame, height_mm.shape, mm_per_px)
    ax = axes[-1]
    vmax = float(np.percentile(height_mm, 99.9)) if vmax_mm is None else vmax_mm
    vmin = min(0.0, float(np.percentile(height_mm, 0.1)))
    vmax = max(vmax, vmin + 1e-3)
    im = ax.imshow(height_mm, cmap="viridis", vmin=vmin, vmax=vmax)
    ax.set_title("height map (depth into the gel)")
    _scale_bar(ax, height_mm.shape, mm_per_px, "white")
    cb = fig.colorbar(im, ax=ax, shrink=0.85)
    cb.set_label("depth (mm)")
    ax.set_xticks([])
    ax.set_yticks([])
    _title_and_credit(fig, title, credit)
    return fig


def save_depth_image(path: str | Path, height_mm: np.ndarray, *, mm_per_px: float,
                     frame: np.ndarray | None = None, title: str | None = None,
                     vmax_mm: float | None = None, credit: str | None = None,
                     dpi: int = 100) -> Path:
    """Write :func:`depth_figure` to a PNG.

    Parameters
    ----------
    path : str or Path
        Output file.
    height_mm, mm_per_px, frame, title, vmax_mm, credit
        See :func:`depth_figure`.
    dpi : int, default 100

    Returns
    -------
    path : Path
    """
    fig = depth_figure(height_mm, mm_per_px=mm_per_px, frame=frame, title=title,
                       vmax_mm=vmax_mm, credit=credit)
    return _save(fig, path, dpi)
