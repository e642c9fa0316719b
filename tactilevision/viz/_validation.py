"""The paper's Fig. 8 for our data: force against depth, measured and simulated."""

from __future__ import annotations

from pathlib import Path

__all__ = ["save_validation_figure", "validation_figure"]


def validation_figure(result, *, title: str | None = None):
    """Force-depth figure of a :class:`~tactilevision.diagnosis.IndentationValidation`.

    Parameters
    ----------
    result : IndentationValidation or IndenterValidation
    title : str, optional

    Returns
    -------
    fig : matplotlib.figure.Figure
        Left: measured presses (dots) and the simulated P(w) curve. Right:
        relative depth error per press against its depth (a trend there is a
        missing effect, not noise), with the paper's 6% band.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
    law = {"neo_hookean": "Neo-Hookean", "linear": "small strain"}[getattr(result, "law",
                                                                          "neo_hookean")]
    ax.plot(result.curve_depth_mm, result.curve_force_n, "-", color="C0",
            label=f"FEM, {law} (E = {result.E_mpa:.4g} MPa, nu = {result.nu:.4f})")
    ax.plot(result.depth_mm, result.force_n, "o", color="C1", ms=4, label="measured")
    ax.set_xlabel("indentation depth w (mm)")
    ax.set_ylabel("force P (N)")
    ax.legend(fontsize=8)
    ax2.axhspan(-6, 6, color="0.9", label="paper: within 6%")
    ax2.plot(result.depth_mm, 100 * result.rel_error, "o", color="C1", ms=4)
    ax2.axhline(0, color="0.4", lw=0.8)
    ax2.set_xlabel("measured depth w (mm)")
    ax2.set_ylabel("simulated / measured depth - 1 (%)")
    ax2.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    return fig


def save_validation_figure(path: str | Path, result, *, title: str | None = None,
                           dpi: int = 100) -> Path:
    """Write :func:`validation_figure` to a PNG; returns the path."""
    import matplotlib.pyplot as plt

    fig = validation_figure(result, title=title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
