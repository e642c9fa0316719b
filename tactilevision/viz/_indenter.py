"""Figures and the report page of a ball's diagnosis (``diagnose`` of a sphere's table)."""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from ._calibration import figures_html, html_head, pyplot

__all__ = ["indenter_figure", "write_indenter_report"]


def indenter_figure(diag, path: str | Path, *, title: str | None = None, dpi: int = 110
                    ) -> Path:
    """Force against depth with every rung's model, and each press's apparent E per rung.

    Parameters
    ----------
    diag : IndenterDiagnosis
    path : str or Path
        The PNG written.
    title : str, optional
    dpi : int, default 110

    Returns
    -------
    Path
    """
    plt = pyplot()
    w, P = diag.depth_mm, diag.force_n
    order = np.argsort(w)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax1.plot(w, P, "ko", label="measured", zorder=3)
    for k, r in enumerate(diag.ladder):
        label = "base: linear, " + r.contact if k == 0 else "+ " + r.effects[-1]
        ax1.plot(w[order], r.predicted_n[order], "-", label=f"{label} "
                 f"(E {r.E_mpa:.3g} MPa, RMSE {r.rmse_n * 1e3:.3g} mN)")
        ax2.plot(w[order], r.apparent_E_mpa[order], "o-", label=f"{label} "
                 f"(drift {100 * r.drift:+.0f} %)")
    ax1.set_xlabel("depth w (mm)")
    ax1.set_ylabel("force P (N)")
    ax1.legend(fontsize=8)
    ax2.set_xlabel("depth w (mm)")
    ax2.set_ylabel(f"apparent E of each press (MPa, nu = {diag.nu:g})")
    ax2.legend(fontsize=8)
    ax2.set_title("flat when the model is right", fontsize=9)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return out


def write_indenter_report(diag, out_dir: str | Path, figures: dict[str, Path], *,
                          source: str = "") -> Path:
    """Write ``report.html`` of a ball's diagnosis: the ladder, the message, the figure.

    Parameters
    ----------
    diag : IndenterDiagnosis
    out_dir : str or Path
    figures : dict of str to Path
    source : str
        The table's path, for the title.

    Returns
    -------
    Path
    """
    e = html.escape
    rows = "".join(
        f"<tr><td>{e(' + '.join(('base', *r.effects)))}</td><td>{e(r.law)}</td>"
        f"<td>{e(r.contact)}</td><td>{r.E_mpa:.4f}</td><td>{r.rmse_n * 1e3:.4g}</td>"
        f"<td>{r.bic:.2f}</td><td>{100 * r.drift:+.1f} %</td></tr>" for r in diag.ladder)
    verdict = ", ".join(diag.missing_effects) or "nothing missing"
    page = html_head(f"tactilevision diagnose: {source}") + f"""\
<h1>A ball's model against measurement: {e(source)}</h1>
<p class=big>Missing: <b>{e(verdict)}</b></p>
<p>{e(diag.message)}</p>
<h2>Error ladder (E at nu = {diag.nu:g})</h2>
<table><tr><th>model</th><th>law</th><th>contact</th><th>E (MPa)</th><th>RMSE (mN)</th>
<th>BIC</th><th>apparent E drift</th></tr>{rows}</table>
{figures_html(figures)}
</body></html>
"""
    out = Path(out_dir) / "report.html"
    out.write_text(page, encoding="utf-8")
    return out
