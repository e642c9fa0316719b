"""Figures and the report page of a ball's diagnosis (``diagnose`` of a sphere's table),
and the figure of a ball's calibration."""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from ._calibration import figures_html, html_head, pyplot

__all__ = ["ball_calibration_figure", "indenter_figure", "write_indenter_report"]


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


def ball_calibration_figure(cal, path: str | Path, *, dpi: int = 110) -> Path:
    """A ball's calibration at a glance: force against the depths its circles certified,
    with the fitted law, and each press's apparent E.

    Parameters
    ----------
    cal : tactilevision.pipeline.BallCalibration
    path : str or Path
        The PNG written.
    dpi : int, default 110

    Returns
    -------
    Path

    Notes
    -----
    The depth bars are each press's random error (1 sd) plus the shared bound every
    circle's radius may be off by together (:class:`tactilevision.pipeline.BallDepths`).
    """
    plt = pyplot()
    d, fit = cal.depths, cal.fit
    w, P = d.depth_mm, cal.force_n
    cfg = cal.session.config
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax1.errorbar(w, P, xerr=d.depth_std_mm + d.depth_shared_mm, fmt="ko", ms=4, capsize=2,
                 label="presses (depth from the circle, sd + shared bound)", zorder=3)
    curve = np.linspace(0.0, float(w.max()) * 1.05, 80)[1:]
    curve = curve[curve <= cal.indenter.reach_mm(cfg.gel_thickness_mm, fit.law, fit.contact)]
    ax1.plot(curve, cal.indenter.force(curve, E_mpa=fit.E_mpa, nu=fit.nu,
                                      thickness_mm=cfg.gel_thickness_mm, law=fit.law,
                                      contact=fit.contact), "-",
             label=f"{fit.law}, {fit.contact}: E {fit.E_mpa:.4g} MPa "
                   f"[{fit.E_ci95_mpa[0]:.3g}, {fit.E_ci95_mpa[1]:.3g}]")
    ax1.set_xlabel("depth w (mm)")
    ax1.set_ylabel("force P (N)")
    ax1.legend(fontsize=8)
    order = np.argsort(w)
    ax2.plot(w[order], fit.apparent_E_mpa[order], "o-")
    ax2.axhspan(*fit.E_ci95_mpa, color="0.85", label="E's 95 % interval")
    ax2.set_xlabel("depth w (mm)")
    ax2.set_ylabel(f"apparent E of each press (MPa, nu = {fit.nu:.3g})")
    ax2.set_title("flat when the law is right", fontsize=9)
    ax2.legend(fontsize=8)
    fig.suptitle(f"{cal.session.path.name}: ball R = {cfg.indenter_radius_mm:g} mm on "
                 f"h = {cfg.gel_thickness_mm:g} mm, {len(w)} presses", fontsize=10)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return out
