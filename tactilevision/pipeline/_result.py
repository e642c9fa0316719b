"""The calibration folder: :class:`CalibrationResult` writes and reads it (I/O edge).

``calibrate`` writes ``fit.json`` (the ``fit --json`` keys, then the session's),
``measurements.csv`` with its ``session.toml``, ``holds.csv``, ``rejected.csv``
and ``design.toml`` (the session's design, to plan the next from: formats.md
section 3). Every reader of such a folder (``history``,
``forces --fit``, ``view --fit``, ``batch calibrate``) goes through
:meth:`CalibrationResult.load`; :func:`write_calibration` writes the folder whole,
with its figures and ``report.html``, or changes nothing.
"""

from __future__ import annotations

import csv
import json
import math
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .._assets import KNOWN_SENSORS, default_calibration_path
from .._checks import InputError
from ..io import Session, StagedOutput, read_holds, read_measurements, write_measurements
from ..mechanics import APPARENT_E
from ..optics import DepthReconstructor, PhotometricCalibration
from ..planning import design_from_calibration, design_toml
from ..viz import calibration_figures, write_calibration_report
from ._calibration import SessionCalibration

__all__ = ["CALIBRATION_FILES", "CalibrationResult", "read_material", "result_dict",
           "session_reconstructor", "write_calibration"]

#: The files a calibration folder holds (the figures and report.html unless ``report=False``).
CALIBRATION_FILES = ("rejected.csv", "measurements.csv", "session.toml", "holds.csv", "fit.json",
                     "design.toml", "report.html", "force_depth.png", "stiffness_line.png",
                     "residuals.png", "mosaic.png", "bevel.png")

_REJECTED = ("press", "reason", "detail", "t_frame_s", "bevel_snr")


def _has_material(fit: dict) -> bool:
    """fit.json's E and nu are finite numbers (a design can be planned from them)."""
    return all(isinstance(fit.get(k), int | float) and math.isfinite(fit[k])
               for k in ("E_mpa", "nu"))


def result_dict(cal: SessionCalibration) -> dict:
    """The ``fit.json`` object of a calibration: the ``fit --json`` keys, then the session's.

    The session's keys include ``sensor_name`` (``[sensor] name``) and
    ``session_date`` (``[session] date`` as an ISO string, or None), which
    ``tactilevision history`` reads.

    Parameters
    ----------
    cal : SessionCalibration
        With a fit (``cal.fit`` not None).

    Returns
    -------
    obj : dict

    Raises
    ------
    InputError
        When nothing was fitted (``cal.failure`` says why).
    """
    if cal.fit is None:
        raise InputError(f"nothing was fitted, so there is no fit.json: {cal.failure}")
    obj = cal.fit.to_json_dict()
    c = cal.certification
    std = cal.depth_std_mm
    cfg = cal.session.config
    obj.update({
        "session": str(cal.session.path),
        "sensor_name": cfg.sensor_name,
        "session_date": cfg.date.isoformat() if cfg.date is not None else None,
        "depth_rule": cal.depth_rule,
        "nu_rounds": cal.nu_rounds,
        "depth_std_median_mm": float(np.median(std)) if len(std) else None,
        "depth_tolerance_mm": cfg.depth_tolerance_mm,
        "depth_bounded": [p.press for p, ok in zip(c.presses, cal.depth_certified, strict=True)
                          if not ok],
        "bevel_optics": c.bevel_optics,
        "bands_not_read": ([p.press for p in c.presses if not p.band_resolved]
                           if c.bevel_optics is not None else None),
        "clock_offset_s": c.clock_offset_s,
        "clock_source": c.clock_source,
        "n_rejected": len(c.rejected),
        "rejected": [_rejection(r) for r in c.rejected],
        "warnings": list(cal.warnings),
        "seconds": cal.seconds,
        "ft_zero": cal.ft_zero.to_json_dict() if cal.ft_zero is not None else None,
        "mark_rule": ({k: (float(v) if isinstance(v, float) else v)
                       for k, v in c.mark_rule.items()} if c.mark_rule is not None else None),
    })
    if cal.relaxation is not None:
        r = cal.relaxation.to_json_dict()
        r["holds"] = "holds.csv"
        if cal.moduli is not None:
            r.update({k: list(v) if isinstance(v, tuple) else v for k, v in cal.moduli.items()})
            r["headline_E"] = "E_mpa is E0_mpa, the instantaneous modulus"
        elif cal.relaxation.verdict == "decay not identified":
            r["headline_E"] = APPARENT_E
        obj["relaxation"] = r
    return obj


def _rejection(r) -> dict:
    """A rejected press as fit.json lists it."""
    return {"press": r.press, "reason": r.reason, "detail": r.detail, "t_frame_s": r.t_frame_s,
            "bevel_snr": r.bevel_score if np.isfinite(r.bevel_score) else None}


@dataclass(frozen=True)
class CalibrationResult:
    """A calibration folder's content: E, nu, their intervals, the relaxation, the clock,
    the certified presses' measurements, the holds, the rejections and the provenance.

    Attributes
    ----------
    fit : dict or None
        The ``fit.json`` object (formats.md section 3); None when nothing was
        fitted (too few certified presses: the folder then has no fit.json).
    measurements : dict of str to (N,) ndarray or None
        The columns of ``measurements.csv`` (formats.md section 2), one row per
        certified press (read back: numbers as float64, text columns as str
        arrays); None when the folder has none.
    holds : dict of str to (K,) ndarray or None
        The columns of ``holds.csv``: ``press``, ``t_s``, ``fz_n``, ``ramp_s``.
    rejected : list of dict
        Each rejected press: ``press``, ``reason``, ``detail``, ``t_frame_s``,
        ``bevel_snr`` (None where no bevel was scored).
    thickness_mm, radius_mm : float
        Layer thickness h and indenter radius a, mm (the measurements' sidecar
        ``session.toml``; NaN when unknown).
    folder : Path or None
        Where it was read from or saved to.
    """

    fit: dict | None
    measurements: dict[str, np.ndarray] | None = None
    holds: dict[str, np.ndarray] | None = None
    rejected: list[dict] = field(default_factory=list)
    thickness_mm: float = math.nan
    radius_mm: float = math.nan
    folder: Path | None = None

    @classmethod
    def from_calibration(cls, cal: SessionCalibration) -> CalibrationResult:
        """What :func:`~tactilevision.pipeline.calibrate_session` found, as saved.

        Parameters
        ----------
        cal : SessionCalibration

        Returns
        -------
        CalibrationResult
        """
        cfg = cal.session.config
        c = cal.certification
        return cls(fit=result_dict(cal) if cal.fit is not None else None,
                   measurements=cal.measurements() if c.presses else None,
                   holds=cal.holds() if cal.fit is not None else None,
                   rejected=[_rejection(r) for r in c.rejected],
                   thickness_mm=cfg.gel_thickness_mm, radius_mm=cfg.indenter_radius_mm)

    # -- what users read -------------------------------------------------------------------
    def _value(self, key: str) -> float:
        v = (self.fit or {}).get(key)
        return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else math.nan

    def _pair(self, key: str) -> tuple[float, float]:
        v = (self.fit or {}).get(key)
        if isinstance(v, list | tuple) and len(v) == 2 and all(
                isinstance(x, int | float) and not isinstance(x, bool) for x in v):
            return float(v[0]), float(v[1])
        return math.nan, math.nan

    @property
    def E_mpa(self) -> float:
        """Young's modulus E, MPa (E_0 for a relaxing gel; NaN when not computed)."""
        return self._value("E_mpa")

    @property
    def nu(self) -> float:
        """Poisson's ratio nu (NaN when not computed)."""
        return self._value("nu")

    @property
    def E_ci95_mpa(self) -> tuple[float, float]:
        """E's 95 % interval, MPa."""
        return self._pair("E_ci95_mpa")

    @property
    def nu_ci95(self) -> tuple[float, float]:
        """nu's 95 % interval."""
        return self._pair("nu_ci95")

    @property
    def n_presses(self) -> int:
        """Presses fitted."""
        n = (self.fit or {}).get("n_presses", (self.fit or {}).get("n"))
        if isinstance(n, int) and not isinstance(n, bool):
            return n
        return 0 if self.measurements is None else len(self.measurements["press"])

    @property
    def clock_offset_s(self) -> float:
        """F/T clock minus camera clock, s (NaN when unknown)."""
        return self._value("clock_offset_s")

    @property
    def relaxation(self) -> dict | None:
        """The relaxation's verdict, g, tau and the moduli (fit.json's ``relaxation``)."""
        r = (self.fit or {}).get("relaxation")
        return r if isinstance(r, dict) else None

    # -- the folder ------------------------------------------------------------------------
    def save(self, folder: str | Path) -> list[str]:
        """Write ``rejected.csv``, ``measurements.csv`` (with its ``session.toml``),
        ``holds.csv``, ``fit.json`` and ``design.toml`` (the session's design, for
        ``tactilevision plan``, where the fit has E and nu) into `folder` (those this
        result has).

        Writes in place: use :func:`write_calibration` (or
        :class:`~tactilevision.io.StagedOutput`) for a folder written whole or
        not at all.

        Parameters
        ----------
        folder : str or Path
            An existing folder.

        Returns
        -------
        names : list of str
            The files written.

        Raises
        ------
        InputError
            A file that cannot be written, or measurements without h and a.
        """
        folder = Path(folder)
        written = []
        try:
            with open(folder / "rejected.csv", "w", newline="") as fh:
                wr = csv.writer(fh)
                wr.writerow(_REJECTED)
                for r in self.rejected:
                    snr = r.get("bevel_snr")
                    wr.writerow([r["press"], r["reason"], r["detail"], f"{r['t_frame_s']:.4f}",
                                 "" if snr is None else f"{snr:.2f}"])
            written.append("rejected.csv")
            if self.measurements is not None:
                write_measurements(folder / "measurements.csv", self.measurements,
                                   thickness_mm=self.thickness_mm, radius_mm=self.radius_mm,
                                   depth_rule=(self.fit or {}).get("depth_rule"))
                written += ["measurements.csv", "session.toml"]
            if self.holds is not None:
                _write_holds(folder / "holds.csv", self.holds)
                written.append("holds.csv")
            if self.fit is not None:
                (folder / "fit.json").write_text(json.dumps(self.fit, indent=2, allow_nan=False)
                                                 + "\n", encoding="utf-8")
                written.append("fit.json")
                if self.measurements is not None and _has_material(self.fit):
                    # the session's design, to plan the next one from (tactilevision plan)
                    try:
                        with warnings.catch_warnings(record=True) as said:
                            warnings.simplefilter("always")
                            design = design_toml(design_from_calibration(folder))
                    except InputError as exc:       # the calibration itself stands
                        warnings.warn(f"no design.toml: {exc}", stacklevel=2)
                    else:
                        for w in said:      # a staging folder's path: the file the user gets
                            warnings.warn(str(w.message).replace(
                                f"{folder}/fit.json: ", "design.toml: the fit's "),
                                w.category, stacklevel=2)
                        (folder / "design.toml").write_text(design, encoding="utf-8")
                        written.append("design.toml")
        except OSError as exc:
            raise InputError(f"cannot write the calibration into {folder}: {exc}") from None
        return written

    @classmethod
    def load(cls, path: str | Path, *, require_fit: bool = True,
             tables: bool = True) -> CalibrationResult:
        """Read a calibration folder written by ``calibrate`` (or :meth:`save`).

        Parameters
        ----------
        path : str or Path
            The folder, or its ``fit.json`` (or any JSON file with the ``fit
            --json`` keys: then only `fit` is read).
        require_fit : bool, default True
            Refuse a folder without ``fit.json`` (nothing was fitted).
        tables : bool, default True
            Also read ``measurements.csv`` and ``holds.csv`` (False: ``fit.json``
            and ``rejected.csv`` only, for a reader that needs E and nu).

        Returns
        -------
        CalibrationResult

        Raises
        ------
        InputError
            Naming the folder or file: it does not exist, has no fit.json (when
            required), fit.json is not valid JSON or not a JSON object, or a
            table is malformed (the message of
            :func:`~tactilevision.io.read_measurements`,
            :func:`~tactilevision.io.read_holds`, or naming rejected.csv's line).
        """
        path = Path(path)
        if path.is_file():
            return cls(fit=_read_fit(path), folder=path.parent)
        if not path.is_dir():
            raise InputError(f"calibration folder {path} does not exist or is not a folder")
        fit_path = path / "fit.json"
        if not fit_path.is_file() and require_fit:
            raise InputError(f"calibration folder {path} has no fit.json (give the output folder "
                             "of tactilevision calibrate)")
        fit = _read_fit(fit_path) if fit_path.is_file() else None
        holds = None
        if tables and (path / "holds.csv").is_file():
            holds = _read_holds(path / "holds.csv")
        columns, h, a = None, math.nan, math.nan
        if tables and (path / "measurements.csv").is_file():
            table = read_measurements(path / "measurements.csv")
            columns = dict(table.columns)
            columns.update({k: np.asarray(v) for k, v in table.labels.items()})
            h, a = table.thickness_mm, table.radius_mm
        return cls(fit=fit, holds=holds, rejected=_read_rejected(path / "rejected.csv"),
                   measurements=columns, thickness_mm=h, radius_mm=a, folder=path)


def read_material(path: str | Path) -> tuple[float, float, dict]:
    """E and nu from a calibration folder or a ``fit --json`` / ``fit.json`` file.

    Parameters
    ----------
    path : str or Path
        The folder ``calibrate`` wrote, or a JSON file with ``E_mpa`` and ``nu``.

    Returns
    -------
    E_mpa : float
        Young's modulus E, MPa.
    nu : float
        Poisson's ratio.
    fit : dict
        The whole JSON object (``beta``, ``thickness_mm`` and the rest).

    Raises
    ------
    InputError
        Naming `path`: it does not exist, is not a JSON object, or has no
        finite numeric ``E_mpa`` and ``nu``.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path} does not exist")
    fit = CalibrationResult.load(path, tables=False).fit or {}
    E, nu = fit.get("E_mpa"), fit.get("nu")
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in (E, nu)):
        raise InputError(f"{path} has no numeric E_mpa and nu (E_mpa {E!r}, nu {nu!r})")
    if not (math.isfinite(E) and math.isfinite(nu)):
        raise InputError(f"{path} has E_mpa = {E} and nu = {nu}: not a usable fit")
    return float(E), float(nu), fit


def _read_fit(path: Path) -> dict:
    """fit.json as a dict, or an InputError naming the file."""
    try:
        obj = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise InputError(f"{path} is not valid JSON: {exc}") from None
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror}") from None
    if not isinstance(obj, dict):
        raise InputError(f"{path} is not a JSON object")
    return obj


def _read_holds(path: Path) -> dict[str, np.ndarray]:
    """holds.csv's columns (empty columns for a header alone)."""
    with open(path, newline="") as fh:
        rows = [r for r in csv.reader(fh) if r]
    if len(rows) <= 1:
        return {"press": np.zeros(0, np.int64), "t_s": np.zeros(0), "fz_n": np.zeros(0),
                "ramp_s": np.zeros(0)}
    return read_holds(path)


def _read_rejected(path: Path) -> list[dict]:
    """rejected.csv's rows ([] when absent), or an InputError naming file and line."""
    if not path.is_file():
        return []
    out = []
    with open(path, newline="") as fh:
        reader = csv.DictReader(fh)
        missing = [k for k in _REJECTED if k not in (reader.fieldnames or [])]
        if missing:
            raise InputError(f"{path}: no column {', '.join(missing)} (rejected.csv has "
                             f"{', '.join(_REJECTED)})")
        for line, row in enumerate(reader, start=2):
            try:
                out.append({"press": int(row["press"]), "reason": row["reason"],
                            "detail": row["detail"], "t_frame_s": float(row["t_frame_s"]),
                            "bevel_snr": float(row["bevel_snr"]) if row["bevel_snr"] else None})
            except (TypeError, ValueError):
                raise InputError(f"{path}, line {line}: press, t_frame_s or bevel_snr is not "
                                 "a number") from None
    return out


def _write_holds(path: Path, holds: dict) -> None:
    """``holds.csv``: press, t_s (since the hold's start), fz_n over each press's hold, and
    the press's loading time ramp_s (empty when not found)."""
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["press", "t_s", "fz_n", "ramp_s"])
        for p, t, f, r in zip(holds["press"], holds["t_s"], holds["fz_n"], holds["ramp_s"],
                              strict=True):
            w.writerow([int(p), f"{t:.4f}", f"{f:.9g}", "" if np.isnan(r) else f"{r:.4f}"])


def session_reconstructor(session: Session) -> DepthReconstructor | None:
    """Depth reconstructor of the session's sensor (its ``[sensor] calibration``, else the
    bundled one of a known sensor), or None when there is none of the frames' shape."""
    cfg = session.config
    path = cfg.calibration
    if path is None and cfg.sensor_name in KNOWN_SENSORS:
        path = default_calibration_path(cfg.sensor_name)
    if path is None:
        return None
    cal = PhotometricCalibration.load(path)
    if cal.shape != session.shape:
        return None
    return DepthReconstructor(cal, reference=session.reference)


def write_calibration(cal: SessionCalibration, out: str | Path, *, overwrite: bool = False,
                      report: bool = True) -> CalibrationResult:
    """Write a calibration folder whole (tables, fit.json, figures, report.html), or nothing.

    Parameters
    ----------
    cal : SessionCalibration
        From :func:`~tactilevision.pipeline.calibrate_session` (a failed one
        too: its rejections, measurements and report say why).
    out : str or Path
        The folder; created if needed.
    overwrite : bool, default False
        Replace files in `out` that tactilevision did not write.
    report : bool, default True
        Also the figures and ``report.html``.

    Returns
    -------
    CalibrationResult
        What was written, ``folder`` set to `out`.

    Raises
    ------
    InputError
        `out` cannot be written, or holds files tactilevision did not write
        (without `overwrite`): nothing is changed then.
    """
    out = Path(out)
    result = CalibrationResult.from_calibration(cal)
    with StagedOutput(out, overwrite=overwrite) as stage:
        result.save(stage.path)
        if report:
            figs = calibration_figures(cal, stage.path,
                                       reconstructor=session_reconstructor(cal.session))
            write_calibration_report(cal, stage.path, figs)
        stage.commit()
    return replace(result, folder=out)
