"""Figures of E and nu against date, and the self-contained ``report.html`` (I/O edge)."""

from __future__ import annotations

import base64
import datetime
import html
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ..viz import html_head, pyplot
from ._read import CalibrationRecord
from ._table import HISTORY_COLUMNS
from ._trend import Assessment

__all__ = ["history_figures", "write_history_report"]


def _safe(sensor: str) -> str:

    return re.sub(r"[^A-Za-z0-9_.-]", "_", sensor) or "unnamed"


def _errorbars(ax, dates, values, ci, beyond, label: str) -> None:
    v = np.asarray(values)
    lo = v - np.array([c[0] for c in ci])
    hi = np.array([c[1] for c in ci]) - v
    ok = ~np.asarray(beyond)
    for mask, colour, lab in ((ok, "C0", label), (~ok, "C3", f"{label}, outside day 0's "
                                                               "interval")):
        if mask.any():
            ax.errorbar([d for d, m in zip(dates, mask, strict=True) if m], v[mask],
                        yerr=[lo[mask], hi[mask]], fmt="o", color=colour, capsize=4, label=lab)


def history_figures(records: Sequence[CalibrationRecord], assessment: Assessment,
                    out_dir: str | Path, *, dpi: int = 100) -> dict[str, Path]:
    """Write ``E_<sensor>.png`` and ``nu_<sensor>.png``: each calibration against its date.

    E: each calibration with its interval (red when outside the first's),
    the first calibration's interval as a band, the weighted trend with its
    interval, and the date from which the first E was stale. nu: each
    calibration with its interval and the first's band.

    Parameters
    ----------
    records : sequence of CalibrationRecord
        One sensor's, sorted by date.
    assessment : Assessment
        :func:`~tactilevision.history.assess` of `records`.
    out_dir : str or Path
        An existing folder.
    dpi : int, default 100

    Returns
    -------
    figures : dict of str to Path
        ``'E'`` and ``'nu'`` to the files written.
    """
    plt = pyplot()
    out = Path(out_dir)
    name = _safe(assessment.sensor)
    first = records[0]
    dates = [r.date for r in records]
    figs = {}

    fig, ax = plt.subplots(figsize=(7, 4), dpi=dpi)
    ax.axhspan(*first.E_ci95_mpa, color="C0", alpha=0.12, label="day 0's interval")
    _errorbars(ax, dates, [r.E_mpa for r in records], [r.E_ci95_mpa for r in records],
               assessment.beyond, "E, 95% interval")
    tr = assessment.trend
    if tr is not None:
        d = np.linspace(0.0, float(assessment.days.max()), 50)
        x = [first.date + datetime.timedelta(days=float(t)) for t in d]
        ax.plot(x, tr.at(d), "k-", lw=1, label="weighted trend")
        ax.fill_between(x, tr.at(d) - tr.band(d), tr.at(d) + tr.band(d), color="k", alpha=0.08)
    if assessment.stale_from is not None:
        ax.axvline(assessment.stale_from, color="C3", ls="--", lw=1,
                   label=f"stale from {assessment.stale_from.isoformat()}")
    ax.set_xlabel("date")
    ax.set_ylabel("E (MPa)")
    ax.set_title(f"{assessment.sensor}: Young's modulus")
    ax.legend(fontsize=8)
    fig.autofmt_xdate()
    fig.tight_layout()
    figs["E"] = out / f"E_{name}.png"
    fig.savefig(figs["E"])
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 4), dpi=dpi)
    ax.axhspan(*first.nu_ci95, color="C1", alpha=0.12, label="day 0's interval")
    lo, hi = first.nu_ci95
    nu_beyond = [i > 0 and not lo <= r.nu <= hi for i, r in enumerate(records)]
    _errorbars(ax, dates, [r.nu for r in records], [r.nu_ci95 for r in records], nu_beyond,
               "nu, 95% interval")
    ax.set_xlabel("date")
    ax.set_ylabel("nu")
    ax.set_title(f"{assessment.sensor}: Poisson's ratio")
    ax.legend(fontsize=8)
    fig.autofmt_xdate()
    fig.tight_layout()
    figs["nu"] = out / f"nu_{name}.png"
    fig.savefig(figs["nu"])
    plt.close(fig)
    return figs


def _img(path: Path, alt: str) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return (f'<figure><img src="data:image/png;base64,{data}" alt="{html.escape(alt)}">'
            "</figure>")


def write_history_report(out_dir: str | Path,
                         sensors: Mapping[str, tuple[Sequence[CalibrationRecord], Assessment,
                                                     list[dict], Mapping[str, Path]]],
                         pooled: Mapping[str, str] | None = None) -> Path:
    """Write ``report.html``: per sensor, the verdict, the table and the figures.

    The page has the style of ``calibrate``'s report
    (:func:`~tactilevision.viz.write_calibration_report`) and is
    self-contained: the figures are embedded as data URIs (their PNG files
    stay beside it too).

    Parameters
    ----------
    out_dir : str or Path
        An existing folder.
    sensors : mapping of str to (records, assessment, rows, figures)
        Per sensor: its calibrations, :func:`~tactilevision.history.assess`,
        :func:`~tactilevision.history.history_rows` and
        :func:`history_figures`.
    pooled : mapping of str to str, optional
        Per sensor, a sentence on its pooled presses
        (:meth:`PooledDiagnosis.summary`), shown under the verdict.

    Returns
    -------
    path : Path
        ``out_dir/report.html``.
    """
    e = html.escape
    parts = [html_head("tactilevision history"), "<h1>Calibration history</h1>\n"]
    for sensor, (records, a, rows, figs) in sensors.items():
        verdict = "recalibrate" if a.recalibrate else "within its calibration"
        parts.append(f"<h2>{e(sensor)}: {len(records)} calibration(s), {e(verdict)}</h2>\n")
        parts.append('<p class="big">' + "<br>".join(e(s.strip())
                                                      for s in a.message.split("\n")) + "</p>\n")
        if pooled and sensor in pooled:
            parts.append(f"<p>{e(pooled[sensor])}</p>\n")
        shown = [c for c in HISTORY_COLUMNS if c not in ("folder", "date_source")]
        parts.append("<table><tr>" + "".join(f"<th>{e(c)}</th>" for c in shown) + "</tr>\n")
        for row in rows:
            cells = []
            for c in shown:
                v = row[c]
                cells.append("" if v is None else f"{v:.4g}" if isinstance(v, float) else str(v))
            style = ' style="color:#b00"' if row["beyond_day0_ci"] else ""
            parts.append(f"<tr{style}>" + "".join(f"<td>{e(x)}</td>" for x in cells)
                         + "</tr>\n")
        parts.append("</table>\n<p>Folders: " + ", ".join(
            f"{e(r['date'])}: <code>{e(r['folder'])}</code> (date from {e(r['date_source'])})"
            for r in rows) + "</p>\n")
        parts.extend(_img(p, f"{k} of {sensor}") for k, p in figs.items())
    parts.append("</body></html>\n")
    path = Path(out_dir) / "report.html"
    path.write_text("".join(parts), encoding="utf-8")
    return path
