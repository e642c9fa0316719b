"""Figures and the HTML page of a session calibration (``tactilevision calibrate``)."""

from __future__ import annotations

import html
from pathlib import Path

import cv2
import numpy as np

from ..planning import untestable_in_table
from ._depth import _scale_bar

__all__ = ["bevel_panels", "calibration_figures", "figures_html", "fitted_forces", "html_head",
           "pyplot", "write_calibration_report"]


def pyplot():
    """matplotlib.pyplot on the non-interactive Agg backend (unless one is already chosen)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def html_head(title: str) -> str:
    """Opening of a report page (escaped title, the shared style)."""
    return (f'<!doctype html>\n<html><head><meta charset="utf-8"><title>{html.escape(title)}'
            "</title>\n<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto}\n"
            ".big{font-size:1.3em} td,th{padding:2px 8px;text-align:left}\n"
            "img{max-width:100%} figure{margin:1em 0}</style></head><body>\n")


def figures_html(figures: dict[str, Path]) -> str:
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


def fitted_forces(cal) -> tuple[np.ndarray, str]:
    """The forces a session's fit used, and what they are, for the figures' axes.

    Parameters
    ----------
    cal : SessionCalibration

    Returns
    -------
    force_n : (N,) float64 ndarray
        Each certified press's force as the fit used it, N
        (:attr:`~tactilevision.SessionCalibration.force_fit_n`; the F/T
        window's mean when a calibration carries none).
    what : str
        What was taken off the F/T window's mean, for an axis label.
    """
    ps = cal.certification.presses
    f = np.asarray(getattr(cal, "force_fit_n", np.zeros(0)), np.float64)
    if f.shape != (len(ps),):
        return np.array([q.force_n for q in ps], np.float64), "F/T window mean"
    parts = []
    if len(getattr(cal, "force0_n", ())) == len(ps):
        parts.append("at the instant of loading")
    if np.any(np.asarray(cal.bevel_force_n) != 0):
        parts.append("less the bevel's band")
    zero = getattr(cal, "ft_zero", None)
    if zero is not None and zero.subtracted_n:
        parts.append("less the F/T zero")
    return f, "as fitted" + (": " + ", ".join(parts) if parts else "")


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
        ``force_depth``, ``stiffness_line``, ``residuals`` (with a fit),
        ``mosaic`` (with a certified press), ``bevel`` (the bevel of every
        press, certified or rejected).
    """
    plt = pyplot()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths: dict[str, Path] = {}
    if cal.fit is None:
        if cal.certification.presses:
            paths["mosaic"] = _mosaic(cal, out / "mosaic.png", reconstructor, dpi)
        paths["bevel"] = bevel_panels(cal, out / "bevel.png", dpi=dpi)
        return paths
    fit = cal.fit
    ps = cal.certification.presses
    w = cal.depth_mm
    p, what = fitted_forces(cal)
    ind = np.array([q.indenter for q in ps])
    h = fit.thickness_mm
    ok = np.isfinite(fit.c_n_per_mm) and np.isfinite(fit.beta)
    ww = np.linspace(0, w.max() * 1.08, 200)

    fig, ax = plt.subplots(figsize=(5.5, 4), layout="constrained")
    sd = cal.depth_std_mm if len(cal.depth_std_mm) == len(ps) else np.zeros(len(ps))
    for k in np.unique(ind):
        s = ind == k
        w0 = ps[np.flatnonzero(s)[0]].w0_mm
        ax.errorbar(w[s], p[s], xerr=2 * sd[s], fmt="o", ms=4, elinewidth=0.8,
                    label=f"indenter {k} (w0 = {w0:g} mm)")
    if ok:
        ax.plot(ww, ww * _fit_line(fit, ww), "-", color="0.3",
                label=f"eq. (5): c = {fit.c_n_per_mm:.3f} N/mm, beta = {fit.beta:.3f}")
    ax.set_xlabel("certified depth w (mm; bars: 2 sd)")
    ax.set_ylabel(f"force P (N), {what}", fontsize=8)
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
    ax.set_ylabel(f"P / w (N/mm), P {what}", fontsize=8)
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
    a1.text(0.01, 0.99, f"P {what}; mean {1e3 * float(np.mean(res)):+.2f} mN, rms "
            f"{1e3 * float(np.sqrt(np.mean(res ** 2))):.2f} mN", transform=a1.transAxes,
            va="top", fontsize=7)
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
    paths["bevel"] = bevel_panels(cal, out / "bevel.png", dpi=dpi)
    return paths


def _mosaic(cal, path: Path, reconstructor, dpi: int) -> Path:
    plt = pyplot()
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
        t = np.deg2rad(cfg.bevel_direction_deg)
        bx = cx + cfg.bevel_offset_mm / s * np.cos(t)
        by = cy + cfg.bevel_offset_mm / s * np.sin(t)
        L = 0.5 * cfg.bevel_length_mm / s
        ax.plot([bx + L * np.sin(t), bx - L * np.sin(t)], [by - L * np.cos(t), by + L * np.cos(t)],
                "-", color="r", lw=1.5)
        ax.set_title(f"indenter {k}, press {q.press}\nw = "
                     f"{cal.depth_mm[ps.index(q)]:.4f} mm, bevel SNR {q.bevel_score:.0f}",
                     fontsize=8)
        ax.set_xticks([])
        ax.set_yticks([])
        _scale_bar(ax, frame.shape[:2], s, "w")      # the panels' spatial scale, mm
    fig.suptitle("certification frames: footprint (white) and the bevel's crest (red)",
                 fontsize=9)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def bevel_panels(cal, path: str | Path, *, dpi: int = 100, columns: int = 8) -> Path:
    """One small panel per press: its bevel, seen across the crest, and what was read.

    Each panel is the colour change (frame - reference, the three channels
    stretched to the press's own range) in the bevel's frame: across the
    crest horizontally (the indenter to the left), along the crest
    vertically, at the frame certification used (its window's first frame)
    or, for a rejected press, the frame its rejection names. For a vernier
    (``bevel_angle_deg > 0``) the dashed lines mark the crest and the
    band's edges read (crest +- L); the title gives the press, w0, the
    overshoot past w0 with its standard uncertainty and the signal-to-noise
    ratio, or the rejection's reason.

    Parameters
    ----------
    cal : SessionCalibration
    path : str or Path
        PNG to write.
    dpi : int, default 100
    columns : int, default 10

    Returns
    -------
    path : Path
    """
    plt = pyplot()
    cert = cal.certification
    cfg = cal.session.config
    s = cfg.mm_per_px
    tan = float(np.tan(np.deg2rad(cfg.bevel_angle_deg)))
    reach_mm = max(0.6, min(0.1 / tan, 3.0) + 0.25) if tan > 0 else 0.8
    items = [("ok", q) for q in cert.presses] + [("rej", r) for r in cert.rejected]
    items.sort(key=lambda it: it[1].press)
    n = max(len(items), 1)
    cols = min(columns, n)
    rows = -(-n // cols)
    # a fixed grid (image panels with no axes: nothing for a layout engine to place; the
    # constrained layout took most of the figure's time for 50 panels)
    fig_w, fig_h = 2.1 * cols, 2.3 * rows + 0.8
    fig, axes = plt.subplots(rows, cols, figsize=(fig_w, fig_h), squeeze=False,
                             gridspec_kw={"left": 0.01, "right": 0.99, "bottom": 0.01,
                                          "top": 1 - 1.0 / fig_h, "wspace": 0.12,
                                          "hspace": 0.5})
    depth = {q.press: (d, sd) for q, d, sd in zip(
        cert.presses, cal.depth_mm,
        cal.depth_std_mm if len(cal.depth_std_mm) == len(cert.presses)
        else np.zeros(len(cert.presses)), strict=True)}
    t = np.deg2rad(cfg.bevel_direction_deg)
    for ax in axes.ravel():
        ax.set_axis_off()
    for ax, (kind, q) in zip(axes.ravel(), items, strict=False):
        centre = (tuple(q.footprint.center_px) if kind == "ok" else q.centre_px)
        if centre is None:
            ax.text(0.5, 0.5, f"press {q.press}\n{q.reason}", ha="center", va="center",
                    fontsize=8, transform=ax.transAxes, color="C3")
            continue
        bx = centre[0] + cfg.bevel_offset_mm / s * np.cos(t)
        by = centre[1] + cfg.bevel_offset_mm / s * np.sin(t)
        u = np.arange(-reach_mm, reach_mm + 1e-9, s) / s
        v = np.arange(-0.6 * cfg.bevel_length_mm, 0.6 * cfg.bevel_length_mm + 1e-9, s) / s
        uu, vv = np.meshgrid(u, v)
        x = (bx + uu * np.cos(t) - vv * np.sin(t)).astype(np.float32)
        y = (by + uu * np.sin(t) + vv * np.cos(t)).astype(np.float32)
        frame = cal.session.frame(q.frame).astype(np.float32)
        d = frame - cal.session.reference.astype(np.float32)
        crop = cv2.remap(d, x, y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                         borderValue=(0, 0, 0))
        lim = max(float(np.percentile(np.abs(crop), 99)), 1.0)
        rgb = np.clip(0.5 + 0.5 * crop[..., ::-1] / lim, 0, 1)
        ax.imshow(rgb, extent=(u[0] * s, u[-1] * s, v[-1] * s, v[0] * s), aspect="auto")
        if kind == "ok":
            r = q.reading
            dd, sd = depth[q.press]
            if r is not None:
                for e in (r.crest_px - r.half_width_px, r.crest_px, r.crest_px + r.half_width_px):
                    ax.axvline(e * s, color="w" if e != r.crest_px else "y", lw=0.7, ls="--")
                title = (f"press {q.press} (w0 {q.w0_mm:g})\n+{1e3 * (dd - q.w0_mm):.1f} "
                         f"± {1e3 * sd:.1f} um, SNR {q.bevel_score:.0f}")
            else:
                title = f"press {q.press} (w0 {q.w0_mm:g})\nmark SNR {q.bevel_score:.0f}"
            ax.set_title(title, fontsize=8)
        else:
            snr = "" if not np.isfinite(q.bevel_score) else f", SNR {q.bevel_score:.0f}"
            ax.set_title(f"press {q.press}: rejected\n{q.reason}{snr}", fontsize=8, color="C3")
    mode = ("vernier: dashed lines at the crest (yellow) and the band's edges read; "
            "titles: overshoot past w0 ± 1 sd" if tan > 0 else "bevel mark at its onset")
    fig.suptitle(f"the bevel of every press, across the crest (mm; indenter to the left)\n"
                 f"{mode}", fontsize=10, y=1 - 0.1 / fig_h, va="top")
    out = Path(path)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return out


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
    c = cal.certification
    e = html.escape
    rows = "".join(
        f"<tr><td>{r.press}</td><td>{e(r.reason)}</td><td>{e(r.detail)}</td>"
        f"<td>{r.t_frame_s:.2f}</td></tr>" for r in c.rejected)
    result, fit_text, warn = _fit_html(cal)
    rule_text = _DEPTH_RULE_TEXT[cal.depth_rule]
    optics = c.bevel_optics
    optics_text = ("" if not optics else
                   f" Bevel read with an edge blur of {optics['blur_px']:g} px (chosen on "
                   f"{optics['n_bands']} long bands)"
                   + ("; short bands leaned on the session's flank colours" if optics.get("prior")
                      else "") + ".")
    table = _presses_html(cal)
    figs = figures_html(figures)
    page = html_head(f"tactilevision calibrate: {cal.session.path}") + f"""\
<h1>Elastomer calibration of {e(str(cal.session.path))}</h1>
{result}
<p>{len(c.presses)} presses certified, {len(c.rejected)} rejected. {fit_text}</p>
<p>Certified depth rule: <b>{e(cal.depth_rule)}</b> ({rule_text}).{optics_text}
Clock offset t_force - t_frame = {c.clock_offset_s:.4f} s ({e(c.clock_source)}).
Camera noise {c.noise_sigma:.2f} grey levels. Took {cal.seconds:.1f} s.</p>
<h2>Warnings and notes</h2><ul>{warn}</ul>
{_untestable_html(cal)}
<h2>Rejected presses</h2>
<table><tr><th>press</th><th>reason</th><th>detail</th><th>t (s)</th></tr>{rows}</table>
{table}
<h2>Figures</h2>{figs}
<p>Files: measurements.csv (one row per certified press), fit.json, rejected.csv.</p>
</body></html>
"""
    path = out / "report.html"
    path.write_text(page, encoding="utf-8")
    return path


#: The certified depth rules of the report, in words.
_DEPTH_RULE_TEXT = {
    "land": "the depth at which the bulging gel meets the block land, from the FEM at the "
            "fitted nu",
    "mark": "w0, the indenter's height over the land at the first frame showing the bevel "
            "mark, plus what the force says the stage went on by past it (the force's rise "
            "from the frame period before that frame to the window, over eq. (5)'s slope)",
    "nominal": "the paper's w = w0, the indenter's height over the land, at the first frame "
               "showing the bevel mark",
    "vernier": "w0 plus the overshoot read on the bevel: the band of contact on its flanks, "
               "half-width L, closes the gap by L tan(theta); less the gel's bulge there "
               "(FEM) when bulge_correction is on",
}


def _untestable_html(cal) -> str:
    """The report's "What this session could not test" paragraph ('' with no presses).

    The catalogue effects whose column is constant or missing in this session's
    measurements table (:func:`tactilevision.planning.untestable_in_table`, the test
    ``diagnose`` and ``plan`` make), each with why and what would make it testable.
    """
    if not cal.certification.presses:
        return ""
    e = html.escape
    why = untestable_in_table(cal.measurements(), window_at=cal.session.config.window_at)
    if not why:
        return ("<h2>What this session could not test</h2><p>Nothing: every effect of the "
                "catalogue has a column that varies in measurements.csv, so "
                "<code>tactilevision diagnose</code> can test each.</p>")
    items = "".join(f"<li><b>{e(k)}</b>: {e(v)}</li>" for k, v in why.items())
    return ("<h2>What this session could not test</h2><p>"
            f"<code>tactilevision diagnose</code> cannot test {len(why)} effect(s) of the "
            "catalogue on this session's measurements.csv: the column each needs does not "
            "vary. Its verdict says nothing about them. <code>tactilevision plan "
            "--from-calibration</code> on this folder plans a session that can.</p>"
            f"<ul>{items}</ul>")


def _fit_html(cal) -> tuple[str, str, str]:
    """The report's result line, the fit's sentence and the warnings' list items."""
    fit = cal.fit
    e = html.escape
    warn = "".join(f"<li>{e(w)}</li>" for w in cal.warnings) or "<li>none</li>"
    if fit is None:
        result = (f"<p class=big>Nothing was fitted: {e(cal.failure or '')}</p>"
                  "<p>The bevel panels below show what each press looked like and why it was "
                  "rejected.</p>")
        return result, "", warn
    if np.isfinite(fit.E_mpa):
        result = (f"<p class=big>E = {fit.E_mpa:.4f} MPa ({fit.confidence:.0%} CI "
                  f"{fit.E_ci95_mpa[0]:.4f} to {fit.E_ci95_mpa[1]:.4f}), nu = {fit.nu:.4f} "
                  f"({fit.nu_ci95[0]:.4f} to {fit.nu_ci95[1]:.4f})</p>")
    else:
        result = (f"<p class=big>E and nu not computed: "
                  f"{e(fit.out_of_table_message or '')}</p>")
    fit_text = (f"Fit of eq. (5) P/w = c (1 + beta w/h): c = {fit.c_n_per_mm:.4f} N/mm, "
                f"beta = {fit.beta:.4f}, rmse {fit.rmse_n:.4f} N, R<sup>2</sup> = "
                f"{fit.r_squared:.5f}; beta and kappa from the {e(fit.beta_table)} tables "
                f"({e(fit.contact)} punch), h = {fit.thickness_mm:g} mm, "
                f"a = {fit.radius_mm:g} mm. Intervals: {e(fit.ci_method)}.")
    notes = [n for n in fit.notes if n not in cal.warnings]
    warn += "".join(f"<li>{e(n)}</li>" for n in notes if "interval" in n or "table" in n)
    return result, fit_text, warn


def _presses_html(cal) -> str:
    """The table of certified presses ('' when none)."""
    c = cal.certification
    e = html.escape
    if not c.presses:
        return ""
    sd = (cal.depth_std_mm if len(cal.depth_std_mm) == len(c.presses)
          else np.zeros(len(c.presses)))
    bulge = cal.bulge_mm if len(cal.bulge_mm) == len(c.presses) else np.zeros(len(c.presses))
    fitted, what = (fitted_forces(cal) if cal.fit is not None
                    else (np.full(len(c.presses), np.nan), ""))
    trs = "".join(
        f"<tr><td>{q.press}</td><td>{q.indenter}</td><td>{q.w0_mm:g}</td>"
        f"<td>{d:.5f}</td><td>{1e3 * u:.2f}</td><td>{1e3 * (d - q.w0_mm):+.2f}</td>"
        f"<td>{1e3 * b:.2f}</td><td>{q.force_n:.4f}</td><td>{f:.4f}</td>"
        f"<td>{q.bevel_score:.0f}</td></tr>"
        for q, d, u, b, f in zip(c.presses, cal.depth_mm, sd, bulge, fitted, strict=True))
    return ("<h2>Certified presses</h2>"
            + (f"<p>force P: {e(what)}.</p>" if what else "")
            + "<table><tr><th>press</th><th>indenter</th>"
            "<th>w0 (mm)</th><th>depth (mm)</th><th>sd (um)</th><th>overshoot (um)</th>"
            "<th>bulge (um)</th><th>F/T window mean (N)</th><th>force P fitted (N)</th>"
            "<th>bevel SNR</th></tr>"
            f"{trs}</table>")
