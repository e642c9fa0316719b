"""Figures and the HTML page of a session calibration (``tactilevision calibrate``)."""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

__all__ = ["calibration_figures", "write_calibration_report"]


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def _html_head(title: str) -> str:
    """Opening of a report page (escaped title, the shared style)."""
    return (f'<!doctype html>\n<html><head><meta charset="utf-8"><title>{html.escape(title)}'
            "</title>\n<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto}\n"
            ".big{font-size:1.3em} td,th{padding:2px 8px;text-align:left}\n"
            "img{max-width:100%} figure{margin:1em 0}</style></head><body>\n")


def _figures_html(figures: dict[str, Path]) -> str:
    """The report's figures as <figure> elements (images beside the page)."""
    e = html.escape
    return "".join(f'<figure><img src="{e(p.name)}" alt="{e(k)}"></figure>'
                   for k, p in figures.items())


def _fit_line(fit, w: np.ndarray) -> np.ndarray:
    """P/w of eq. (5) at depths w."""
    return fit.c_n_per_mm * (1.0 + fit.beta * w / fit.thickness_mm)


def _band(fit, w: np.ndarray, z: float = 1.96) -> np.ndarray:
    """Half-width of the confidence band of the fitted line P/w = c + slope w/h."""
    x = w / fit.thickness_mm
    var = (fit.c_se_n_per_mm ** 2 + (x * fit.slope_se_n_per_mm) ** 2
           + 2 * x * fit.corr_c_slope * fit.c_se_n_per_mm * fit.slope_se_n_per_mm)
    return z * np.sqrt(np.maximum(var, 0.0))


def calibration_figures(cal, out_dir: str | Path, *, reconstructor=None, dpi: int = 100
                        ) -> dict[str, Path]:
    """Write the report's figures for a :class:`~tactilevision.SessionCalibration`.

    Parameters
    ----------
    cal : SessionCalibration
    out_dir : str or Path
    reconstructor : DepthReconstructor, optional
        For the height-map mosaic; without it the mosaic shows the colour
        change of the frames.
    dpi : int, default 100

    Returns
    -------
    paths : dict of str to Path
        ``force_depth``, ``stiffness_line``, ``residuals``, ``mosaic``.
    """
    plt = _plt()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    fit = cal.fit
    ps = cal.certification.presses
    w = cal.depth_mm
    p = np.array([q.force_n for q in ps])
    ind = np.array([q.indenter for q in ps])
    h = fit.thickness_mm
    ok = np.isfinite(fit.c_n_per_mm) and np.isfinite(fit.beta)
    ww = np.linspace(0, w.max() * 1.08, 200)
    paths = {}

    fig, ax = plt.subplots(figsize=(5.5, 4), layout="constrained")
    for k in np.unique(ind):
        s = ind == k
        w0 = ps[np.flatnonzero(s)[0]].w0_mm
        ax.plot(w[s], p[s], "o", ms=4, label=f"indenter {k} (w0 = {w0:g} mm)")
    if ok:
        ax.plot(ww, ww * _fit_line(fit, ww), "-", color="0.3",
                label=f"eq. (5): c = {fit.c_n_per_mm:.3f} N/mm, beta = {fit.beta:.3f}")
    ax.set_xlabel("certified depth w (mm)")
    ax.set_ylabel("force P (N)")
    ax.legend(fontsize=7)
    ax.set_title("force against depth")
    paths["force_depth"] = out / "force_depth.png"
    fig.savefig(paths["force_depth"], dpi=dpi)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(5.5, 4), layout="constrained")
    ax.plot(w / h, p / w, "o", ms=4, color="C1", label="presses")
    if ok:
        xx = ww[1:]
        line = _fit_line(fit, xx)
        band = _band(fit, xx)
        ax.plot(xx / h, line, "-", color="C0", label="fitted line (eq. 5)")
        ax.fill_between(xx / h, line - band, line + band, color="C0", alpha=0.2,
                        label=f"{fit.confidence:.0%} band of the line")
    ax.set_xlabel("w / h")
    ax.set_ylabel("P / w (N/mm)")
    txt = (f"E = {fit.E_mpa:.4f} MPa [{fit.E_ci95_mpa[0]:.4f}, {fit.E_ci95_mpa[1]:.4f}]\n"
           f"nu = {fit.nu:.4f} [{fit.nu_ci95[0]:.4f}, {fit.nu_ci95[1]:.4f}]"
           if np.isfinite(fit.E_mpa) else "E, nu out of the table")
    ax.text(0.02, 0.97, txt, transform=ax.transAxes, va="top", fontsize=8)
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title("stiffness against depth")
    paths["stiffness_line"] = out / "stiffness_line.png"
    fig.savefig(paths["stiffness_line"], dpi=dpi)
    plt.close(fig)

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.5), layout="constrained")
    res = p - w * _fit_line(fit, w) if ok else np.full_like(p, np.nan)
    std = np.array([q.force_std_n for q in ps]) / np.sqrt(
        max(cal.session.config.window_samples, 1))
    a1.errorbar(w, res, yerr=2 * std, fmt="o", ms=3, color="C1", lw=0.8)
    a1.axhline(0, color="0.4", lw=0.8)
    a1.set_xlabel("certified depth w (mm)")
    a1.set_ylabel("P - model (N)")
    a1.set_title("residuals (bars: 2 sd of the window mean)", fontsize=9)
    t = np.array([q.time_s for q in ps])
    a2.plot(t, res, "o", ms=3, color="C2")
    a2.axhline(0, color="0.4", lw=0.8)
    a2.set_xlabel("time in session (s)")
    a2.set_ylabel("P - model (N)")
    a2.set_title("residuals against time", fontsize=9)
    paths["residuals"] = out / "residuals.png"
    fig.savefig(paths["residuals"], dpi=dpi)
    plt.close(fig)

    paths["mosaic"] = _mosaic(cal, out / "mosaic.png", reconstructor, dpi)
    return paths


def _mosaic(cal, path: Path, reconstructor, dpi: int) -> Path:
    plt = _plt()
    from matplotlib.patches import Circle

    ps = cal.certification.presses
    cfg = cal.session.config
    s = cfg.mm_per_px
    kinds = sorted({q.indenter for q in ps})
    fig, axes = plt.subplots(1, len(kinds), figsize=(3.2 * len(kinds), 3.0),
                             layout="constrained", squeeze=False)
    for ax, k in zip(axes[0], kinds, strict=True):
        q = next(q for q in ps if q.indenter == k)
        frame = cal.session.frame(q.frame)
        if reconstructor is not None:
            img = reconstructor(frame)
            im = ax.imshow(img, cmap="viridis")
            fig.colorbar(im, ax=ax, shrink=0.7, label="height (mm)")
        else:
            d = np.abs(frame.astype(np.float32) - cal.session.reference).sum(axis=2)
            ax.imshow(d, cmap="magma")
        cx, cy = q.footprint.center_px
        ax.add_patch(Circle((cx, cy), q.footprint.radius_px, fill=False, ec="w", lw=1.2))
        t = np.deg2rad(cfg.bevel_angle_deg)
        bx = cx + cfg.bevel_offset_mm / s * np.cos(t)
        by = cy + cfg.bevel_offset_mm / s * np.sin(t)
        L = 0.5 * cfg.bevel_length_mm / s
        ax.plot([bx + L * np.sin(t), bx - L * np.sin(t)], [by - L * np.cos(t), by + L * np.cos(t)],
                "-", color="r", lw=1.5)
        ax.set_title(f"indenter {k}, press {q.press}\nw = "
                     f"{cal.depth_mm[ps.index(q)]:.3f} mm, bevel score {q.bevel_score:.1f}",
                     fontsize=8)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle("certification frames: footprint (white) and bevel contact (red)", fontsize=9)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def write_calibration_report(cal, out_dir: str | Path, figures: dict[str, Path]) -> Path:
    """Write ``report.html``: the numbers, the rejected presses, the figures.

    Parameters
    ----------
    cal : SessionCalibration
    out_dir : str or Path
    figures : dict of str to Path
        From :func:`calibration_figures`.

    Returns
    -------
    path : Path
    """
    out = Path(out_dir)
    fit = cal.fit
    c = cal.certification
    e = html.escape
    rows = "".join(
        f"<tr><td>{r.press}</td><td>{e(r.reason)}</td><td>{e(r.detail)}</td>"
        f"<td>{r.t_frame_s:.2f}</td></tr>" for r in c.rejected)
    warn = "".join(f"<li>{e(w)}</li>" for w in cal.warnings) or "<li>none</li>"
    if np.isfinite(fit.E_mpa):
        result = (f"<p class=big>E = {fit.E_mpa:.4f} MPa "
                  f"({fit.confidence:.0%} CI {fit.E_ci95_mpa[0]:.4f} to {fit.E_ci95_mpa[1]:.4f}),"
                  f" nu = {fit.nu:.4f} ({fit.nu_ci95[0]:.4f} to {fit.nu_ci95[1]:.4f})</p>")
    else:
        result = f"<p class=big>E and nu not computed: {e(fit.out_of_table_message or '')}</p>"
    figs = _figures_html(figures)
    page = _html_head(f"tactilevision calibrate: {cal.session.path}") + f"""\
<h1>Elastomer calibration of {e(str(cal.session.path))}</h1>
{result}
<p>{len(c.presses)} presses certified, {len(c.rejected)} rejected. Fit of eq. (5)
P/w = c (1 + beta w/h): c = {fit.c_n_per_mm:.4f} N/mm, beta = {fit.beta:.4f},
rmse {fit.rmse_n:.4f} N, R<sup>2</sup> = {fit.r_squared:.5f}; beta and kappa from
the {e(fit.beta_table)} tables ({e(fit.contact)} punch), h = {fit.thickness_mm:g} mm,
a = {fit.radius_mm:g} mm.</p>
<p>Certified depth rule: <b>{e(cal.depth_rule)}</b>
{"(the depth at which the bulging gel meets the block land, from the FEM at the fitted nu)"
 if cal.depth_rule == "land" else "(the paper's w = w0, the indenter's height over the land)"}.
Clock offset t_force - t_frame = {c.clock_offset_s:.4f} s ({e(c.clock_source)}).
Camera noise {c.noise_sigma:.2f} grey levels. Took {cal.seconds:.1f} s.</p>
<h2>Warnings</h2><ul>{warn}</ul>
<h2>Rejected presses</h2>
<table><tr><th>press</th><th>reason</th><th>detail</th><th>t (s)</th></tr>{rows}</table>
<h2>Figures</h2>{figs}
<p>Files: measurements.csv (one row per certified press), fit.json, rejected.csv.</p>
</body></html>
"""
    path = out / "report.html"
    path.write_text(page, encoding="utf-8")
    return path
