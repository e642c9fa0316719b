"""The result of the main job in memory: :class:`SessionCalibration`, and the force over
each press's hold (``holds.csv``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..contact import (
    Certification,
    CertifiedPress,
    ForceZero,
    approach_start,
    hold_end,
    hold_start,
)
from ..io import Session
from ..mechanics import IndentationFit, RelaxationFit

__all__ = ["HOLD_SEARCH_S", "SessionCalibration", "hold_curves", "hold_spans"]

#: How long before a press's certification frame its approach's rise is looked for, s:
#: the end of the rise is the hold's start (:func:`hold_spans`).
HOLD_SEARCH_S = 0.5


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
    depth_indenter_std_mm : (N,) float64 ndarray
        For ``'mark'``: the part of `depth_std_mm` an indenter's presses share (the
        error of its P(w0), counted n times over as there), mm; empty otherwise.
    depth_half95_mm : (N,) float64 ndarray
        Each press's own 95 % depth half-width, mm (its own sd, an indenter's
        shared part counted once, and the bound every press shares taken as a
        uniform's); empty when nothing was fitted. :attr:`depth_certified`
        compares it with ``[gauge_block] depth_tolerance_mm``.
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
    depth_indenter_std_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    depth_half95_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    bulge_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    bevel_force_n: np.ndarray = field(default_factory=lambda: np.zeros(0))
    failure: str | None = None
    relaxation: RelaxationFit | None = None
    moduli: dict | None = None
    force0_n: np.ndarray = field(default_factory=lambda: np.zeros(0))
    force_fit_n: np.ndarray = field(default_factory=lambda: np.zeros(0))
    ft_zero: ForceZero | None = None

    @property
    def depth_certified(self) -> np.ndarray:
        """(N,) bool ndarray: each certified press's depth within +-
        ``[gauge_block] depth_tolerance_mm`` at 95 % (:attr:`depth_half95_mm`); the
        others are only bounded (fitted with their weight, named in a warning). All
        False when nothing was fitted."""
        n = len(self.certification.presses)
        if len(self.depth_half95_mm) != n:
            return np.zeros(n, bool)
        return np.asarray(self.depth_half95_mm <= self.session.config.depth_tolerance_mm)

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
        return hold_curves(self.session, self.certification, max_points)

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
            ``force_n``); where the presses' crossings of w0 were read (a
            mark's onset), ``force_w0_n`` and ``force_w0_sem_n``: the force
            at that crossing, less the zero, and its standard uncertainty, N
            (:mod:`tactilevision.diagnosis` tests them for changes within
            indenters).
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
        if len(self.depth_indenter_std_mm) == len(ps):
            col["depth_indenter_std_mm"] = list(self.depth_indenter_std_mm)
        onset = np.array([p.force_onset_n for p in ps], np.float64)
        if np.any(np.isfinite(onset)):         # the force where each press crossed w0
            col["force_w0_n"] = list(onset)
            col["force_w0_sem_n"] = [p.force_onset_sem_n for p in ps]
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



def hold_spans(session: Session, certification: Certification
                ) -> list[tuple[CertifiedPress, float, float]]:
    """Each certified press's hold on the F/T clock, (press, start, end), s: from its
    arrival at depth to the start of its release (presses whose release is not found left
    out).

    The arrival is where the force stops rising (:func:`~tactilevision.contact.hold_start`
    over the :data:`HOLD_SEARCH_S` before the press's certification frame to its release),
    not the frame itself: a drawn mark's first trace comes while the stage still goes
    deeper, up to a frame period or two before it stops (a hold read from there starts
    with the approach's last rise: on a Taxim mark session of a gel relaxing with tau
    0.7 s, the holds then looked straight and tau was not identified). Where no rise is
    found, the frame's time.
    """
    t, fz = np.asarray(session.force_times_s, np.float64), np.asarray(session.forces_n[:, 2])
    off = certification.clock_offset_s
    spans = []
    for p in certification.presses:
        t0 = p.t_frame_s + off
        t1 = hold_end(t, fz, t0)
        if t1 is None:
            continue
        t_hold = hold_start(t, fz, t0 - HOLD_SEARCH_S, t1)
        if t_hold is not None and t_hold < t1:
            t0 = t_hold            # the release found from the frame is the hold's (to 1 ms)
        spans.append((p, t0, t1))
    return spans


def hold_curves(session: Session, certification: Certification, max_points: int = 1000
                 ) -> dict[str, np.ndarray]:
    """The columns of ``holds.csv`` (:meth:`SessionCalibration.holds`)."""
    t, fz = np.asarray(session.force_times_s, np.float64), np.asarray(session.forces_n[:, 2])
    press, ts, fs, ramps = [], [], [], []
    for p, t0, t1 in hold_spans(session, certification):
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
