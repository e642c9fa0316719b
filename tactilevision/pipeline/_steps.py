"""Steps of the main job between certification and the fit: the F/T's zero taken off, the
relaxation of the holds, and the fit of eq. (5) with its warnings kept."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from .._checks import InputError
from ..contact import (
    Certification,
    ForceZero,
    certify_session,
    crossing_bracket,
    force_window,
    force_zero,
)
from ..io import Session
from ..mechanics import (
    APPARENT_E_WHY,
    BETA_TABLE_REACH,
    IndentationFit,
    RelaxationFit,
    elastic_force,
    fit_indentation,
    fit_relaxation,
    past_beta_table_reach,
    refine_relaxation,
)
from ._calibration import hold_curves, hold_spans

__all__ = ["Fitter", "frame_period", "read_force_zero", "relaxation_step", "take_off_zero"]


class Fitter:
    """eq. (5) fitted to the session's forces at given depths, each fit's warnings kept.

    With the FEM beta table, a press certified past the table's reach
    (:data:`~tactilevision.mechanics.BETA_TABLE_REACH`, w/h 0.23) by more than two of its
    depth uncertainties is left out of the fit, with a note naming it (it stays in the
    measurements table, for ``fit --beta-table paper`` or ``diagnose``), instead of one
    press refusing the whole session; once left out, it stays out of this object's later
    fits (the shared depth error's bounds are fitted on the same presses).

    Parameters
    ----------
    force : (N,) float64 ndarray
        The forces fitted when a call gives none, N.
    thickness_mm, radius_mm : float
        Layer thickness h and indenter radius a, mm.
    beta_table : str
        Passed to :func:`~tactilevision.mechanics.fit_indentation`.
    press : (N,) ndarray, optional
        The presses' numbers, for the note; default their positions.
    """

    def __init__(self, force: np.ndarray, *, thickness_mm: float, radius_mm: float,
                 beta_table: str, press: np.ndarray | None = None) -> None:
        self.force = force
        self.kw = dict(thickness_mm=thickness_mm, radius_mm=radius_mm, beta_table=beta_table)
        self.caught: dict[int, list[str]] = {}
        self.press = np.arange(len(force)) if press is None else np.asarray(press)
        self.left_out = np.zeros(len(force), bool)
        # each press's indenter and the part of its depth sd the indenter's presses share
        # (the mark rule sets them): the fits' misfit is read under that shared error
        self.indenter_shared: tuple[np.ndarray, np.ndarray] | None = None

    def __call__(self, depth: np.ndarray, std: np.ndarray | None,
                 f_n: np.ndarray | None = None) -> IndentationFit:
        """Fit at `depth` (mm) with uncertainty `std` (mm) to `f_n` (N; default the forces)."""
        f_n = self.force if f_n is None else f_n
        note = self._past_reach(depth, std)
        keep = ~self.left_out
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            shared = {}
            if self.indenter_shared is not None and std is not None:
                ind, ui = self.indenter_shared
                shared = dict(indenter=ind[keep], depth_indenter_std_mm=np.minimum(
                    ui[keep], std[keep]))
            f = fit_indentation(depth[keep], f_n[keep],
                                depth_std_mm=None if std is None else std[keep], **shared,
                                **self.kw)
        if note is not None:
            f = replace(f, notes=(*f.notes, note))
        self.caught[id(f)] = [str(w.message) for w in caught] + ([note] if note else [])
        return f

    def _past_reach(self, depth: np.ndarray, std: np.ndarray | None) -> str | None:
        """Mark the presses past the FEM table's reach by more than 2 sd; the note (None
        where none is left out)."""
        if self.kw["beta_table"] != "fem":
            return None
        h = float(self.kw["thickness_mm"])
        self.left_out |= past_beta_table_reach(depth, h, std)
        if not self.left_out.any():
            return None
        which = ", ".join(f"{int(p)} (w/h {w / h:.3f})"
                          for p, w in zip(self.press[self.left_out], depth[self.left_out],
                                          strict=True))
        return (f"press(es) {which} certified past the FEM beta table's reach (w/h "
                f"{BETA_TABLE_REACH:g}) by more than two of their depth uncertainties: left "
                "out of E's and nu's fit, kept in the measurements (fit --beta-table paper "
                "reads them)")

    def warnings_of(self, fit: IndentationFit) -> list[str]:
        """The warnings a fit made by this object raised."""
        return self.caught.get(id(fit), [])


def frame_period(session: Session) -> float:
    """The frames' period, s (median step; 0 with one frame)."""
    t = session.frame_times_s
    return float(np.median(np.diff(t))) if t.size > 1 else 0.0



def read_force_zero(session: Session, spans_s: np.ndarray, clock_offset_s: float,
                    mode: str = "auto") -> ForceZero | None:
    """The F/T's zero read in the rests between the presses
    (:func:`~tactilevision.contact.force_zero`), its ``subtracted`` set by `mode` ('auto':
    'drift' when the zero is seen to drift, else 'constant').

    Parameters
    ----------
    session : Session
    spans_s : (P, 2) float64 ndarray
        First and last frame in contact of each press, camera clock, s.
    clock_offset_s : float
        F/T clock minus camera clock, s.
    mode : {'auto', 'constant', 'drift', 'off'}, default 'auto'

    Returns
    -------
    ForceZero or None
        None when no settled rest was found.
    """
    period = (float(np.median(np.diff(session.frame_times_s))) if session.n_frames > 1
              else 0.0)
    # a press touches the gel from before its first frame in contact to after its last
    contact = spans_s + clock_offset_s + np.array([-period, period])
    zero = force_zero(session.force_times_s, session.forces_n[:, 2], contact,
                      subtracted="constant" if mode == "auto" else mode)
    if zero is not None and mode == "auto" and zero.drifts:
        zero = replace(zero, subtracted="drift")
    return zero


def take_off_zero(session: Session, cert: Certification, mode: str
                   ) -> tuple[Session, Certification, ForceZero | None, list[str]]:
    """Read the F/T's zero between the presses and take it off the log and the presses'
    forces; the notes say what was done.

    Parameters
    ----------
    session : Session
    cert : Certification
        From :func:`~tactilevision.contact.certify_session` on `session`.
    mode : {'auto', 'constant', 'drift', 'off'}
        As ``ft_zero`` of :func:`~tactilevision.pipeline.calibrate_session`.

    Returns
    -------
    session : Session
        With the zero taken off ``forces_n[:, 2]`` (unchanged for 'off').
    cert : Certification
        Its presses' ``force_n`` and ``force_onset_n`` likewise.
    zero : ForceZero or None
        The zero read (:func:`~tactilevision.contact.force_zero`); None when no
        settled rest was found.
    notes : list of str
    """
    spans = cert.press_spans_s
    if spans.shape[0] == 0:
        return session, cert, None, []
    zero = read_force_zero(session, spans, cert.clock_offset_s, mode)
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



def relaxation_step(session: Session, cert: Certification, progress: Callable | None,
                bevel_threshold: float | str = "auto"
                ) -> tuple[Certification, RelaxationFit | None, list[str], np.ndarray | None]:
    """Fit the holds; for a relaxing gel, certify again with the clock on the elastic force.

    Parameters
    ----------
    session : Session
        With the F/T's zero taken off (:func:`take_off_zero`).
    cert : Certification
    progress : callable or None
        Wraps the frame iterator of a second certification.
    bevel_threshold : float or 'auto', default 'auto'
        As in :func:`~tactilevision.contact.certify_session`.

    Returns
    -------
    cert : Certification
        Certified again on the elastic force for a relaxing gel, else `cert`.
    relaxation : RelaxationFit or None
        :func:`~tactilevision.mechanics.fit_relaxation` (refined on the whole log
        for a relaxing gel); None when not tested (fewer than 3 holds).
    notes : list of str
    force0 : (N,) float64 ndarray or None
        Each certified press's force at the instant of loading, N (the F/T
        window's mean of the elastic force behind the log); None unless the gel
        relaxes.
    """
    def fit(c: Certification, holds: dict[str, np.ndarray]) -> RelaxationFit:
        # with each press's time and indenter: softening, which does not recover between
        # presses, is told from relaxation, which does
        return fit_relaxation(holds["press"], holds["t_s"], holds["fz_n"], holds["ramp_s"],
                              press_time_s={p.press: p.time_s for p in c.presses},
                              press_group={p.press: p.indenter for p in c.presses})

    holds = hold_curves(session, cert)
    if np.unique(holds["press"]).size < 3:
        return cert, None, ["relaxation: fewer than 3 holds found in the F/T log, not tested"], None
    try:
        relax = fit(cert, holds)
    except InputError as exc:
        return cert, None, [f"relaxation: not tested ({exc})"], None
    if not relax.resolved:
        note = f"relaxation {relax.verdict}: {relax.why}"
        if relax.verdict == "decay not identified":
            note += f"; the E fitted is {APPARENT_E_WHY}"
        return cert, relax, ([] if relax.verdict == "flat" else [note]), None

    def refined(c: Certification, r: RelaxationFit) -> RelaxationFit:
        # each hold remembers the presses before it: g and tau from the whole log
        spans = np.array([(t0, t1) for _, t0, t1 in hold_spans(session, c)]).reshape(-1, 2)
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
        holds = hold_curves(session, again)
        if np.unique(holds["press"]).size >= 3:
            again_relax = fit(again, holds)
            if again_relax.resolved:
                relax = refined(again, again_relax)
    off, n = again.clock_offset_s, session.config.window_samples
    force0 = np.array([force_window(session.force_times_s, elastic, p.t_frame_s + off + p.hold_s,
                                    n).fz_n for p in again.presses])
    again = _elastic_crossings(again, session.force_times_s, elastic[:, 2])
    note = (f"the gel relaxes while held (g = {relax.g:.3f}, tau = {relax.tau_s:.3g} s from "
            f"{relax.n_presses} holds; {relax.why}): the clock was synchronised on the "
            f"elastic force behind the F/T log ({cert.clock_offset_s:.4f} s on the measured force, "
            f"{again.clock_offset_s:.4f} s on the elastic one), and the fit takes each "
            "press's force from it (force0_n, the force at the instant of loading; a drawn "
            "mark's crossing forces likewise): E is E_0, the instantaneous modulus")
    return again, relax, [note], force0


def _elastic_crossings(cert: Certification, force_times_s: np.ndarray, elastic_fz_n: np.ndarray
                       ) -> Certification:
    """A drawn mark's crossing forces P(w0) read again on the elastic force behind the log,
    at the instants that bracket each crossing (:func:`~tactilevision.contact.crossing_bracket`
    over ``onset_span_s``): the mark rule takes each depth past w0 from the difference of
    the window's force and P(w0), which must come from one force. On a Taxim mark session
    of a gel relaxing with g 0.25, tau 0.7 s, the elastic window force less the measured
    P(w0) read the depths 34 um deep on average."""
    presses = []
    for p in cert.presses:
        if p.rule == "onset" and np.all(np.isfinite(p.onset_span_s)):
            f, sd = crossing_bracket(force_times_s, elastic_fz_n, *p.onset_span_s,
                                     ramp_end_s=p.hold_start_s)
            p = replace(p, force_onset_n=f, force_onset_sem_n=sd)
        presses.append(p)
    return replace(cert, presses=presses)
