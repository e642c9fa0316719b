"""Figures and the HTML page of ``tactilevision diagnose``."""

from __future__ import annotations

import html
import math
from pathlib import Path

import numpy as np

from ..mechanics import make_effect
from ._calibration import figures_html, html_head, pyplot

__all__ = ["diagnosis_figures", "write_diagnosis_report"]


def _binned(x: np.ndarray, y: np.ndarray, bins: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Mean of y in quantile bins of x (or per value when x has few)."""
    values = np.unique(x)
    if values.size <= bins:
        return values, np.array([y[x == v].mean() for v in values])
    edges = np.unique(np.quantile(x, np.linspace(0, 1, bins + 1)))
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, edges.size - 2)
    keep = [i for i in range(edges.size - 1) if np.any(idx == i)]
    return (np.array([x[idx == i].mean() for i in keep]),
            np.array([y[idx == i].mean() for i in keep]))


def diagnosis_figures(diag, out_dir: str | Path, *, dpi: int = 100) -> dict[str, Path]:
    """Write the diagnosis figures.

    Parameters
    ----------
    diag : Diagnosis
    out_dir : str or Path
        Created if needed.
    dpi : int, default 100

    Returns
    -------
    figures : dict of str to Path
        ``residuals`` (residuals_by_covariate.png: residuals in mN against
        each covariate, the model diagnosed on top and after the added
        effects below, with binned means and each test's p-value) and
        ``ladder`` (error_ladder.png: RMSE and cross-validated RMSE of each
        step as bars, the replicate noise floor as a line, E at each step).
    """
    plt = pyplot()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    figs: dict[str, Path] = {}
    cols = diag.columns
    tests = {t.name: t for t in diag.covariates}
    after = {t.name: t for t in diag.covariates_after}
    names = [t.name for t in diag.covariates]
    first, last = diag.fits[0], diag.fits[-1]
    rows = [("model diagnosed", first, tests, diag.fit_rows[0])]
    if len(diag.fits) > 1:
        rows.append((f"+ {', '.join(s.added for s in diag.ladder[1:])}", last, after,
                     diag.fit_rows[-1]))
    ncol = min(4, max(1, len(names)))
    nrow_per = math.ceil(len(names) / ncol) if names else 1
    fig, axes = plt.subplots(nrow_per * len(rows), ncol, squeeze=False,
                             figsize=(3.4 * ncol, 2.6 * nrow_per * len(rows)))
    for r, (label, fit, tdict, mask) in enumerate(rows):
        for k, name in enumerate(names):
            ax = axes[r * nrow_per + k // ncol, k % ncol]
            x = cols[name][mask]
            res = fit.residuals_n * 1e3
            ok = np.isfinite(x)
            hit = name == diag.unexplained_covariate or (
                diag.missing_effect is not None and name in _effect_columns(diag.missing_effect))
            ax.scatter(x[ok], res[ok], s=8, alpha=0.6, color="C3" if hit and r == 0 else "C0")
            if ok.sum() > 2:
                bx, by = _binned(x[ok], res[ok])
                ax.plot(bx, by, "k-", lw=1.5)
            ax.axhline(0, color="0.5", lw=0.8)
            t = tdict.get(name)
            ptxt = f"p = {t.p_value:.1g}, {t.explained_fraction:.0%}" if t else ""
            ax.set_title(f"{name}  {ptxt}", fontsize=9,
                         color="C3" if t is not None and t.significant else "k")
            ax.tick_params(labelsize=8)
            if k % ncol == 0:
                ax.set_ylabel(f"{label}\nresidual (mN)", fontsize=8)
        for k in range(len(names), nrow_per * ncol):
            axes[r * nrow_per + k // ncol, k % ncol].axis("off")
    fig.suptitle("Residuals against every covariate (red title: significant structure)",
                 fontsize=10)
    fig.tight_layout()
    figs["residuals"] = out / "residuals_by_covariate.png"
    fig.savefig(figs["residuals"], dpi=dpi)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(1.8 + 1.6 * len(diag.ladder), 3.8))
    x = np.arange(len(diag.ladder))
    ax.bar(x - 0.2, [s.rmse_n * 1e3 for s in diag.ladder], 0.4, label="RMSE")
    ax.bar(x + 0.2, [s.cv_rmse_n * 1e3 for s in diag.ladder], 0.4,
           label="cross-validated RMSE")
    if math.isfinite(diag.noise_floor_n):
        ax.axhline(diag.noise_floor_n * 1e3, color="k", ls="--",
                   label=f"noise floor {diag.noise_floor_n * 1e3:.2f} mN")
    labels = []
    for s in diag.ladder:
        head = "base" if s.added is None else f"+ {s.added}"
        et = (f"E {s.E_mpa:.3g} MPa\nnu {s.nu:.3f}" if math.isfinite(s.E_mpa)
              else "E, nu: -")
        labels.append(f"{head}\n{et}")
    ax.set_xticks(x, labels, fontsize=8)
    ax.set_ylabel("force error (mN)")
    ax.set_title("Error ladder")
    ax.legend(fontsize=8)
    fig.tight_layout()
    figs["ladder"] = out / "error_ladder.png"
    fig.savefig(figs["ladder"], dpi=dpi)
    plt.close(fig)
    return figs


def _effect_columns(name: str) -> tuple[str, ...]:
    return tuple(make_effect(name).columns)


def write_diagnosis_report(diag, out_dir: str | Path, figures: dict[str, Path], *,
                           source: str = "") -> Path:
    """Write ``report.html``: the story, the tests, the candidates, the figures.

    Parameters
    ----------
    diag : Diagnosis
    out_dir : str or Path
    figures : dict of str to Path
        From :func:`diagnosis_figures`.
    source : str
        The table's path, for the title.

    Returns
    -------
    path : Path
    """
    e = html.escape
    out = Path(out_dir)

    def num(v: float, fmt: str = ".3g") -> str:
        return format(v, fmt) if math.isfinite(v) else "-"

    cov = "".join(
        f"<tr><td>{e(t.name)}</td><td>{t.p_value:.2g}</td><td>{t.explained_fraction:.0%}</td>"
        f"<td>{'yes' if t.significant else ''}</td></tr>" for t in diag.covariates)
    def params(c) -> str:
        return ", ".join(f"{k.split('.', 1)[1]} = {v:.4g}" for k, v in c.params.items())

    cand = "".join(
        f"<tr><td>{e(c.effect)}</td><td>{c.delta_bic:.1f}</td><td>{num(c.cv_rmse_n * 1e3)}</td>"
        f"<td>{e(params(c))}</td></tr>" for c in diag.candidates)
    ladder = "".join(
        f"<tr><td>{e(' + '.join(s.model))}</td><td>{s.rmse_n * 1e3:.3f}</td>"
        f"<td>{s.cv_rmse_n * 1e3:.3f}</td><td>{num(s.E_mpa, '.4f')}</td>"
        f"<td>{num(s.nu, '.4f')}</td></tr>" for s in diag.ladder)
    figs = figures_html(figures)
    verdict = diag.missing_effect or "nothing missing"
    page = html_head(f"tactilevision diagnose: {source}") + f"""\
<h1>Model against measurement: {e(source)}</h1>
<p class=big>Verdict: <b>{e(verdict)}</b>{
    f"; unexplained structure along <b>{e(diag.unexplained_covariate)}</b>"
    if diag.unexplained_covariate else ""}</p>
<p>{e(diag.message)}</p>
<h2>Error ladder</h2>
<table><tr><th>model</th><th>RMSE (mN)</th><th>CV RMSE (mN)</th><th>E (MPa)</th><th>nu</th></tr>
{ladder}</table>
<p>Replicate noise floor: {num(diag.noise_floor_n * 1e3, '.3f')} mN.</p>
<h2>Where the model diagnosed fails</h2>
<table><tr><th>covariate</th><th>p-value</th><th>residual variance explained</th>
<th>significant</th></tr>{cov}</table>
<h2>Candidate effects (model + one effect)</h2>
<table><tr><th>effect</th><th>delta BIC</th><th>CV RMSE (mN)</th><th>parameters</th></tr>
{cand}</table>
<h2>Figures</h2>{figs}
</body></html>
"""
    path = out / "report.html"
    path.write_text(page, encoding="utf-8")
    return path
