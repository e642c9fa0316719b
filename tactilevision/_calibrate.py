"""The main job: a session folder in, certified presses and E, nu out.

:func:`calibrate_session` chains :func:`tactilevision.io.read_session`,
:func:`tactilevision.contact.certify_session` and
:func:`tactilevision.mechanics.fit_indentation`.

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
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ._checks import InputError
from .contact import (
    EDGE_SHARED_FRACTION,
    RESOLVED_PX,
    BevelGeometry,
    Certification,
    CertifiedPress,
    ForceZero,
    approach_start,
    bevel_force,
    bulge_at,
    certified_depths,
    certify_session,
    crossing_forces,
    force_window,
    force_zero,
    hold_end,
    mark_depths,
    mark_shared_mm,
    unresolved_closure,
    vernier_shared_mm,
)
from .io import Session, read_session
from .mechanics import (
    IndentationFit,
    RelaxationFit,
    elastic_force,
    fit_indentation,
    fit_relaxation,
    refine_relaxation,
    relaxed_moduli,
)

__all__ = ["SessionCalibration", "calibrate_session"]


@dataclass(frozen=True)
class SessionCalibration:
    """Result of :func:`calibrate_session`.

    Attributes
    ----------
    session : Session
    certification : Certification
    depth_rule : str
        ``'vernier'``, ``'nominal'`` or ``'land'``.
    depth_mm : (N,) float64 ndarray
        Certified depth of each certified press (order of
        ``certification.presses``), mm.
    depth_std_mm : (N,) float64 ndarray
        Its standard uncertainty, mm (the vernier reading's, or the onset
        frame's for ``'nominal'``; 0 for ``'land'``).
    bulge_mm : (N,) float64 ndarray
        The bulge subtracted from each vernier depth, mm (0 otherwise).
    bevel_force_n : (N,) float64 ndarray
        The force of the bevel's band taken off each press's F/T force, N (0
        otherwise): ``force_n`` of the measurements is the indenter's alone.
    fit : IndentationFit
    nu_rounds : list of float
        nu after each certification-fit round (``'vernier'`` with the bulge
        correction, ``'land'``).
    seconds : float
        Wall time of certification and fit.
    warnings : list of str
        Certification's warnings and the fit's.
    failure : str or None
        Why nothing was fitted (too few certified presses), else None; then
        ``fit`` is None and the certification is still there to report.
    relaxation : RelaxationFit or None
        The standard linear solid fitted to the holds (None when not tested).
        When it is ``resolved``, ``fit`` is on the forces taken back to the
        instant of loading: its E is E_0.
    moduli : dict or None
        ``E0_mpa``, ``E_inf_mpa`` and their intervals
        (:func:`~tactilevision.mechanics.relaxed_moduli`) for a relaxing gel.
    force0_n : (N,) float64 ndarray
        For a relaxing gel, each press's force at the instant of loading, N:
        the F/T window's mean of the elastic force behind the log
        (:func:`~tactilevision.mechanics.elastic_force`), the bevel's band
        not yet taken off; empty otherwise. The fit uses it.
    force_fit_n : (N,) float64 ndarray
        The force of each certified press exactly as the fit used it, N: the
        F/T window's mean (``force0_n`` for a relaxing gel), the F/T's zero
        and the bevel's band taken off; the figures and the report show
        these (empty when nothing was fitted).
    ft_zero : ForceZero or None
        The F/T's zero read between the presses (:func:`~tactilevision.contact.
        force_zero`) and what was taken off the forces (``ft_zero.subtracted``);
        None when no settled rest was found. ``session`` then holds the log
        with it taken off.
    """

    session: Session
    certification: Certification
    depth_rule: str
    depth_mm: np.ndarray
    fit: IndentationFit | None
    nu_rounds: list[float]
    seconds: float
    warnings: list[str] = field(default_factory=list)
    depth_std_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    bulge_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    bevel_force_n: np.ndarray = field(default_factory=lambda: np.zeros(0))
    failure: str | None = None
    relaxation: RelaxationFit | None = None
    moduli: dict | None = None
    force0_n: np.ndarray = field(default_factory=lambda: np.zeros(0))
    force_fit_n: np.ndarray = field(default_factory=lambda: np.zeros(0))
    ft_zero: ForceZero | None = None

    def _window_times(self) -> np.ndarray:
        """The middle of each certified press's force window, F/T clock, s."""
        off = self.certification.clock_offset_s
        return np.array([p.t_frame_s + off + p.hold_s for p in self.certification.presses])

    def _bevel(self) -> np.ndarray:
        n = len(self.certification.presses)
        return self.bevel_force_n if len(self.bevel_force_n) == n else np.zeros(n)

    def holds(self, max_points: int = 1000) -> dict[str, np.ndarray]:
        """Each certified press's force over its hold: the columns of ``holds.csv``.

        The hold runs from the press's arrival at depth (the end of the force's
        rise, :func:`~tactilevision.contact.hold_start`, which also starts the
        force window) to the start of its release
        (:func:`~tactilevision.contact.hold_end`). A press whose release is not
        found in the log is left out.

        Parameters
        ----------
        max_points : int, default 1000
            Samples per press at most: longer holds are averaged in blocks.

        Returns
        -------
        columns : dict of str to (K,) ndarray
            ``press`` (int64), ``t_s`` (time since the hold's start, s, at the
            block's centre), ``fz_n`` (the F/T log's fz, N, with the
            bevel's own force not taken off) and ``ramp_s`` (the press's
            loading time, from the force's rise
            (:func:`~tactilevision.contact.approach_start`) to the hold's
            start, s, the same on each of its rows; NaN when not found).
        """
        return _hold_curves(self.session, self.certification, max_points)

    def measurements(self) -> dict[str, np.ndarray]:
        """Columns of ``measurements.csv`` (formats.md section 2), one row per certified press.

        Returns
        -------
        columns : dict of str to (N,) ndarray
            ``press, indenter, depth_mm, depth_std_mm, overshoot_mm, force_n,
            bevel_force_n, force_std_n, force_sem_n, fx_n, fy_n, time_s, hold_s, wait_s, x_mm,
            y_mm`` (``overshoot_mm``: certified depth minus the indenter's w0;
            ``force_n``: the F/T window's mean less ``bevel_force_n``, the
            bevel's own band, and less ``ft_zero_n``, the F/T's zero read
            between the presses); for a relaxing gel also ``force0_n``, the
            force at the instant of loading, less the bevel's; with a zero
            that drifts and was taken off as a constant, ``ft_drift_n``: the
            zero at the press less that constant, N (the drift left in
            ``force_n``).
        """
        ps = self.certification.presses
        col = {
            "press": [p.press for p in ps], "indenter": [p.indenter for p in ps],
            "depth_mm": list(self.depth_mm),
            "depth_std_mm": list(self.depth_std_mm) if len(self.depth_std_mm) == len(ps)
            else [float("nan")] * len(ps),
            "overshoot_mm": [d - p.w0_mm for d, p in zip(self.depth_mm, ps, strict=True)],
            "force_n": [p.force_n - b for p, b in zip(ps, self._bevel(), strict=True)],
            "bevel_force_n": list(self._bevel()),
            "force_std_n": [p.force_std_n for p in ps],
            "force_sem_n": [p.force_sem_n for p in ps], "fx_n": [p.fx_n for p in ps],
            "fy_n": [p.fy_n for p in ps], "time_s": [p.time_s for p in ps],
            "hold_s": [p.hold_s for p in ps], "wait_s": [p.wait_s for p in ps],
            "x_mm": [p.x_mm for p in ps], "y_mm": [p.y_mm for p in ps],
        }
        if len(self.force0_n) == len(ps):
            col["force0_n"] = list(self.force0_n - self._bevel())
        z = self.ft_zero
        if z is not None:
            t = self._window_times()
            col["ft_zero_n"] = list(z.taken_off(t))
            if z.drifts and z.subtracted == "constant":
                col["ft_drift_n"] = list(z.at(t) - z.zero_n)
        return {k: np.asarray(v, np.float64 if k not in ("press", "indenter") else np.int64)
                for k, v in col.items()}


def _hold_spans(session: Session, certification: Certification
                ) -> list[tuple[CertifiedPress, float, float]]:
    """Each certified press's hold on the F/T clock, (press, start, end), s: from its
    arrival at depth to the start of its release (presses whose release is not found left
    out)."""
    t, fz = np.asarray(session.force_times_s, np.float64), np.asarray(session.forces_n[:, 2])
    off = certification.clock_offset_s
    spans = []
    for p in certification.presses:
        t0 = p.t_frame_s + off
        t1 = hold_end(t, fz, t0)
        if t1 is not None:
            spans.append((p, t0, t1))
    return spans


def _hold_curves(session: Session, certification: Certification, max_points: int = 1000
                 ) -> dict[str, np.ndarray]:
    """The columns of ``holds.csv`` (:meth:`SessionCalibration.holds`)."""
    t, fz = np.asarray(session.force_times_s, np.float64), np.asarray(session.forces_n[:, 2])
    press, ts, fs, ramps = [], [], [], []
    for p, t0, t1 in _hold_spans(session, certification):
        ta = approach_start(t, fz, t0)
        ramp = np.nan if ta is None else t0 - ta
        sel = np.flatnonzero((t >= t0) & (t <= t1))
        k = max(1, -(-sel.size // max_points))
        m = sel.size // k
        if m == 0:
            continue
        blocks = sel[: m * k].reshape(m, k)
        ts.append(t[blocks].mean(axis=1) - t0)
        fs.append(fz[blocks].mean(axis=1))
        press.append(np.full(m, p.press))
        ramps.append(np.full(m, ramp))
    if not press:
        return {"press": np.zeros(0, np.int64), "t_s": np.zeros(0), "fz_n": np.zeros(0),
                "ramp_s": np.zeros(0)}
    return {"press": np.concatenate(press).astype(np.int64), "t_s": np.concatenate(ts),
            "fz_n": np.concatenate(fs), "ramp_s": np.concatenate(ramps)}


def _relaxation(session: Session, cert: Certification, progress: Callable | None,
                bevel_threshold: float | str = "auto"
                ) -> tuple[Certification, RelaxationFit | None, list[str], np.ndarray | None]:
    """Fit the holds; for a relaxing gel, certify again with the clock on the elastic force.

    Returns the certification, the fit (None when not tested), notes, and each certified
    press's force at the instant of loading (the F/T window's mean of the elastic force
    behind the log; None unless the gel relaxes)."""
    def fit(c: Certification, holds: dict[str, np.ndarray]) -> RelaxationFit:
        # with each press's time and indenter: softening, which does not recover between
        # presses, is told from relaxation, which does
        return fit_relaxation(holds["press"], holds["t_s"], holds["fz_n"], holds["ramp_s"],
                              press_time_s={p.press: p.time_s for p in c.presses},
                              press_group={p.press: p.indenter for p in c.presses})

    holds = _hold_curves(session, cert)
    if np.unique(holds["press"]).size < 3:
        return cert, None, ["relaxation: fewer than 3 holds found in the F/T log, not tested"], None
    try:
        relax = fit(cert, holds)
    except InputError as exc:
        return cert, None, [f"relaxation: not tested ({exc})"], None
    if not relax.resolved:
        return cert, relax, ([] if relax.verdict == "flat" else
                             [f"relaxation {relax.verdict}: {relax.why}"]), None

    def refined(c: Certification, r: RelaxationFit) -> RelaxationFit:
        # each hold remembers the presses before it: g and tau from the whole log
        spans = np.array([(t0, t1) for _, t0, t1 in _hold_spans(session, c)]).reshape(-1, 2)
        try:
            return refine_relaxation(session.force_times_s, session.forces_n[:, 2], spans, r)
        except InputError:
            return r

    relax = refined(cert, relax)
    elastic = elastic_force(session.force_times_s, session.forces_n, relax.g, relax.tau_s)
    again = certify_session(session, progress=progress, sync_fz_n=elastic[:, 2],
                            contact_area_px=cert.contact_area_px, bevel_threshold=bevel_threshold)
    # the holds are fitted again only if they moved: on the vernier's path a hold starts
    # where the force stops rising, whatever the clock; on a frame-timed one it follows it
    def starts(c: Certification) -> list[tuple[int, float]]:
        return [(p.press, round(p.t_frame_s + c.clock_offset_s, 3)) for p in c.presses]

    if starts(again) != starts(cert):
        holds = _hold_curves(session, again)
        if np.unique(holds["press"]).size >= 3:
            again_relax = fit(again, holds)
            if again_relax.resolved:
                relax = refined(again, again_relax)
    off, n = again.clock_offset_s, session.config.window_samples
    force0 = np.array([force_window(session.force_times_s, elastic, p.t_frame_s + off + p.hold_s,
                                    n).fz_n for p in again.presses])
    note = (f"the gel relaxes while held (g = {relax.g:.3f}, tau = {relax.tau_s:.3g} s from "
            f"{relax.n_presses} holds; {relax.why}): the clock was synchronised on the "
            f"elastic force behind the F/T log ({cert.clock_offset_s:.4f} s on the measured force, "
            f"{again.clock_offset_s:.4f} s on the elastic one), and the fit takes each "
            "press's force from it (force0_n, the force at the instant of loading): E is "
            "E_0, the instantaneous modulus")
    return again, relax, [note], force0


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
        For a broken session (see :func:`~tactilevision.io.read_session`), no
        press found, a fit that fails, or (unless `allow_failure`) fewer than
        two certified presses at distinct depths; for ``'vernier'`` on a
        session whose bevel has no vernier.
    """
    t0 = time.perf_counter()
    if bevel_threshold != "auto" and (isinstance(bevel_threshold, bool) or not (
            isinstance(bevel_threshold, int | float) and math.isfinite(bevel_threshold)
            and bevel_threshold > 0)):
        raise InputError(f"bevel_threshold must be a positive number or 'auto', got "
                         f"{bevel_threshold!r}")
    if not isinstance(session, Session):
        session = read_session(session)
    cfg = session.config
    if relaxation not in ("auto", "off"):
        raise InputError(f"relaxation must be 'auto' or 'off', got {relaxation!r}")
    if ft_zero not in ("auto", "constant", "drift", "off"):
        raise InputError(f"ft_zero must be 'auto', 'constant', 'drift' or 'off', got "
                         f"{ft_zero!r}")
    cert = certify_session(session, progress=progress, bevel_threshold=bevel_threshold)
    session, cert, zero, zero_notes = _take_off_zero(session, cert, ft_zero)
    relax, relax_notes, force0 = None, [], None
    if relaxation == "auto" and cert.presses:
        cert, relax, relax_notes, force0 = _relaxation(session, cert, progress, bevel_threshold)
    notes = (list(session.notes) + list(cert.warnings) + zero_notes  # the reader's notes first
             + relax_notes)
    if depth_rule == "auto":
        depth_rule = "vernier" if cfg.bevel_angle_deg > 0 else "mark"
    if depth_rule not in ("vernier", "mark", "nominal", "land"):
        raise InputError(f"depth rule must be 'auto', 'vernier', 'mark', 'nominal' or 'land', "
                         f"got {depth_rule!r}")
    if depth_rule == "mark" and cfg.bevel_angle_deg > 0:
        raise InputError(f"{session.path}: the 'mark' depth rule is for a bevel mark "
                         "([gauge_block] bevel_angle_deg = 0); a machined bevel is read by "
                         "'vernier'")
    if depth_rule == "vernier" and cfg.bevel_angle_deg <= 0:
        raise InputError(f"{session.path}: the 'vernier' depth rule needs a machined bevel "
                         "([gauge_block] bevel_angle_deg > 0)")
    presses = cert.presses
    n_depths = np.unique([p.w0_mm for p in presses]).size
    if len(presses) < 2 or n_depths < 2:
        reasons = "; ".join(f"press {r.press}: {r.reason}" for r in cert.rejected[:5])
        msg = (f"{session.path}: only {len(presses)} of {len(presses) + len(cert.rejected)} "
               f"presses passed certification ({n_depths} distinct depths), too few to fit"
               + (f" ({reasons})" if reasons else ""))
        if not allow_failure:
            raise InputError(msg)
        z = np.array([p.w0_mm for p in presses], np.float64)
        return SessionCalibration(session=session, certification=cert, depth_rule=depth_rule,
                                  depth_mm=z, fit=None, nu_rounds=[],
                                  seconds=time.perf_counter() - t0, warnings=notes,
                                  depth_std_mm=np.zeros_like(z), bulge_mm=np.zeros_like(z),
                                  failure=msg, ft_zero=zero)
    w0 = np.array([p.w0_mm for p in presses])
    force = np.array([p.force_n for p in presses])
    if force0 is not None:
        force = force0
    closure = np.array([p.closure_mm for p in presses])
    closure_std = np.array([p.closure_std_mm for p in presses])
    h, a = cfg.gel_thickness_mm, cfg.indenter_radius_mm
    kw = dict(thickness_mm=h, radius_mm=a, beta_table=beta_table)

    caught_by_fit: dict[int, list[str]] = {}

    def fit_at(depth: np.ndarray, std: np.ndarray | None,
               f_n: np.ndarray | None = None) -> IndentationFit:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            f = fit_indentation(depth, force if f_n is None else f_n, depth_std_mm=std, **kw)
        caught_by_fit[id(f)] = [str(w.message) for w in caught]
        return f

    rounds: list[float] = []
    shared: tuple[np.ndarray, np.ndarray] | None = None   # shared depth error, (low, high)
    bulge = np.zeros_like(w0)
    bevel_n = np.zeros_like(w0)
    std = closure_std.copy()
    try:
        if depth_rule == "vernier":
            if any(p.rule != "vernier" for p in presses):
                raise InputError("the 'vernier' depth rule needs every press read by the vernier")
            geom = BevelGeometry(offset_mm=cfg.bevel_offset_mm,
                                 direction_deg=cfg.bevel_direction_deg,
                                 angle_deg=cfg.bevel_angle_deg, length_mm=cfg.bevel_length_mm)
            depth = w0 + closure
            if cfg.bulge_correction:
                depth, bulge = _vernier_depths(w0, closure, cfg, float(nu_start))
            fit = fit_at(depth, std)
            nu, E = float(nu_start), None
            if np.isfinite(fit.E_mpa) and np.isfinite(fit.nu):
                nu, E = float(np.clip(fit.nu, 0.30, 0.499)), float(fit.E_mpa)
            corrections = cfg.bulge_correction or cfg.bevel_force_correction
            for _ in range(max_rounds if corrections else 0):
                if cfg.bulge_correction:
                    depth, bulge = _vernier_depths(w0, closure, cfg, nu)
                if cfg.bevel_force_correction and E is not None:
                    bevel_n = bevel_force(closure, geom, thickness_mm=h, E_mpa=E, nu=nu)
                fit = fit_at(depth, std, force - bevel_n)
                if fit.out_of_table or not np.isfinite(fit.nu):
                    notes.append("the fit left the beta table, so the corrections stay at "
                                 f"nu = {nu:.4f}: {fit.out_of_table_message}")
                    break
                rounds.append(float(fit.nu))
                settled = abs(fit.nu - nu) < nu_tol and (
                    E is not None and abs(fit.E_mpa / E - 1) < 1e-3)
                nu, E = float(np.clip(fit.nu, 0.30, 0.499)), float(fit.E_mpa)
                if settled:
                    break
            else:
                if corrections:
                    notes.append(f"nu did not settle in {max_rounds} rounds of the corrections "
                                 f"(last {rounds[-2:]})")
            edge = (cert.bevel_optics or {}).get("edge_px")
            half = (vernier_shared_mm([p.band_resolved for p in presses], geom, cfg.mm_per_px,
                                      edge) if edge else np.zeros_like(w0))
            if np.any(half > 0):
                shared = (-half, half)
                n_read = int(np.sum(half > 0))
                notes.append(f"the band's edges sit within +-{EDGE_SHARED_FRACTION:g} of the "
                             f"session's edge width ({edge:.2f} px) of the true edges of "
                             f"contact, the same way for every press: +-"
                             f"{1e3 * float(half.max()):.2f} um shared by the {n_read} read "
                             "bands, carried into E's and nu's intervals")
            unread = sum(not p.band_resolved for p in presses)
            if unread:
                top = 2e3 * unresolved_closure(geom, cfg.mm_per_px)[0]
                notes.append(f"{unread} of {len(presses)} bands not read (shorter than "
                             f"{RESOLVED_PX:g} px without the session's flank colours, or their "
                             "crest away from the long bands'): their overshoot is only "
                             f"bounded, 0 to {top:.1f} um or to their reading if longer, with "
                             "the sd of a uniform over that (the point: the band read with "
                             "edge lines and shadows, clipped to it); the fit weighs them "
                             "accordingly")
            if cfg.bulge_correction:
                notes.append(_bulge_note(bulge, depth, cfg, rounds, w0, closure, fit_at, std,
                                         force - bevel_n))
            else:
                notes.append("no bulge correction ([gauge_block] bulge_correction = false): the "
                             "certified depth is w0 plus the vernier's reading")
            if cfg.bevel_force_correction:
                frac = bevel_n / np.maximum(force, 1e-12)
                notes.append(f"the bevel's own band of contact pressed "
                             f"{1e3 * bevel_n.min():.1f} to {1e3 * bevel_n.max():.1f} mN "
                             f"({100 * frac.max():.1f}% of the F/T force at most; layer model at "
                             "the fitted E, nu), taken off the forces")
        elif depth_rule == "mark":
            depth, std, fit, shared, mark_notes = _mark_rule(presses, force, fit_at, cfg,
                                                             _period(session))
            notes.extend(mark_notes)
        elif depth_rule == "nominal":
            depth = certified_depths(w0, rule="nominal", thickness_mm=h, radius_mm=a)
            if all(p.rule == "vernier" for p in presses):
                std = np.zeros_like(w0)
                notes.append("depth rule 'nominal' on a vernier session: the overshoot the bevel "
                             "reads is ignored")
            fit = fit_at(depth, std if np.any(std > 0) else None)
            if all(p.rule == "onset" for p in presses):
                # what w = w0 leaves out: the onset's half frame and the force's overshoot
                marked, *_ = _mark_rule(presses, force, fit_at, cfg, _period(session))
                left = marked - depth
                shared = (np.zeros_like(left), np.maximum(left, 0.0))
                notes.append(f"depth rule 'nominal' on a mark: w = w0 leaves out the depth past "
                             f"w0 that the force reads ({1e3 * float(np.median(left)):.1f} um "
                             "median), one-sided and shared by every press: E's and nu's "
                             "intervals carry it")
        else:
            std = np.zeros_like(w0)
            nu = float(nu_start)
            for _ in range(max_rounds):
                depth = certified_depths(w0, rule="land", thickness_mm=h, radius_mm=a, nu=nu)
                fit = fit_at(depth, None)
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
    except InputError as exc:
        if not allow_failure:
            raise
        msg = f"{session.path}: the fit failed: {exc}"
        return SessionCalibration(session=session, certification=cert, depth_rule=depth_rule,
                                  depth_mm=w0 + closure, fit=None, nu_rounds=rounds,
                                  seconds=time.perf_counter() - t0, warnings=notes,
                                  depth_std_mm=std, bulge_mm=bulge, bevel_force_n=bevel_n,
                                  failure=msg, ft_zero=zero)
    for msg in caught_by_fit.get(id(fit), []):      # the warnings of the fit reported
        if msg not in notes:
            notes.append(msg)
    if shared is not None:
        fit = _with_shared_depth(fit, fit_at, depth, std, force - bevel_n, *shared)
    moduli = None
    if relax is not None and relax.resolved and np.isfinite(fit.E_mpa):
        moduli = relaxed_moduli(fit.E_mpa, fit.E_ci95_mpa, relax,
                                np.array([p.hold_s for p in presses]),
                                np.array([p.press for p in presses]))
    return SessionCalibration(session=session, certification=cert, depth_rule=depth_rule,
                              depth_mm=depth, fit=fit, nu_rounds=rounds,
                              seconds=time.perf_counter() - t0, warnings=notes,
                              depth_std_mm=std, bulge_mm=bulge, bevel_force_n=bevel_n,
                              relaxation=relax, moduli=moduli,
                              force0_n=force0 if force0 is not None else np.zeros(0),
                              force_fit_n=force - bevel_n, ft_zero=zero)


def _period(session: Session) -> float:
    """The frames' period, s (median step; 0 with one frame)."""
    t = session.frame_times_s
    return float(np.median(np.diff(t))) if t.size > 1 else 0.0


#: The stiffening of eq. (5) that the 'mark' rule's dP/dw assumes. The FEM's beta of a
#: bonded layer at w/h 0.05 to 0.2 (mechanics.beta_relation) is 0.77 to 0.82 at a/h 0.83
#: and nu 0.45 to 0.499 (dP/dw within 1 %), and 0.37 to 1.14 over a/h 0.5 to 1.2: dP/dw
#: then -6 to +4 % off at w/h 0.2, half that at 0.1, about mark_shared_mm's STIFFNESS_REL.
MARK_BETA = 0.8


def _mark_rule(presses, force: np.ndarray, fit_at, cfg, period: float):
    """The ``'mark'`` depth rule: depths from w0 and the force's rise from each indenter's
    P(w0) to the force window (:func:`~tactilevision.contact.crossing_forces`,
    :func:`~tactilevision.contact.mark_depths`), dP/dw from each press's own P/w. Returns
    the depths, their random uncertainty, the fit, the shared error as (low, high) per press
    (mm), and the notes."""
    if any(p.rule != "onset" for p in presses):
        raise InputError("the 'mark' depth rule needs every press certified by a mark's onset")
    w0 = np.array([p.w0_mm for p in presses])
    travel = np.array([p.travel_mm for p in presses])
    f_on, sem_on, disjoint = crossing_forces(
        np.array([p.indenter for p in presses]), np.array([p.force_onset_n for p in presses]),
        np.array([p.force_onset_sem_n for p in presses]))
    sem = np.array([p.force_sem_n for p in presses])
    h = cfg.gel_thickness_mm
    depth = w0 + travel / 2
    after = travel / 2
    for _ in range(20):
        # dP/dw between the crossing and the window, from each press's own P/w with eq. 5's
        # shape at a typical beta: the depths do not lean on the fit made from them
        x = (depth - after / 2) / h
        k = force / np.maximum(depth, 1e-9) * (1 + 2 * MARK_BETA * x) / (1 + MARK_BETA * x)
        k = np.maximum(k, 1e-6)
        new, std, after = mark_depths(w0, force, f_on, k, force_sem_n=sem,
                                      force_crossing_sd_n=sem_on, travel_mm=travel)
        moved = float(np.max(np.abs(new - depth)))
        depth = new
        if moved < 1e-6:
            break
    fit = fit_at(depth, std)
    half = mark_shared_mm(travel, after, period)
    # where P(w0) lies in its indenter's bracket is not random across indenters: a stage
    # that stops soon after w0 puts every crossing near the top of its last frame period,
    # so the brackets' middles read P(w0) low by up to their half-width, the deeper (faster)
    # presses most (on simulated 10 frames/s sessions the depth error rose 2 to 47 um per mm
    # of w0, and beta read low). Carried as shared: every press at its bracket's end at once.
    ind = np.array([p.indenter for p in presses])
    n_group = np.array([np.count_nonzero(ind == g) for g in ind], np.float64)
    cross = np.where(np.isfinite(f_on), np.sqrt(3.0) * np.nan_to_num(sem_on)
                     / np.sqrt(n_group) / k, 0.0)
    half = half + cross
    unread = int(np.sum(~np.isfinite(f_on)))
    notes = [f"depth rule 'mark': w = w0 + the depth past w0 that the force reads, from the "
             "crossing of w0 (P(w0) of each indenter: the intersection of its presses' frame "
             "periods before the mark first showed) to the force window "
             f"({1e3 * float(np.median(after)):.1f} um median, "
             f"{1e3 * float(np.min(after)):.1f} to {1e3 * float(np.max(after)):.1f} um; dP/dw "
             f"from each press's P/w, eq. 5 at beta {MARK_BETA:g}); shared by every press, "
             f"+-{1e3 * float(np.median(half)):.1f} um median (the clock, dP/dw, and where "
             f"P(w0) lies in its indenter's bracket, +-{1e3 * float(np.median(cross)):.1f} um "
             "median), carried whole into E's and nu's intervals"
             + (f"; {unread} presses without the crossing's force keep w0 + half a frame's "
                "travel" if unread else "")
             + (f"; the presses of {disjoint} indenter(s) do not agree on P(w0) (their mean is "
                "used): a gel not uniform, or a drifting force?" if disjoint else "")]
    return depth, std, fit, (-half, half), notes


def _with_shared_depth(fit: IndentationFit, fit_at, depth: np.ndarray, std: np.ndarray,
                       force: np.ndarray, low: np.ndarray, high: np.ndarray) -> IndentationFit:
    """E's and nu's intervals widened by a depth error that every press shares.

    The depths are moved by `low` and by `high` (mm, per press: the error's bounds) and
    fitted again; E's and nu's intervals become the hull of the three fits' intervals
    and point values. A bounded systematic error does not average out over presses: its
    whole range is carried (the hull covers at least as often as each fit's interval,
    whatever the error within its bounds). A bound at which beta's whole interval leaves
    the FEM table is excluded by the data (no layer fits the presses so moved) and adds
    nothing; one that cannot be fitted for another reason is said to leave the intervals
    too narrow."""
    if not (np.isfinite(fit.E_mpa) and np.isfinite(fit.nu)):
        # beta's interval leaves the table at the certified depths: a bound of the shared
        # error may fit a layer, but E and nu from that bound alone came out confident and
        # wrong on simulated sessions (nu [0.34, 0.38] for a true 0.48): not reported
        return fit
    E_lo, E_hi = fit.E_ci95_mpa
    nu_lo, nu_hi = fit.nu_ci95
    moved, failed, excluded = [], [], []
    for shift in (low, high):
        if not np.any(shift != 0):
            continue
        d = depth + shift
        try:
            if np.any(d <= 0):
                raise InputError("a depth at the error's bound is not positive")
            f2 = fit_at(d, std, force)
        except InputError as exc:
            failed.append(str(exc))
            continue
        if not (np.isfinite(f2.E_mpa) and np.isfinite(f2.nu)):
            # beta's whole interval beyond the table: no layer of any nu fits the presses
            # with the depths moved so far, so the data exclude that end of the error
            excluded.append(f"{1e3 * float(np.median(shift)):+.1f} um")
            continue
        moved.append(f2)
        E_lo, E_hi = min(E_lo, f2.E_mpa, f2.E_ci95_mpa[0]), max(E_hi, f2.E_mpa, f2.E_ci95_mpa[1])
        nu_lo = min(nu_lo, f2.nu, f2.nu_ci95[0])
        nu_hi = max(nu_hi, f2.nu, f2.nu_ci95[1])
    if failed:
        # a bound that cannot be fitted: the intervals cannot carry the error, and say so
        note = (f"the shared depth error ({1e3 * float(np.median(low)):+.1f} to "
                f"{1e3 * float(np.median(high)):+.1f} um median) could not be carried into the "
                f"intervals: at its bound {'; '.join(failed)}; E's and nu's intervals hold the "
                "press scatter only and are too narrow")
        fit = replace(fit, notes=(*fit.notes, note))
    if excluded:
        fit = replace(fit, notes=(*fit.notes, (
            f"the shared depth error at {' and '.join(excluded)} (median over presses) puts "
            "beta's whole interval outside the FEM table (no nu of a bonded elastic layer fits "
            "the presses so moved): the data exclude that end of it, and E's and nu's "
            "intervals carry the rest")))
    if not moved:
        return fit
    where = "its bounds" if len(moved) == 2 else "the bound the data allow"
    note = (f"shared depth error {1e3 * float(np.median(low)):+.1f} to "
            f"{1e3 * float(np.median(high)):+.1f} um (median over presses): E and nu refitted at "
            f"{where} ({', '.join(f'E = {m.E_mpa:.4f} MPa, nu = {m.nu:.4f}' for m in moved)}); "
            f"the intervals are the hull: E [{E_lo:.4f}, {E_hi:.4f}] MPa, nu [{nu_lo:.4f}, "
            f"{nu_hi:.4f}] (the press scatter alone: E [{fit.E_ci95_mpa[0]:.4f}, "
            f"{fit.E_ci95_mpa[1]:.4f}], nu [{fit.nu_ci95[0]:.4f}, {fit.nu_ci95[1]:.4f}])")
    return replace(fit, E_ci95_mpa=(float(E_lo), float(E_hi)), nu_ci95=(float(nu_lo),
                                                                          float(nu_hi)),
                   notes=(*fit.notes, note))


def _take_off_zero(session: Session, cert: Certification, mode: str
                   ) -> tuple[Session, Certification, ForceZero | None, list[str]]:
    """Read the F/T's zero between the presses and take it off the log and the presses'
    forces (``mode``: 'auto', 'constant', 'drift' or 'off'); the notes say what was done."""
    spans = cert.press_spans_s
    if spans.shape[0] == 0:
        return session, cert, None, []
    period = (float(np.median(np.diff(session.frame_times_s))) if session.n_frames > 1
              else 0.0)
    # a press touches the gel from before its first frame in contact to after its last
    contact = spans + cert.clock_offset_s + np.array([-period, period])
    zero = force_zero(session.force_times_s, session.forces_n[:, 2], contact,
                      subtracted="constant" if mode == "auto" else mode)
    if zero is not None and mode == "auto" and zero.drifts:
        zero = replace(zero, subtracted="drift")
    if zero is None:
        return session, cert, None, ["the F/T's zero could not be read: no settled rest between "
                                     "the presses; the forces are as the F/T read them"]
    note = zero.sentence()
    if mode == "off":
        return session, cert, zero, [note]
    forces = session.forces_n.copy()
    forces[:, 2] -= zero.taken_off(session.force_times_s)
    off = cert.clock_offset_s
    presses = [replace(p, force_n=p.force_n - float(zero.taken_off(p.t_frame_s + off + p.hold_s)),
                       force_onset_n=p.force_onset_n - float(zero.taken_off(p.t_frame_s + off)))
               for p in cert.presses]
    return (replace(session, forces_n=forces), replace(cert, presses=presses), zero, [note])


def _vernier_depths(w0: np.ndarray, closure: np.ndarray, cfg, nu: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Solve ``w + b(w) = w0 + closure`` for every press (b: the bulge at the bevel)."""
    depth = w0 + closure
    bulge = np.zeros_like(depth)
    for _ in range(6):          # b is a few % of w: a contraction
        bulge = bulge_at(cfg.bevel_offset_mm, depth, thickness_mm=cfg.gel_thickness_mm,
                         radius_mm=cfg.indenter_radius_mm, nu=nu)
        new = w0 + closure - bulge
        if np.max(np.abs(new - depth)) < 1e-8:
            depth = new
            break
        depth = new
    return depth, bulge


def _bulge_note(bulge: np.ndarray, depth: np.ndarray, cfg, rounds: list[float], w0, closure,
                fit_at, std, force) -> str:
    """One sentence on the bulge correction: its size and how it feeds back into nu."""
    frac = float(np.median(bulge / depth))
    text = (f"bulge correction: the gel rises {100 * frac:.2f}% of w at the bevel "
            f"({cfg.bevel_offset_mm:g} mm = {cfg.bevel_offset_mm / cfg.gel_thickness_mm:.2f} h "
            "from the axis; FEM, bonded Neo-Hookean layer)")
    if rounds:
        nu = rounds[-1]
        d2, _ = _vernier_depths(w0, closure, cfg, min(nu + 0.01, 0.499))
        f2 = fit_at(d2, std, force)
        if np.isfinite(f2.nu):
            gain = (f2.nu - nu) / (min(nu + 0.01, 0.499) - nu)
            text += (f", settled at nu = {nu:.4f} in {len(rounds)} round(s); d nu_fit / d nu = "
                     f"{gain:.2f}")
    return text
