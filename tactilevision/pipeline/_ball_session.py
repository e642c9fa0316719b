"""The main job for a ball: a session of frames and F/T forces in, E (and nu) out.

A session whose ``[indenter] shape`` is ``"sphere"`` has no gauge block: each
press's depth is read from the ball's contact circle through the sphere's a(w)
(:func:`circle_depths`; the circle from :func:`tactilevision.optics.find_contact_circle`,
found on textured balls, under a drift of the illumination, on contacts that cover much
of the pad or run past its edge, and refused where it cannot be trusted), its force from
the F/T log over the hold (:func:`tactilevision.contact.find_ball_presses`); a press whose
force needs a modulus no tactile gel has at its circle's depth (:data:`E_PLAUSIBLE_MPA`)
is refused, and E is fitted to the others by the sphere's force law
(:func:`tactilevision.mechanics.fit_indenter`), the circles' shared error carried into its
interval. :func:`write_ball_calibration` writes the output folder (formats.md section 3,
"A ball session").
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .._checks import InputError
from ..contact import BallPresses, Rejection, find_ball_presses
from ..io import (
    DeadWeightSession,
    Session,
    StagedOutput,
    read_dead_weights,
    read_session,
    write_measurements,
)
from ..mechanics import IndenterFit, Sphere, fit_indenter
from ..optics import (
    CIRCLE_ERROR,
    MIN_RIM_IN_FRAME,
    ContactCircle,
    DepthReconstructor,
    PhotometricCalibration,
    find_contact_circle,
)
from ..viz import ball_calibration_figure
from ._ball import CIRCLE_ERROR_RADIUS_PX, BallDepths, contact_depths
from ._ball_caps import CAP_PRESS_SD, CAP_SCALE_SD, BallCaps, ball_press_caps
from ._steps import read_force_zero

__all__ = ["BALL_CALIBRATION_FILES", "E_PLAUSIBLE_MPA", "BallCalibration", "ball_indenter",
           "calibrate_ball_session", "calibrate_dead_weights", "circle_depths",
           "write_ball_calibration"]

#: The moduli a press's force and its circle's depth may imply, MPa. The gels of vision-based
#: tactile sensors are silicones and polyurethanes from about Shore 00-10 (some 0.05 MPa) to
#: Shore A 60 (some 2 to 3 MPa); the range reaches a decade past each end so that no real gel
#: is refused for its softness or stiffness. A press whose force needs a modulus outside it
#: at its circle's depth has the wrong circle (a texture's, part of the contact) or a force
#: that is not its own (units, a tare, another press).
E_PLAUSIBLE_MPA = (0.01, 10.0)

#: The files :func:`write_ball_calibration` writes.
BALL_CALIBRATION_FILES = ("measurements.csv", "session.toml", "circles.csv", "rejected.csv",
                          "fit.json", "calibration.png")


@dataclass(frozen=True)
class BallCalibration:
    """What :func:`calibrate_ball_session` (or :func:`calibrate_dead_weights`) found.

    Attributes
    ----------
    session : tactilevision.io.Session or tactilevision.io.DeadWeightSession
    indenter : Sphere
    presses : tactilevision.contact.BallPresses or None
        The presses found in the frames and their force windows (None for dead
        weights).
    used : (N,) int64 ndarray
        Index into ``presses.presses`` (dead weights: into the frames) of each fitted
        press (those whose circle gave a depth).
    depths : BallDepths
        The fitted presses' depths from their contact circles.
    force_n, force_sem_n : (N,) float64 ndarray
        Each fitted press's force and its standard uncertainty, N (the F/T window's
        mean and standard error; dead weights: m g and the mass's uncertainty times g).
    rejected : list of Rejection
        Presses rejected by the force log or by their circle.
    fit : IndenterFit
    nu, law, contact : the a(w) the depths were read through
    warnings : list of str
    seconds : float
        Wall time of :func:`calibrate_ball_session`, s.
    caps : BallCaps or None
        The height map's cap of each fitted press against its circle's depth (the
        cross-check; None without an optics calibration).
    """

    session: Session | DeadWeightSession
    indenter: Sphere
    presses: BallPresses | None
    used: np.ndarray
    depths: BallDepths
    force_n: np.ndarray
    force_sem_n: np.ndarray
    rejected: list[Rejection]
    fit: IndenterFit
    nu: float
    law: str
    contact: str
    warnings: list[str] = field(default_factory=list)
    seconds: float = 0.0
    caps: BallCaps | None = None

    @property
    def frames(self) -> np.ndarray:
        """(N,) int64 ndarray: the frame of each fitted press."""
        if self.presses is None:
            return self.used
        return np.array([self.presses.presses[i].frame for i in self.used], np.int64)


def ball_indenter(session: Session | DeadWeightSession) -> Sphere:
    """The session's ball: ``[indenter] radius_mm``, on the pad of ``[sensor]
    gel_radius_mm`` when it is given (the infinite layer, the sphere table, when it is
    the default 20 h), the gel domed by ``[sensor] gel_dome_radius_mm`` where given.

    Raises
    ------
    InputError
        Naming the file and key: a dome without the pad's radius, or not wider than it.
    """
    cfg = session.config
    pad = cfg.gel_radius_mm
    infinite = abs(pad - 20.0 * cfg.gel_thickness_mm) <= 1e-9 * pad
    try:
        return Sphere(cfg.indenter_radius_mm, pad_radius_mm=None if infinite else pad,
                      dome_radius_mm=cfg.gel_dome_radius_mm)
    except InputError as exc:
        raise InputError(f"{session.path / 'session.toml'}: [sensor] gel_dome_radius_mm: "
                         f"{exc}") from None


def calibrate_ball_session(session: Session | str | Path, *, nu: float = 0.5,
                           law: str = "neo_hookean", progress: Callable | None = None,
                           min_contact_px: int = 200,
                           optics: PhotometricCalibration | str | Path | None = None,
                           e_range_mpa: tuple[float, float] = E_PLAUSIBLE_MPA
                           ) -> BallCalibration:
    """Find every press of a ball session, read its depth from its contact circle, fit E.

    Parameters
    ----------
    session : Session or path
        A session (or its folder) whose ``[indenter] shape`` is ``"sphere"``.
    nu : float, default 0.5
        Poisson's ratio of a(w) and the nu E is reported at when the presses do not
        identify it (:func:`~tactilevision.mechanics.fit_indenter`).
    law : {'neo_hookean', 'linear'}, default 'neo_hookean'
        The force law and a(w): finite strain, or small strain.
    progress : callable, optional
        Wraps the frame iterator (e.g. ``tqdm``).
    min_contact_px : int, default 200
        Pixels of contact that make a frame part of a press.
    optics : PhotometricCalibration or path, optional
        A photometric calibration of the sensor: each fitted press's height map then
        gives its cap as a cross-check of the circle's depth
        (:func:`ball_press_caps`, ``caps``); default: the session's ``[optics]
        calibration``, else none.
    e_range_mpa : (float, float), default :data:`E_PLAUSIBLE_MPA`
        The moduli a press's force may imply at its circle's depth; a press outside is
        rejected (``'force contradicts the circle'``).

    Returns
    -------
    BallCalibration

    Raises
    ------
    InputError
        For a session that is not a ball's, no press found, a clock that cannot be
        synchronised, a bad `e_range_mpa`, or fewer than two presses with a depth and a
        force.

    Notes
    -----
    The contact condition is ``[indenter] contact`` (default frictionless). Each
    press's depth is w = a^-1(r s), r the contact circle's radius at the frame in the
    middle of the force window (:func:`circle_depths`), s = ``mm_per_px``; its random and
    shared errors (:class:`BallDepths`) enter the fit as errors in the depths and a shared
    depth error (``depth_shared_mm``), and the F/T window's standard error as the force's.
    A press is rejected, with its reason in ``rejected``, when its circle is not found or
    not trusted (:func:`~tactilevision.optics.find_contact_circle`: cut by the image's
    edge, a rim that does not stand out from the pad) or its force needs a modulus outside
    `e_range_mpa` at its circle's depth.
    The F/T's zero is read from the rests between the presses and taken off the forces
    (its line over the session where it drifts, else its mean; as ``calibrate_session``'s
    ``ft_zero='auto'``).
    """
    t0 = time.perf_counter()
    if not isinstance(session, Session):
        session = read_session(session)
    cfg = session.config
    if cfg.indenter_shape != "sphere":
        raise InputError(f"{session.path / 'session.toml'}: [indenter] shape is "
                         f"{cfg.indenter_shape!r}: calibrate_ball_session reads a ball's "
                         "session (shape = \"sphere\"); a gauge block's is calibrate_session's")
    ball = ball_indenter(session)
    e_range = _e_range(e_range_mpa)
    found = find_ball_presses(session, min_contact_px=min_contact_px, progress=progress)
    frames = [(p.press, p.frame, p.t_frame_s) for p in found.presses]
    used, depths, rejected = _circle_depths(session, ball, frames, nu, law, session.frame)
    force = np.array([found.presses[i].force_n for i in used])
    sem = np.array([found.presses[i].force_sem_n for i in used])
    force, zero_note = _take_off_zero(session, found, used, force)
    keep, refused = _force_check(session, ball, [frames[i] for i in used], depths, force,
                                 nu, law, e_range)
    used, depths = [used[i] for i in keep], _take(depths, keep)
    force, sem = force[keep], sem[keep]
    rejected = sorted(rejected + refused + list(found.rejected), key=lambda r: r.press)
    cal = _fit(session, ball, found, used, depths, force, sem, rejected, nu, law,
               list(session.notes) + list(found.warnings) + [zero_note], t0)
    return replace(with_caps(cal, optics), seconds=time.perf_counter() - t0)


def with_caps(cal: BallCalibration, optics: PhotometricCalibration | str | Path | None, *,
              frame_of: Callable[[int], np.ndarray] | None = None) -> BallCalibration:
    """`cal` with its presses' caps (:func:`ball_press_caps`) and a sentence on them, where
    an optics calibration is given or named by the session (else `cal` as it is);
    `frame_of` reads a frame by its index (default the session's ``frame``). A cap check
    that cannot be made (a calibration that does not load or fit the frames, a press
    without its annulus) leaves `cal` as it is, with a warning saying why."""
    session = cal.session
    optics = optics if optics is not None else session.config.calibration
    if optics is None:
        return cal
    cfg = session.config
    try:            # a cross-check: where it cannot be made, the calibration stands, said so
        if not isinstance(optics, PhotometricCalibration):
            optics = PhotometricCalibration.load(optics)
        recon = DepthReconstructor(optics, reference=session.reference)
        frame_of = frame_of or session.frame
        heights = np.stack([recon(frame_of(int(f))) for f in cal.frames])
        stated = optics.provenance.get("inner_cap_sd")
        caps = ball_press_caps(heights, cal.depths, cal.indenter, mm_per_px=cfg.mm_per_px,
                               thickness_mm=cfg.gel_thickness_mm, nu=cal.nu,
                               contact=cal.contact,
                               press_sd=CAP_PRESS_SD if stated is None else float(stated))
    except InputError as exc:
        return replace(cal, warnings=[*cal.warnings, f"cap cross-check not made: {exc}"])
    notes = [caps.summary()]
    rel = float(np.median(cal.depths.depth_shared_mm / cal.depths.depth_mm))
    # the median ratio: the shared scale, the circles' shared depth error, and the
    # presses' own scatter through a median (1.2533 sd / sqrt(n))
    n_caps = max(1, int(np.count_nonzero(np.isfinite(caps.ratio))))
    bound = 2.0 * float(np.sqrt(CAP_SCALE_SD ** 2 + rel ** 2
                                + (1.2533 * caps.press_sd) ** 2 / n_caps))
    off = float(np.nanmedian(caps.ratio)) - 1.0
    if abs(off) > bound:
        notes.append(f"the caps and the circles disagree by {100 * off:+.1f} %, beyond both "
                     f"their errors (+-{100 * bound:.0f} %): the circles are biased, or the "
                     "optics calibration does not fit these frames")
    return replace(cal, caps=caps, warnings=list(cal.warnings) + notes)


def _take_off_zero(session: Session, found: BallPresses, used: list[int],
                   force: np.ndarray) -> tuple[np.ndarray, str]:
    """The F/T's zero, read between the presses (:func:`read_force_zero`: its line where
    it drifts, else its mean), taken off each press's force; and the note saying so."""
    off = found.clock_offset_s
    zero = read_force_zero(session, found.press_spans_s, off)
    if zero is None:
        return force, ("the F/T's zero could not be read: no settled rest between the "
                       "presses; the forces are as the F/T read them")
    at = np.array([found.presses[i].t_frame_s + off for i in used])
    return force - np.asarray(zero.taken_off(at), np.float64), zero.sentence()


def calibrate_dead_weights(session: DeadWeightSession | str | Path, *, nu: float = 0.5,
                           law: str = "neo_hookean",
                           optics: PhotometricCalibration | str | Path | None = None,
                           e_range_mpa: tuple[float, float] = E_PLAUSIBLE_MPA
                           ) -> BallCalibration:
    """E from a ball at rest under known masses: P = m g, the depth from its contact circle.

    The route for a lab without an F/T sensor (formats.md section 1, "Dead weights").

    Parameters
    ----------
    session : DeadWeightSession or path
        Read by :func:`~tactilevision.io.read_dead_weights`, or its folder.
    nu : float, default 0.5
        Poisson's ratio of a(w), and E's nu when the weights do not identify it.
    law : {'neo_hookean', 'linear'}, default 'neo_hookean'
    optics : PhotometricCalibration or path, optional
        As :func:`calibrate_ball_session`'s: each frame's height-map cap beside its
        circle's depth (default: the folder's ``[optics] calibration``, else none).
    e_range_mpa : (float, float), default :data:`E_PLAUSIBLE_MPA`
        As :func:`calibrate_ball_session`'s.

    Returns
    -------
    BallCalibration
        ``presses`` None; ``force_sem_n`` the masses' uncertainties times g.

    Raises
    ------
    InputError
        For a broken folder (:func:`~tactilevision.io.read_dead_weights`), a bad
        `e_range_mpa`, or fewer than two frames whose circle gives a depth and whose mass
        it agrees with.
    """
    t0 = time.perf_counter()
    if not isinstance(session, DeadWeightSession):
        session = read_dead_weights(session)
    ball = ball_indenter(session)
    e_range = _e_range(e_range_mpa)
    frames = [(i, i, float("nan")) for i in range(len(session.frame_paths))]
    stack = session.frames()
    used, depths, rejected = _circle_depths(session, ball, frames, nu, law,
                                            lambda i: stack[i])
    keep, refused = _force_check(session, ball, [frames[i] for i in used], depths,
                                 session.force_n[used], nu, law, e_range)
    used, depths = [used[i] for i in keep], _take(depths, keep)
    rejected = sorted(rejected + refused, key=lambda r: r.press)
    cal = _fit(session, ball, None, used, depths, session.force_n[used],
               session.force_std_n[used], rejected, nu, law, list(session.notes), t0)
    return replace(with_caps(cal, optics, frame_of=lambda i: stack[i]),
                   seconds=time.perf_counter() - t0)


def circle_depths(circle: ContactCircle, indenter: Sphere, *, mm_per_px: float,
                  thickness_mm: float, nu: float = 0.5, law: str = "neo_hookean",
                  contact: str | None = None, name: str = "frame") -> BallDepths:
    """One press's depth from its contact circle (:func:`~tactilevision.optics.find_contact_circle`)
    through the indenter's a(w), with its uncertainty.

    Parameters
    ----------
    circle : ContactCircle
    indenter : Sphere
    mm_per_px, thickness_mm, nu, law, contact
        As :func:`ball_press_depths`'s.
    name : str
        The frame, for messages.

    Returns
    -------
    BallDepths
        One press. Its radius errors: the detector's (:data:`~tactilevision.optics.CIRCLE_ERROR`,
        2.5 % of the radius, random and shared alike) taken at the circle's radius or at
        61 px, whichever is larger (an edge is located to a number of pixels on a small
        circle; a large one's edge moves with its texture and the colour response's
        saturation, by 2 to 9 % of its radius on the renders of
        ``tests/test_ball_texture.py``), and the radial profile's own bootstrap sd in
        quadrature with the random part.

    Raises
    ------
    InputError
        Naming the frame: a contact radius the indenter's table does not reach or not
        smaller than the ball; or a bad scale.
    """
    s = _scale(mm_per_px)
    kw = {"nu": nu, "thickness_mm": thickness_mm, "law": law, "contact": contact}
    try:
        w, dw_da = contact_depths(indenter, np.array([float(circle.radius_px) * s]), kw)
    except InputError as exc:
        raise InputError(f"{name}: {exc}") from None
    return _circle_press(circle, s, float(w[0]), float(dw_da[0]), nu=nu, law=law,
                         contact=indenter._contact(contact))


def _scale(mm_per_px: float) -> float:
    s = float(mm_per_px)
    if not (np.isfinite(s) and s > 0):
        raise InputError(f"mm_per_px must be positive, got {mm_per_px!r}")
    return s


def _circle_press(circle: ContactCircle, s: float, w: float, dw_da: float, *, nu: float,
                  law: str, contact: str) -> BallDepths:
    """One press's :class:`BallDepths` from its circle, depth w (mm) and dw/da."""
    r = float(circle.radius_px)
    scale_px = max(r, CIRCLE_ERROR_RADIUS_PX)
    sd_px = float(np.hypot(CIRCLE_ERROR.radius_sd * scale_px, circle.radius_sd_px))
    bias_px = CIRCLE_ERROR.radius_bias * scale_px
    a = r * s
    one = np.ones(1)
    return BallDepths(depth_mm=w * one, depth_std_mm=dw_da * sd_px * s * one,
                      depth_shared_mm=dw_da * bias_px * s * one, contact_radius_mm=a * one,
                      centres_px=np.asarray(circle.centre_px, np.float64).reshape(1, 2),
                      radii_px=r * one, dw_da=dw_da * one, radius_sd_px=sd_px,
                      radius_bias_px=bias_px,
                      notes=(f"depths from the contact circles (the radial profile's edge "
                             f"about the colour edge's centre) through a(w) ({law}, "
                             f"{contact}, nu = {nu:g}); circle radius "
                             "error 2.5 % of the radius or of 61 px, whichever is larger, "
                             "random and shared, and the profile's own sd",))


def _circle_depths(session, ball: Sphere, frames: list[tuple[int, int, float]], nu: float,
                   law: str, frame_of: Callable[[int], np.ndarray]
                   ) -> tuple[list[int], BallDepths | None, list[Rejection]]:
    """Each press's depth from its frame's circle, so that one bad circle rejects its press
    only: (indices of those read, their depths, the rejections). The circles' depths are
    read through one table or FEM sweep, the shallowest press's; where that refuses one,
    each press alone, the refused one rejected."""
    cfg = session.config
    kw = dict(mm_per_px=cfg.mm_per_px, thickness_mm=cfg.gel_thickness_mm, nu=nu, law=law,
              contact=cfg.indenter_contact)
    found, rejected = [], []
    for i, (press, frame, t) in enumerate(frames):
        name = f"press {press} (frame {frame}, {session.frame_paths[frame].name})"

        def reject(reason: str, detail: str, press=press, frame=frame, t=t) -> None:
            rejected.append(Rejection(press=press, reason=reason, detail=detail, t_frame_s=t,
                                      frame=frame))

        try:
            circle = find_contact_circle(frame_of(frame), session.reference)
        except InputError as exc:
            reject("no contact circle", f"{name}: {exc}")
            continue
        if circle.problems:
            cut = circle.rim_in_frame < MIN_RIM_IN_FRAME
            reject("contact cut by the image's edge" if cut else "contact circle not trusted",
                   f"{name}: " + "; ".join(circle.problems))
            continue
        found.append((i, name, circle, reject))
    used, parts, w = [], [], None
    try:
        if not found:
            raise InputError("no circle")
        s = _scale(cfg.mm_per_px)
        w, dw_da = contact_depths(ball, np.array([c.radius_px for _, _, c, _ in found]) * s,
                            {k: kw[k] for k in ("nu", "thickness_mm", "law", "contact")})
    except InputError:
        pass                                            # each alone: the refused one named
    for k, (i, name, circle, reject) in enumerate(found):
        try:
            parts.append(circle_depths(circle, ball, name=name, **kw) if w is None else
                         _circle_press(circle, s, float(w[k]), float(dw_da[k]), nu=nu,
                                       law=law, contact=ball._contact(kw["contact"])))
        except InputError as exc:
            reject("no depth from the circle", str(exc))
            continue
        used.append(i)
    return used, (_stack(parts) if parts else None), rejected


def _e_range(e_range_mpa) -> tuple[float, float]:
    """`e_range_mpa` checked: two finite moduli, 0 < low < high."""
    try:
        lo, hi = (float(v) for v in e_range_mpa)
    except (TypeError, ValueError):
        raise InputError(f"e_range_mpa must be two moduli (low, high) in MPa, got "
                         f"{e_range_mpa!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
        raise InputError(f"e_range_mpa must hold 0 < low < high, got {e_range_mpa!r}")
    return lo, hi


def _force_check(session, ball: Sphere, frames: list[tuple[int, int, float]],
                 depths: BallDepths | None, force: np.ndarray, nu: float, law: str,
                 e_range: tuple[float, float]) -> tuple[list[int], list[Rejection]]:
    """Each press's apparent E, its force over the law's at E = 1 at its circle's depth:
    (indices of the presses whose E lies in `e_range`, the others' rejections)."""
    if depths is None or not len(frames):
        return [], []
    cfg = session.config
    g = ball.force(depths.depth_mm, E_mpa=1.0, nu=nu, thickness_mm=cfg.gel_thickness_mm,
                   law=law, contact=cfg.indenter_contact)
    e_app = np.asarray(force, np.float64) / np.asarray(g, np.float64)
    lo, hi = e_range
    keep, rejected = [], []
    for k, (press, frame, t) in enumerate(frames):
        if np.isfinite(e_app[k]) and lo <= e_app[k] <= hi:
            keep.append(k)
            continue
        name = f"press {press} (frame {frame}, {session.frame_paths[frame].name})"
        rejected.append(Rejection(
            press=press, reason="force contradicts the circle", t_frame_s=t, frame=frame,
            detail=f"{name}: its circle (radius {depths.contact_radius_mm[k]:.4g} mm) gives a "
                   f"depth of {1e3 * depths.depth_mm[k]:.4g} um, where its force, "
                   f"{force[k]:.4g} N, needs E = {e_app[k]:.3g} MPa ({law}, nu = {nu:g}): "
                   f"outside the {lo:g} to {hi:g} MPa of any tactile gel (the circle is not "
                   "the contact's, or the force not the press's)"))
    return keep, rejected


def _take(depths: BallDepths | None, keep: list[int]) -> BallDepths | None:
    """`depths` of the presses `keep` only (None where none is kept)."""
    if depths is None or not keep:
        return None
    idx = np.asarray(keep, np.int64)
    return replace(depths, **{name: getattr(depths, name)[idx] for name in (
        "depth_mm", "depth_std_mm", "depth_shared_mm", "contact_radius_mm", "centres_px",
        "radii_px", "dw_da")})


def _fit(session, ball: Sphere, found: BallPresses | None, used: list[int],
         depths: BallDepths | None, force: np.ndarray, sem: np.ndarray,
         rejected: list[Rejection], nu: float, law: str, notes: list[str], t0: float
         ) -> BallCalibration:
    """E fitted to the presses with a depth and a force (two or more, else refused)."""
    cfg = session.config
    if len(used) < 2:
        reasons = "; ".join(f"press {r.press}: {r.reason} ({r.detail})" for r in rejected[:4])
        raise InputError(f"{session.path}: {len(used)} of {len(used) + len(rejected)} presses "
                         f"have a depth and a force, too few to fit E"
                         + (f" ({reasons})" if reasons else ""))
    fit = fit_indenter(depths.depth_mm, force, ball, thickness_mm=cfg.gel_thickness_mm,
                       law=law, contact=cfg.indenter_contact, nu=nu,
                       depth_std_mm=depths.depth_std_mm,
                       depth_shared_mm=depths.depth_shared_mm,
                       force_std_n=sem if np.all(np.isfinite(sem)) else None)
    return BallCalibration(session=session, indenter=ball, presses=found,
                           used=np.array(used, np.int64), depths=depths,
                           force_n=np.asarray(force, np.float64),
                           force_sem_n=np.asarray(sem, np.float64), rejected=rejected,
                           fit=fit, nu=float(nu), law=law,
                           contact=ball._contact(cfg.indenter_contact), warnings=notes,
                           seconds=time.perf_counter() - t0)


def _stack(parts: list[BallDepths]) -> BallDepths:
    """One :class:`BallDepths` of the presses' own (each read alone)."""
    cat = {name: np.concatenate([getattr(p, name) for p in parts])
           for name in ("depth_mm", "depth_std_mm", "depth_shared_mm", "contact_radius_mm",
                        "centres_px", "radii_px", "dw_da")}
    return BallDepths(**cat, radius_sd_px=parts[0].radius_sd_px,
                      radius_bias_px=parts[0].radius_bias_px, notes=parts[0].notes)


def write_ball_calibration(cal: BallCalibration, out: str | Path, *, figure: bool = True,
                           overwrite: bool = False) -> dict[str, Path]:
    """Write a ball session's calibration folder.

    Parameters
    ----------
    cal : BallCalibration
    out : str or Path
        The folder (created). The files are written whole into a hidden folder in it and
        moved into place at the end (:class:`~tactilevision.io.StagedOutput`): a rerun
        replaces its own files; others stay unless `overwrite`.
    figure : bool, default True
        Also draw ``calibration.png``
        (:func:`tactilevision.viz.ball_calibration_figure`).
    overwrite : bool, default False
        Replace files in `out` that tactilevision did not write there.

    Returns
    -------
    dict of str to Path
        Each file written.

    Notes
    -----
    ``measurements.csv`` (formats.md section 2: ``depth_mm``, ``force_n``,
    ``depth_std_mm``, ``depth_shared_mm``, ``force_sem_n``, ``press``, ``time_s``
    (since the first frame), ``hold_s``, ``force_std_n``, ``fx_n``, ``fy_n``) with its
    sidecar ``session.toml`` (the ball: shape, radius, contact, pad), so that ``fit``,
    ``diagnose`` and ``validate`` read it again with the same noise model;
    ``circles.csv`` (each press's frame, circle and depth); ``rejected.csv``;
    ``fit.json`` (``fit --json``'s object of a ball, with ``source``, ``n_rejected``
    and ``clock_offset_s``); ``calibration.png`` (force against depth with the fitted
    law, each press's apparent E).
    """
    out = Path(out)
    with StagedOutput(out, overwrite=overwrite) as stage:
        names = _write_files(cal, stage.path, figure)
        stage.commit()
    return {name: out / name for name in names}


def _write_files(cal: BallCalibration, out: Path, figure: bool) -> list[str]:
    """Write the calibration's files into `out`; their names."""
    cfg = cal.session.config
    d = cal.depths
    paths = {name: out / name for name in BALL_CALIBRATION_FILES}
    ind = {"radius_mm": cfg.indenter_radius_mm, "shape": "sphere", "contact": cal.contact}
    sensor = {"gel_thickness_mm": cfg.gel_thickness_mm, "mm_per_px": cfg.mm_per_px}
    if cal.indenter.pad_radius_mm is not None:
        sensor["gel_radius_mm"] = cal.indenter.pad_radius_mm
    if cal.indenter.dome_radius_mm is not None:
        sensor["gel_dome_radius_mm"] = cal.indenter.dome_radius_mm
    paths["session.toml"].write_text(
        "# written by tactilevision calibrate: the ball of the session's presses\n"
        "[sensor]\n" + "".join(f"{k} = {v!r}\n" for k, v in sensor.items())
        + "\n[indenter]\n" + "".join(f"{k} = {json.dumps(v)}\n" for k, v in ind.items()))
    columns = {"depth_mm": d.depth_mm, "force_n": cal.force_n, "depth_std_mm": d.depth_std_mm,
               "depth_shared_mm": d.depth_shared_mm, "force_sem_n": cal.force_sem_n}
    if cal.presses is not None:
        pr = [cal.presses.presses[i] for i in cal.used]
        t0 = float(cal.session.frame_times_s[0])          # time_s: since the session's start
        columns.update({"press": [p.press for p in pr],
                        "time_s": [p.t_frame_s - t0 for p in pr],
                        "hold_s": [p.hold_s for p in pr],
                        "force_std_n": [p.force_std_n for p in pr],
                        "fx_n": [p.fx_n for p in pr], "fy_n": [p.fy_n for p in pr]})
        press = [p.press for p in pr]
    else:
        columns["press"] = press = cal.used
    write_measurements(paths["measurements.csv"], columns, thickness_mm=cfg.gel_thickness_mm,
                       radius_mm=cfg.indenter_radius_mm)
    names = [cal.session.frame_paths[f].name for f in cal.frames]
    paths["circles.csv"].write_text(_circles_csv(cal, press, names))
    paths["rejected.csv"].write_text("press,reason,detail,t_frame_s,frame\n" + "".join(
        f"{r.press},{r.reason},\"{r.detail.replace(chr(34), chr(39))}\","
        f"{_cell(r.t_frame_s)},{r.frame}\n" for r in cal.rejected))
    obj = cal.fit.to_json_dict()
    src = ("forces from the F/T log over each hold" if cal.presses is not None
           else "forces m g of the dead weights")
    obj.update({"source": "depths from the ball's contact circles through a(w) "
                          f"({cal.law}, {cal.contact}, nu = {cal.nu:g}), {src}",
                "session": str(cal.session.path), "n_rejected": len(cal.rejected),
                "clock_offset_s": None if cal.presses is None else cal.presses.clock_offset_s,
                "clock_source": None if cal.presses is None else cal.presses.clock_source,
                "warnings": cal.warnings, "seconds": round(cal.seconds, 2)})
    paths["fit.json"].write_text(json.dumps(obj, indent=2, allow_nan=False) + "\n")
    if figure:
        ball_calibration_figure(cal, paths["calibration.png"])
    else:
        del paths["calibration.png"]
    return list(paths)


def _circles_csv(cal: BallCalibration, press, names: list[str]) -> str:
    """``circles.csv``: each press's frame, circle and depth (and its cap, where the caps
    were read: ``cap_mm``, ``cap_expected_mm``, ``cap_depth_mm``, ``cap_depth_std_mm``)."""
    d, caps = cal.depths, cal.caps
    head = ("press,frame,frame_file,x_px,y_px,radius_px,contact_radius_mm,depth_mm,"
            "depth_std_mm,depth_shared_mm")
    rows = [f"{k},{f},{n},{c[0]:.3f},{c[1]:.3f},{r:.3f},{a:.6g},{w:.6g},{s:.3g},{b:.3g}"
            for k, f, n, c, r, a, w, s, b in zip(
                press, cal.frames, names, d.centres_px, d.radii_px, d.contact_radius_mm,
                d.depth_mm, d.depth_std_mm, d.depth_shared_mm, strict=True)]
    if caps is not None:
        head += ",cap_mm,cap_expected_mm,cap_depth_mm,cap_depth_std_mm"
        rows = [row + "," + ",".join(_cell(v, "6g") for v in vals) for row, *vals in zip(
            rows, caps.cap_mm, caps.expected_mm, caps.depth_mm, caps.depth_std_mm,
            strict=True)]
    return "\n".join([head, *rows]) + "\n"


def _cell(x: float, spec: str = ".4f") -> str:
    """A number for a CSV cell: empty where there is none (a dead weight's time, a cap past
    the ball's reach)."""
    return format(x, spec) if np.isfinite(x) else ""
