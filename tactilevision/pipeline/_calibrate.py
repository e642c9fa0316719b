"""The main job: a session folder in, certified presses and E, nu out.

:func:`calibrate_session` runs the steps in order: read the session
(:func:`tactilevision.io.read_session`); decode the frames, synchronise the
clocks and certify each press (:func:`tactilevision.contact.certify_session`);
take the F/T's zero off (:func:`take_off_zero`); fit the holds' relaxation
(:func:`relaxation_step`); certify each press's depth by the depth rule and fit
eq. (5) (:func:`vernier_rule`, :func:`mark_rule`, :func:`nominal_rule`,
:func:`land_rule` with a :class:`Fitter`); carry a shared depth error into the
intervals (:func:`with_shared_depth`). Each step is a function of the
previous one's results, so a user can run them one by one and look in
between. :class:`CalibrationResult` writes and reads the output folder.

The certified depth of a press (``depth_rule``):

- ``'vernier'`` (the default for a machined bevel, ``bevel_angle_deg > 0``):
  ``w = w0 + closure - b(w)``, the closure read from the band of contact on
  the bevel over the force window's frames, b the bulge of the gel's
  surface at the bevel (:func:`tactilevision.contact.bulge_at`, FEM, needs
  nu; ``bulge_correction = false`` in session.toml leaves it out).
  Certification and fit are iterated towards a fixed point in nu; with the
  bevel 2.5 h or more from the axis the bulge is a few % of w and the
  iteration is well conditioned (d nu_fit / d nu is reported).
- ``'mark'`` (the default for a bevel mark, ``bevel_angle_deg = 0``):
  w0, plus what the force says the stage went on by past it, from the frame
  period before the first frame showing the mark (where the land reached
  w0) to the force window (:func:`tactilevision.contact.mark_depths`);
  what every press shares (the clock, eq. 5's slope) widens E's and nu's
  intervals (:func:`tactilevision.contact.mark_shared_mm`).
- ``'nominal'``: the paper's rule, w = w0, with the uncertainty of the onset
  frame; for a mark, the overshoot it leaves out (read as for ``'mark'``) is a
  shared one-sided error that widens E's and nu's intervals.
- ``'land'``: the depth at which the bulging gel meets a flat land, which
  depends on nu. Ill-conditioned: a smaller nu means a smaller bulge, larger
  certified depths, a smaller fitted beta and a smaller nu again (d nu_fit /
  d nu is about 1.1 on the legacy sample session), so any bias in beta is
  amplified about tenfold in the fixed point: a diagnostic only.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from .._checks import InputError
from ..contact import CLOCK_SD_S, certify_session, readable_overshoot_mm
from ..io import Session, read_session
from ..mechanics import relaxed_moduli
from ._calibration import SessionCalibration
from ._rules import (
    DepthState,
    depth_half95,
    depth_refusals,
    land_rule,
    mark_rule,
    mark_stage_reading,
    nominal_rule,
    tolerance_note,
    vernier_rule,
)
from ._shared import with_shared_depth
from ._steps import Fitter, frame_period, relaxation_step, take_off_zero

__all__ = ["calibrate_session"]


def calibrate_session(session: Session | str | Path, *, depth_rule: str = "auto",
                      beta_table: str = "fem", nu_start: float = 0.48, max_rounds: int = 8,
                      nu_tol: float = 2e-4, progress: Callable | None = None,
                      allow_failure: bool = False, relaxation: str = "auto",
                      bevel_threshold: float | str = "auto", ft_zero: str = "auto"
                      ) -> SessionCalibration:
    """Certify every press of a session and fit E and nu.

    Parameters
    ----------
    session : Session or path
        A session read by :func:`~tactilevision.io.read_session`, or its folder.
    depth_rule : {'auto', 'vernier', 'mark', 'nominal', 'land'}, default 'auto'
        Certified depth (module docstring). ``'auto'``: ``'vernier'`` for a
        machined bevel (``bevel_angle_deg > 0``), ``'mark'`` for a mark.
    beta_table : {'fem', 'paper'}, default 'fem'
        Passed to :func:`~tactilevision.mechanics.fit_indentation`.
    nu_start : float, default 0.48
        nu of the first round of the bulge correction (``'vernier'``) or of
        the land contact (``'land'``).
    max_rounds : int, default 8
    nu_tol : float, default 2e-4
        Stop when nu moves less than this between rounds.
    progress : callable, optional
        Wraps the frame iterator (e.g. ``tqdm``).
    allow_failure : bool, default False
        With fewer than two certified presses at distinct depths, return the
        certification with ``fit = None`` and ``failure`` saying why (so that
        a report can still be written) instead of raising.
    relaxation : {'auto', 'off'}, default 'auto'
        'auto': fit a standard linear solid to the force over each press's
        hold (:func:`~tactilevision.mechanics.fit_relaxation`); when the gel
        is seen to relax, filter the F/T log back to the elastic force behind
        it (:func:`~tactilevision.mechanics.elastic_force`), certify again
        with the clock synchronised on that, and fit its window means (the
        forces at the instant of loading, ``force0_n``, free of each press's
        memory of the one before), so that E is the instantaneous modulus
        E_0; the relaxed E_inf = (1 - g) E_0 is reported beside it
        (``relaxation`` and ``moduli``). ``measurements.csv`` keeps the
        measured ``force_n`` and adds ``force0_n``, which ``fit --holds``
        uses. 'off': none of it.
    bevel_threshold : float or 'auto', default 'auto'
        For a bevel mark (``bevel_angle_deg = 0``): when the mark is seen
        (:func:`~tactilevision.contact.certify_session`). ``'auto'``: from
        the session's own no-contact frames' scores. A number: the fixed
        rule, two consecutive frames above it or one above twice it.
    ft_zero : {'auto', 'constant', 'drift', 'off'}, default 'auto'
        The F/T's zero, read from the log between the presses once each
        release has settled (:func:`~tactilevision.contact.force_zero`):
        'constant' takes its mean off every sample of fz (a sensor tared
        before the gauge block was mounted reads the block's weight
        throughout); a zero that drifts is then reported, and its drift at
        each press listed (``ft_drift_n``) for ``diagnose``; 'drift' takes
        off the zero's line at each sample's time; 'auto' does 'drift' when
        the zero is seen to drift (``ForceZero.drifts``), else 'constant'
        (a drift of -0.1 N over the sample session left in the forces read
        E 25 % high: ``benchmarks/bench_ft_zero.py``); 'off' keeps the
        forces as the F/T read them (the zero is still reported).

    Returns
    -------
    SessionCalibration

    Raises
    ------
    InputError
        For a broken session (see :func:`~tactilevision.io.read_session`), a
        ball's session (:func:`calibrate_ball_session`), no press found, a fit
        that fails, or (unless `allow_failure`) fewer than two certified
        presses at distinct depths; for ``'vernier'`` on a
        session whose bevel has no vernier.
    """
    t0 = time.perf_counter()
    _check_options(bevel_threshold, relaxation, ft_zero)
    if not isinstance(session, Session):
        session = read_session(session)
    cfg = session.config
    if cfg.indenter_shape != "flat_punch":
        raise InputError(f"{session.path / 'session.toml'}: [indenter] shape = "
                         f"{cfg.indenter_shape!r}: calibrate_session certifies a gauge block's "
                         "flat punches; a ball's session is calibrate_ball_session's")
    depth_rule = _resolve_rule(depth_rule, cfg, session.path)
    cert = certify_session(session, progress=progress, bevel_threshold=bevel_threshold)
    session, cert, zero, zero_notes = take_off_zero(session, cert, ft_zero)
    relax, relax_notes, force0 = None, [], None
    if relaxation == "auto" and cert.presses:
        cert, relax, relax_notes, force0 = relaxation_step(session, cert, progress,
                                                           bevel_threshold)
    base_notes = (list(session.notes) + list(cert.warnings) + zero_notes  # the reader's first
                  + relax_notes)
    rounds = dict(nu_start=float(nu_start), max_rounds=max_rounds, nu_tol=nu_tol)
    check_notes: list[str] = []
    while True:
        # a press refused once its depth is read (past the gauge's reach, or two readings
        # that disagree) leaves the rule's inputs too: the rule is read again without it
        # (each round refuses one press or more, or ends)
        notes = list(base_notes)
        common = dict(session=session, certification=cert, depth_rule=depth_rule,
                      warnings=notes, ft_zero=zero)
        too_few = _too_few(session, cert)
        if too_few is not None:
            notes.extend(check_notes)
            if not allow_failure:
                raise InputError(too_few)
            z = np.array([p.w0_mm for p in cert.presses], np.float64)
            return SessionCalibration(depth_mm=z, fit=None, nu_rounds=[],
                                      seconds=time.perf_counter() - t0,
                                      depth_std_mm=np.zeros_like(z), bulge_mm=np.zeros_like(z),
                                      failure=too_few, **common)
        presses = cert.presses
        try:
            st, std_indenter, fit_at, force = _read_depths(session, cert, force0, depth_rule,
                                                           beta_table, rounds, notes)
        except _RuleFailed as failed:
            notes.extend(check_notes)
            if not allow_failure:
                raise failed.exc from None
            st = failed.state
            return SessionCalibration(depth_mm=failed.depth, fit=None, nu_rounds=st.rounds,
                                      seconds=time.perf_counter() - t0, depth_std_mm=st.std,
                                      bulge_mm=st.bulge, bevel_force_n=st.bevel_n,
                                      failure=f"{session.path}: the fit failed: {failed.exc}",
                                      **common)
        refused, round_notes = _refusals(presses, st, std_indenter, depth_rule, session, cert)
        if not refused:
            check_notes.extend(round_notes)
            break
        check_notes.extend(n for n in round_notes if "refused" in n)
        cert, force0 = _without(cert, refused, force0)
    notes.extend(check_notes)
    half95 = depth_half95(*_own_depth_sd(presses, st, std_indenter, depth_rule))
    tol = tolerance_note(presses, half95, cfg.depth_tolerance_mm, readable_overshoot_mm=(
        readable_overshoot_mm(cfg.bevel_angle_deg, cfg.mm_per_px)))
    if tol is not None:
        notes.append(tol)
    fit = st.fit
    for msg in fit_at.warnings_of(fit):      # the warnings of the fit reported
        if msg not in notes:
            notes.append(msg)
    if st.shared is not None:
        fit = with_shared_depth(fit, fit_at, st.depth, st.std, force - st.bevel_n, *st.shared)
    moduli = None
    if relax is not None and relax.resolved and np.isfinite(fit.E_mpa):
        moduli = relaxed_moduli(fit.E_mpa, fit.E_ci95_mpa, relax,
                                np.array([p.hold_s for p in presses]),
                                np.array([p.press for p in presses]))
    return SessionCalibration(depth_mm=st.depth, fit=fit, nu_rounds=st.rounds,
                              seconds=time.perf_counter() - t0, depth_std_mm=st.std,
                              bulge_mm=st.bulge, bevel_force_n=st.bevel_n, relaxation=relax,
                              moduli=moduli,
                              force0_n=force0 if force0 is not None else np.zeros(0),
                              force_fit_n=force - st.bevel_n,
                              depth_indenter_std_mm=std_indenter, depth_half95_mm=half95,
                              **common)


class _RuleFailed(Exception):
    """A depth rule's fit failed: the InputError, the state it got to, the depths to write."""

    def __init__(self, exc: InputError, state: DepthState, depth: np.ndarray) -> None:
        super().__init__(str(exc))
        self.exc, self.state, self.depth = exc, state, depth


def _read_depths(session: Session, cert, force0: np.ndarray | None, depth_rule: str,
                 beta_table: str, rounds: dict, notes: list[str]):
    """The depth rule run on the certified presses: ``(state, std_indenter, fitter,
    force)``; its notes appended to `notes`. Raises :class:`_RuleFailed` where its fit
    fails."""
    cfg = session.config
    presses = cert.presses
    w0 = np.array([p.w0_mm for p in presses])
    force = force0 if force0 is not None else np.array([p.force_n for p in presses])
    closure = np.array([p.closure_mm for p in presses])
    fit_at = Fitter(force, thickness_mm=cfg.gel_thickness_mm, radius_mm=cfg.indenter_radius_mm,
                    beta_table=beta_table, press=np.array([p.press for p in presses]))
    st = DepthState(depth=w0 + closure, std=np.array([p.closure_std_mm for p in presses]),
                    bulge=np.zeros_like(w0), bevel_n=np.zeros_like(w0), notes=notes)
    std_indenter = np.zeros(0)
    try:
        if depth_rule == "vernier":
            vernier_rule(st, presses, cert, cfg, fit_at, force, **rounds)
        elif depth_rule == "mark":
            clock_sd = float(np.nan_to_num(max(CLOCK_SD_S, cert.clock_offset_se_s)))
            st.depth, st.std, st.fit, st.shared, mark_notes, std_indenter = mark_rule(
                presses, force, fit_at, cfg, frame_period(session), clock_sd)
            notes.extend(mark_notes)
        elif depth_rule == "nominal":
            nominal_rule(st, presses, cfg, fit_at, force, frame_period(session))
        else:
            land_rule(st, presses, cfg, fit_at, **rounds)
    except InputError as exc:
        raise _RuleFailed(exc, st, w0 + closure) from exc
    return st, std_indenter, fit_at, force


def _refusals(presses, st: DepthState, std_indenter: np.ndarray, depth_rule: str,
              session: Session, cert) -> tuple[list, list[str]]:
    """The presses refused once their depths are read (:func:`depth_refusals`: past the
    gauge's reach, under any rule; the mark rule's depths also against the stage's
    reading), and the notes."""
    if depth_rule not in ("mark", "vernier"):
        return [], []
    std, half = _own_depth_sd(presses, st, std_indenter, depth_rule)
    stage = mark_stage_reading(presses, session, cert) if depth_rule == "mark" else None
    refused, notes = depth_refusals(presses, np.asarray(st.depth, np.float64), std,
                                    session.config, shared_half=half, stage=stage)
    return refused, notes


def _own_depth_sd(presses, st: DepthState, std_indenter: np.ndarray, depth_rule: str
                  ) -> tuple[np.ndarray, np.ndarray | None]:
    """Each press's own depth sd, mm (under the mark rule the indenter's shared part
    counted once, not n times over as the fit weighs it), and the half-width of the error
    every press shares (the mark's clock and dP/dw, the vernier's band edges; None where
    there is none). Until issue 83's second fresh draw the vernier's edge bound was left
    out here: its depths' 95 % half-widths stated 2.4 to 4.0 um on the sample session
    where its +-2.6 um edge bound makes them 3.8 to 4.9, and a 9 deg design read its
    certified depths +4.8 um off against a mean's stated sd of 1.0
    (`python benchmarks/report.py --subjects vernier_sweep_fresh2`)."""
    std = np.asarray(st.std, np.float64)
    half = None if st.shared is None else np.asarray(st.shared[1], np.float64)
    if depth_rule != "mark":
        return std, half if depth_rule == "vernier" else None
    ind = np.array([p.indenter for p in presses])
    n = np.array([np.sum(ind == g) for g in ind], np.float64)
    shared = np.asarray(std_indenter, np.float64) if len(std_indenter) else np.zeros_like(std)
    std = np.sqrt(np.maximum(std ** 2 - shared ** 2 * (1 - 1 / n), 0.0))
    return std, half


def _without(cert, refused: list, force0: np.ndarray | None):
    """The certification with the `refused` presses moved to its rejections (and the
    relaxation's force0 of the others)."""
    gone = {r.press for r in refused}
    keep = np.array([p.press not in gone for p in cert.presses], bool)
    presses = [p for p, k in zip(cert.presses, keep, strict=True) if k]
    rejected = sorted([*cert.rejected, *refused], key=lambda r: r.press)
    if force0 is not None:
        force0 = np.asarray(force0)[keep]
    return replace(cert, presses=presses, rejected=rejected), force0


def _check_options(bevel_threshold, relaxation: str, ft_zero: str) -> None:
    """Refuse an option of :func:`calibrate_session` it does not know, naming it."""
    if bevel_threshold != "auto" and (isinstance(bevel_threshold, bool) or not (
            isinstance(bevel_threshold, int | float) and math.isfinite(bevel_threshold)
            and bevel_threshold > 0)):
        raise InputError(f"bevel_threshold must be a positive number or 'auto', got "
                         f"{bevel_threshold!r}")
    if relaxation not in ("auto", "off"):
        raise InputError(f"relaxation must be 'auto' or 'off', got {relaxation!r}")
    if ft_zero not in ("auto", "constant", "drift", "off"):
        raise InputError(f"ft_zero must be 'auto', 'constant', 'drift' or 'off', got "
                         f"{ft_zero!r}")


def _resolve_rule(depth_rule: str, cfg, path) -> str:
    """The depth rule ('auto' resolved by the bevel), refused where the bevel has no use
    for it."""
    if depth_rule == "auto":
        depth_rule = "vernier" if cfg.bevel_angle_deg > 0 else "mark"
    if depth_rule not in ("vernier", "mark", "nominal", "land"):
        raise InputError(f"depth rule must be 'auto', 'vernier', 'mark', 'nominal' or 'land', "
                         f"got {depth_rule!r}")
    if depth_rule == "mark" and cfg.bevel_angle_deg > 0:
        raise InputError(f"{path}: the 'mark' depth rule is for a bevel mark "
                         "([gauge_block] bevel_angle_deg = 0); a machined bevel is read by "
                         "'vernier'")
    if depth_rule == "vernier" and cfg.bevel_angle_deg <= 0:
        raise InputError(f"{path}: the 'vernier' depth rule needs a machined bevel "
                         "([gauge_block] bevel_angle_deg > 0)")
    return depth_rule


def _too_few(session: Session, cert) -> str | None:
    """Why the certified presses cannot be fitted (fewer than two, or one depth), or None."""
    presses = cert.presses
    n_depths = np.unique([p.w0_mm for p in presses]).size
    if len(presses) >= 2 and n_depths >= 2:
        return None
    reasons = "; ".join(f"press {r.press}: {r.reason}" for r in cert.rejected[:5])
    return (f"{session.path}: only {len(presses)} of {len(presses) + len(cert.rejected)} "
            f"presses passed certification ({n_depths} distinct depths), too few to fit"
            + (f" ({reasons})" if reasons else ""))
