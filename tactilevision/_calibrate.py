"""The main job: a session folder in, certified presses and E, nu out.

:func:`calibrate_session` chains :func:`tactilevision.io.read_session`,
:func:`tactilevision.contact.certify_session` and
:func:`tactilevision.mechanics.fit_indentation`. With the ``'land'`` depth
rule (default) the certified depth of a press is the depth at which the
bulging gel meets the block land, which depends on nu: certification and fit
are iterated towards a fixed point in nu.

Notes
-----
The ``'land'`` rule is ill-conditioned: a smaller nu means a smaller bulge,
larger certified depths, a smaller fitted beta and a smaller nu again
(d nu_fit / d nu is about 1.1 on the sample session), so any bias in beta is
amplified about tenfold in the fixed point. A 1.5 um mean stage overshoot
moved the fitted nu from 0.480 to 0.445 and the iteration out of the table.
The default is therefore the paper's rule, w = w0, exact when the land does
not meet the bulge first (the sample session's 'ideal' land).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ._checks import InputError
from .contact import Certification, certified_depths, certify_session
from .io import Session, read_session
from .mechanics import IndentationFit, fit_indentation

__all__ = ["SessionCalibration", "calibrate_session"]


@dataclass(frozen=True)
class SessionCalibration:
    """Result of :func:`calibrate_session`.

    Attributes
    ----------
    session : Session
    certification : Certification
    depth_rule : str
        ``'land'`` or ``'nominal'``.
    depth_mm : (N,) float64 ndarray
        Certified depth of each certified press (order of
        ``certification.presses``).
    fit : IndentationFit
    nu_rounds : list of float
        nu after each certification-fit round (``'land'`` rule).
    seconds : float
        Wall time of certification and fit.
    warnings : list of str
        Certification's warnings and the fit's.
    """

    session: Session
    certification: Certification
    depth_rule: str
    depth_mm: np.ndarray
    fit: IndentationFit
    nu_rounds: list[float]
    seconds: float
    warnings: list[str] = field(default_factory=list)

    def measurements(self) -> dict[str, np.ndarray]:
        """Columns of ``measurements.csv`` (formats.md section 2), one row per certified press.

        Returns
        -------
        columns : dict of str to (N,) ndarray
            ``press, indenter, depth_mm, force_n, force_std_n, fx_n, fy_n,
            time_s, hold_s, wait_s, x_mm, y_mm``.
        """
        ps = self.certification.presses
        col = {
            "press": [p.press for p in ps], "indenter": [p.indenter for p in ps],
            "depth_mm": list(self.depth_mm), "force_n": [p.force_n for p in ps],
            "force_std_n": [p.force_std_n for p in ps], "fx_n": [p.fx_n for p in ps],
            "fy_n": [p.fy_n for p in ps], "time_s": [p.time_s for p in ps],
            "hold_s": [p.hold_s for p in ps], "wait_s": [p.wait_s for p in ps],
            "x_mm": [p.x_mm for p in ps], "y_mm": [p.y_mm for p in ps],
        }
        return {k: np.asarray(v, np.float64 if k not in ("press", "indenter") else np.int64)
                for k, v in col.items()}


def calibrate_session(session: Session | str | Path, *, depth_rule: str = "nominal",
                      beta_table: str = "fem", nu_start: float = 0.48, max_rounds: int = 8,
                      nu_tol: float = 2e-4, progress: Callable | None = None
                      ) -> SessionCalibration:
    """Certify every press of a session and fit E and nu.

    Parameters
    ----------
    session : Session or path
        A session read by :func:`~tactilevision.io.read_session`, or its folder.
    depth_rule : {'nominal', 'land'}, default 'nominal'
        Certified depth: the paper's w = w0, or where the bulging gel meets a
        flat land (FEM, needs nu; iterated with the fit). The 'land' joint
        estimate is ill-conditioned (module notes): use it to see the size of
        the bulge effect, not for nu.
    beta_table : {'fem', 'paper'}, default 'fem'
        Passed to :func:`~tactilevision.mechanics.fit_indentation`.
    nu_start : float, default 0.48
        nu of the first certification round (``'land'``).
    max_rounds : int, default 8
    nu_tol : float, default 2e-4
        Stop when nu moves less than this between rounds.
    progress : callable, optional
        Wraps the frame iterator (e.g. ``tqdm``).

    Returns
    -------
    SessionCalibration

    Raises
    ------
    InputError
        For a broken session (see :func:`~tactilevision.io.read_session`), no
        press found, fewer than two certified presses at distinct depths, or
        a fit that fails.
    """
    t0 = time.perf_counter()
    if not isinstance(session, Session):
        session = read_session(session)
    cfg = session.config
    cert = certify_session(session, progress=progress)
    notes = list(cert.warnings)
    if len(cert.presses) < 2:
        reasons = "; ".join(f"press {r.press}: {r.reason}" for r in cert.rejected[:5])
        raise InputError(f"{session.path}: only {len(cert.presses)} of "
                         f"{len(cert.presses) + len(cert.rejected)} presses passed "
                         f"certification, too few to fit ({reasons})")
    w0 = np.array([p.w0_mm for p in cert.presses])
    force = np.array([p.force_n for p in cert.presses])
    h, a = cfg.gel_thickness_mm, cfg.indenter_radius_mm
    kw = dict(thickness_mm=h, radius_mm=a, beta_table=beta_table)

    def fit_at(depth: np.ndarray) -> IndentationFit:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            f = fit_indentation(depth, force, **kw)
        for w in caught:
            msg = str(w.message)
            if msg not in notes:
                notes.append(msg)
        return f

    rounds: list[float] = []
    if depth_rule == "nominal":
        depth = certified_depths(w0, rule="nominal", thickness_mm=h, radius_mm=a)
        fit = fit_at(depth)
    elif depth_rule == "land":
        nu = float(nu_start)
        for _ in range(max_rounds):
            depth = certified_depths(w0, rule="land", thickness_mm=h, radius_mm=a, nu=nu)
            fit = fit_at(depth)
            if fit.out_of_table or not np.isfinite(fit.nu):
                notes.append("the fit left the beta table, so the land-contact depths stay at "
                             f"nu = {nu:.4f}: {fit.out_of_table_message}")
                break
            rounds.append(float(fit.nu))
            if abs(fit.nu - nu) < nu_tol:
                break
            nu = float(np.clip(fit.nu, 0.30, 0.499))
        else:
            notes.append(f"nu did not settle in {max_rounds} certification-fit rounds "
                         f"(last {rounds[-2:]})")
    else:
        raise InputError(f"depth rule must be 'land' or 'nominal', got {depth_rule!r}")
    return SessionCalibration(session=session, certification=cert, depth_rule=depth_rule,
                              depth_mm=depth, fit=fit, nu_rounds=rounds,
                              seconds=time.perf_counter() - t0, warnings=notes)
