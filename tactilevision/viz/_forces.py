"""Force-map images: pressure in kPa with a colour bar, arrows for the tangential part."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._checks import check_array
from ._depth import _frame_panel, _save, _title_and_credit

__all__ = ["force_figure", "save_force_image"]


def force_figure(force_map, *, mm_per_px: float, frame: np.ndarray | None = None,
                 title: str | None = None, vmax_kpa: float | None = None,
                 credit: str | None = None, arrows: int = 16):
    """Figure of one frame's contact force distribution.

    Parameters
    ----------
    force_map : ForceMap
        One frame's result of :class:`~tactilevision.fem.ForceEstimator`
        (``pressure_kpa`` (rows, cols), ``forces_n`` (rows, cols, 3)).
    mm_per_px : float
        Image scale, mm per px, for the scale bar and the axes of the frame.
    frame : (H, W, 3) uint8 ndarray, optional
        The tactile frame (BGR), shown on the left.
    title : str, optional
    vmax_kpa : float, optional
        Upper end of the colour scale; default the 99.9th percentile of the
        pressure.
    credit : str, optional
        Attribution line under the figure.
    arrows : int, default 16
        Arrows along the longer side for the tangential forces (none when
        they are all zero).

    Returns
    -------
    fig : matplotlib.figure.Figure
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    p = check_array(force_map.pressure_kpa, "pressure_kpa", [("R", "C")], dtype=np.floating)
    x, y = np.asarray(force_map.x_mm), np.asarray(force_map.y_mm)
    extent = (x[0] - 0.5 * (x[1] - x[0]), x[-1] + 0.5 * (x[1] - x[0]),
              y[-1] + 0.5 * (y[1] - y[0]), y[0] - 0.5 * (y[1] - y[0]))
    panels = 2 if frame is not None else 1
    fig, axes = plt.subplots(1, panels, figsize=(5.2 * panels, 4.3), squeeze=False,
                             layout="constrained")
    axes = axes[0]
    if frame is not None:
        frame = check_array(frame, "frame", [(None, None, 3)], dtype=np.uint8)
        _frame_panel(axes[0], frame, frame.shape[:2], mm_per_px)
    ax = axes[-1]
    vmax = float(np.percentile(p, 99.9)) if vmax_kpa is None else float(vmax_kpa)
    vmin = min(0.0, float(np.percentile(p, 0.1)))
    vmax = max(vmax, vmin + 1e-6)
    # a diverging map centred on zero shows tension (negative pressure) as a warning colour
    lim = max(vmax, -vmin)
    im = ax.imshow(p, cmap="RdBu_r", vmin=-lim, vmax=lim, extent=extent)
    tot = np.asarray(force_map.total_n)
    ax.set_title(f"pressure; total Fz {tot[2]:.3f} N, Fx {tot[0]:.3f} N, Fy {tot[1]:.3f} N",
                 fontsize=9)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    cb = fig.colorbar(im, ax=ax, shrink=0.85)
    cb.set_label("pressure (kPa)")
    f = np.asarray(force_map.forces_n)
    ft = f[..., :2]
    if np.any(ft != 0):
        step = max(1, max(p.shape) // arrows)
        # tangential force summed over each arrow's block of nodes
        R, C = (p.shape[0] // step) * step, (p.shape[1] // step) * step
        blk = ft[:R, :C].reshape(R // step, step, C // step, step, 2).sum(axis=(1, 3))
        yy = y[:R].reshape(-1, step).mean(axis=1)
        xx = x[:C].reshape(-1, step).mean(axis=1)
        mag = np.hypot(blk[..., 0], blk[..., 1])
        if mag.max() > 0:
            q = ax.quiver(xx, yy, blk[..., 0], blk[..., 1], angles="xy", color="k",
                          scale_units="xy", scale=mag.max() / (step * (x[1] - x[0]) * 1.5),
                          width=0.004)
            ax.quiverkey(q, 0.80, 1.02, float(mag.max()), f"{mag.max() * 1e3:.1f} mN",
                         labelpos="E", fontproperties={"size": 8})
    _title_and_credit(fig, title, credit)
    return fig


def save_force_image(path: str | Path, force_map, *, mm_per_px: float,
                     frame: np.ndarray | None = None, title: str | None = None,
                     vmax_kpa: float | None = None, credit: str | None = None,
                     dpi: int = 100) -> Path:
    """Write :func:`force_figure` to a PNG; returns the path."""
    fig = force_figure(force_map, mm_per_px=mm_per_px, frame=frame, title=title,
                       vmax_kpa=vmax_kpa, credit=credit)
    return _save(fig, path, dpi)
