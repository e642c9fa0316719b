"""A machined bevel (``bevel_angle_deg > 0``): the band of contact read over each hold.

Per press, the hold and the frames the vernier is read on (:func:`_vernier_onset`);
over the session, the edge blur and band model its long bands choose
(:func:`_session_optics`) and every press's band read with them
(:func:`_read_vernier_presses`); the bounds of what a band leaves unread
(:func:`unresolved_closure`, :func:`vernier_shared_mm`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy import stats

from ._holds import hold_start
from ._results import (
    BACKGROUND_DEGREE,
    FRAME_SNR,
    MAX_CLOSURE_MM,
    MIN_BAND_CONTRAST,
    MIN_BEVEL_COVERAGE,
    VERNIER_SNR,
    CertifiedPress,
    Rejection,
)
from ._vernier import (
    RESOLVED_PX,
    BevelGeometry,
    BevelProfile,
    BevelReading,
    bevel_profile,
    read_bevel,
)

__all__ = ["CREST_CHECK_P", "CREST_NOMINAL_PX", "EDGE_SHARED_FRACTION", "SHADOW_RATIO",
           "band_models_agree", "crest_consistency", "readable_overshoot_mm",
           "unresolved_closure", "vernier_shared_mm"]


#: With lines, a long band is read only when its edges alone (``read_bevel(lines='only')``)
#: give its half-width within this (px): in cell E of ``benchmarks/bench_vernier.py
#: --sweep``, Taxim's shadow block beside four narrow bands (2 to 4 px) read 19 to 21 px
#: with flanks and 4 to 5 px without, its long bands agreeing within 0.5 px; in cells B
#: and D some long bands disagree by 2 to 5 px and are not read.
AGREE_PX = 1.5
#: A band whose crest lies farther than this (px), or 4 robust sd of the long bands'
#: crests, from their median is not read (the crest's place is fixed by the block: the
#: long bands of sweep cells A and B lie within 1 px of their median; the misread narrow
#: bands that passed for long ones, 3 to 5.5 px off).
CREST_TOLERANCE_PX = 2.0
#: Without the flank colours' prior, a band is read only when its crest lies within this
#: (px) of the crest line the block's geometry puts it on (session.toml's bevel offset and
#: direction from the press's footprint centre: ``BevelReading.crest_px`` is measured from
#: it). The median of the long bands alone is no anchor where every band read long is a
#: misread: on a drawn vernier design (seed 9161, design 23 of
#: ``benchmarks/bench_mark_sweep.py``: 8.7 deg, 20 frames/s) Taxim's shadow block beside
#: bands 4.4 to 4.8 px long read as bands of 10.5 to 10.9 px with their crests 6.4 to
#: 6.7 px towards the indenter (a block beside the band moves the crest by about half its
#: width, to the shadow's side: +3.2 and +7.25 px in tests/test_vernier_taxim.py),
#: 27 um too deep at 3 um stated, while the two truly long bands, crests -0.35 and -0.8 px,
#: were refused as far from that median. True bands' crests lie within 0.75 px of the line
#: on the committed Taxim session (sample_frames/taxim_gauge) and within 2.1 px on the
#: simulated sample session.
CREST_NOMINAL_PX = 2.5
#: A long band is read, in a session with lines, only when the band read with shadows
#: cast outward from thin edge lines (``read_bevel(lines='shadows')``) is at least this
#: fraction of it (:func:`band_models_agree`). On Taxim's renders that model reads true
#: bands of 9.5 to 38 px at 0.62 to 0.96 of the flanks' reading, and the shadow block
#: beside a band of 2.6 to 5.6 px, read 10 to 12.5 px with flanks and within AGREE_PX by
#: its edges, at 0.42 to 0.56 (8 deg flanks at 15 frames/s, seeds 81, 95 and 96 of
#: ``benchmarks/taxim_gauge_session.py``; sweep cells A to C of
#: ``benchmarks/bench_vernier.py``). Such blocks were read 24 to 31 um deep at 3 to 8 um
#: stated.
SHADOW_RATIO = 0.6
#: The read bands' stated half-width uncertainties are widened by their crests' Birge
#: ratio when the crests scatter more than those uncertainties allow at this significance
#: (:func:`crest_consistency`).
CREST_CHECK_P = 0.05
#: The shared error of a read band's half-width, as a fraction of the session's edge width
#: (:func:`vernier_shared_mm`).
EDGE_SHARED_FRACTION = 0.4


#: The blur that fits the long bands best, times this, reads the short bands without bias.
#: JPEG and the renderer's finite differences make the band's edges a sharp core with
#: tails, which a Gaussian fitted by least squares widens; a short band read with that
#: wider blur comes out short. Measured on three simulated 50-press sessions (JPEG quality
#: 75 and 90): least-squares blurs 1.75 to 2.5 px, unbiased short bands at 1.5 to 2.0 px
#: (benchmarks/bench_vernier.py prints the bias by band length).
BLUR_SHRINK = 0.8
#: Widths (sd, px) of the lines along the band's edges tried on the session's long bands.
_LINE_SDS = (1.2, 2.0, 3.0)
#: The bevel's profile stops this far (mm) from the indenter's footprint on its side: the
#: indenter's own contact shades the gel beside it (Taxim's renders: a trough whose deepest
#: part lies within 0.2 mm of the edge; a 3.5 deg bevel 4 mm from the axis of a 2.5 mm
#: indenter read it into its bands, 3 px too long, and saw 8 of 20 bands under the
#: threshold; ``benchmarks/bench_vernier.py --sweep``, cell L).
INDENTER_CLEARANCE_MM = 0.25
#: A session's bands carry lines when lines at their edges leave less than this share of
#: the residual variance (median over its long bands): 0.03 to 0.39 on 13 Taxim sessions
#: (bevels of 3 to 13 deg; ``benchmarks/bench_vernier.py --sweep`` and its Taxim rows),
#: 0.65 and 0.70 on our two simulated 50-press sessions, whose bands have none.
LINES_RSS_RATIO = 0.5
#: Edge blurs (sd, px) tried on the session's long bands.
_BLURS = (0.6, 0.8, 1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0)


def _vernier_onset(session, geom: BevelGeometry, centre: tuple[float, float], s: float,
                   cand: np.ndarray, reach: float, period: float, half: float, offset: float,
                   t_first: float):
    """Hold of a press and the vernier's frames: the force's hold, the band read over it.

    The hold starts where the F/T log stops rising (:func:`hold_start`), else
    at the first of the longest run of frames that show the band at one
    width. The window's frames (the force window's span from there) must
    show the band together (signal-to-noise ratio :data:`VERNIER_SNR`, not
    filling the whole profile) and three in four of them at the same width
    (to 2.5 sd or 2.5 px, the quick looks being on a 1 px grid): a structure
    that is not a band wanders from frame to frame.

    Returns ``(t_cert, onset, window_frames, window_profiles, snr, reading)``
    or a :class:`Rejection` (its press, time and centre filled in by the caller).
    """
    ref = session.reference
    times = session.frame_times_s
    inner = (geom.offset_mm - session.config.indenter_radius_mm - INDENTER_CLEARANCE_MM) / s
    profiles = {int(i): bevel_profile(session.frame(int(i)), ref, centre, s, geom, reach_px=reach,
                                      inner_px=min(reach, inner))
                for i in cand}
    cover = min(p.coverage for p in profiles.values())
    if cover < MIN_BEVEL_COVERAGE:
        return Rejection(press=-1, reason="bevel out of view",
                         detail=f"only {100 * cover:.0f}% of the bevel's band "
                                f"({geom.offset_mm:g} mm from the indenter at "
                                f"{geom.direction_deg:g} deg) lies inside the image",
                         t_frame_s=float("nan"), frame=int(cand[-1]))
    kw = dict(max_closure_mm=MAX_CLOSURE_MM, coarse=True, background_degree=BACKGROUND_DEGREE)
    fz = session.forces_n[:, 2]
    # from the press's first contact: the whole rise must be in view
    t_hold = hold_start(session.force_times_s, fz, t_first + offset - period,
                        float(times[cand[-1]]) + offset + period)
    if t_hold is not None:
        t_cert = t_hold - offset
        in_window = (times[cand] >= t_cert - 1e-9) & (times[cand] <= t_cert + 2 * half + 1e-9)
        if not in_window.any():         # a window shorter than a frame period
            later = np.flatnonzero(times[cand] >= t_cert - 1e-9)
            if later.size:
                in_window[later[0]] = True
        window = [int(i) for i in cand[in_window]]
    else:
        window = []
    if not window:
        # no hold in the force: the longest run of frames seeing the band at one width
        reads = {i: read_bevel(p, geom, s, **kw) for i, p in profiles.items()}
        snr = np.array([reads[int(i)].snr for i in cand])
        half_w = np.array([reads[int(i)].half_width_px for i in cand])
        runs: list[list[int]] = []
        for j in np.flatnonzero(snr >= FRAME_SNR):
            if runs and runs[-1][-1] == j - 1 and abs(
                    half_w[j] - float(np.median(half_w[runs[-1]]))) <= 1.5:
                runs[-1].append(int(j))
                continue
            runs.append([int(j)])
        if not runs:
            return _never_seen(geom, float(snr.max()), int(cand[int(np.argmax(snr))]))
        run = max(runs, key=lambda r: (len(r), float(snr[r].sum())))
        t_cert = float(times[cand[run[0]]])
        window = [int(cand[j]) for j in run if times[cand[j]] <= t_cert + 2 * half + 1e-9]
    onset = window[0]
    # seen: with lines along the edges too (renderers' and optics' shadows), which no band of
    # another kind needs
    plain = read_bevel([profiles[i] for i in window], geom, s, **kw)
    joint = read_bevel([profiles[i] for i in window], geom, s, **kw, lines="all", line_px=2.0)
    if plain.snr >= joint.snr:
        joint = plain
    # the frames must agree on the width (without lines: a line at an edge trades off
    # against its position, frame by frame)
    per = [read_bevel(profiles[i], geom, s, **kw) for i in window] if len(window) > 1 else [plain]
    # (quick looks on a 1 px grid: each may land a grid step either side)
    agree = [abs(r.half_width_px - plain.half_width_px) <= max(2.5 * r.half_width_std_px, 2.5)
             for r in per]
    consistent = float(np.mean(agree)) >= 0.75       # one noisy frame of 18 (90 fps) may stray
    # a band shorter than RESOLVED_PX on every frame is only bounded, to the same range
    # whatever its frames read (0 to RESOLVED_PX's worth of overshoot on each frame, so
    # also over the window): its frames' disagreement changes nothing that is stated
    consistent = consistent or max(r.half_width_px for r in [plain, *per]) < RESOLVED_PX
    if joint.snr < VERNIER_SNR:
        why = "" if consistent else "; the frames of the hold also disagree on its width"
        return _never_seen(geom, joint.snr, onset, why)
    if not consistent:
        # seen, but not steady: the deciding reason first, the ratio that passed after it
        return Rejection(
            press=-1, reason="bevel band unsteady",
            detail=f"the frames of the hold disagree on the width of the band on the bevel "
                   f"{geom.offset_mm:g} mm from the indenter at {geom.direction_deg:g} deg: "
                   f"{int(np.sum(agree))} of {len(agree)} frames agree with their joint reading "
                   f"({plain.half_width_px:.1f} px half-width), three in four are needed; the "
                   f"band's signal-to-noise ratio, {joint.snr:.1f}, passes the threshold "
                   f"{VERNIER_SNR:g}",
            t_frame_s=float("nan"), frame=onset, bevel_score=joint.snr)
    return t_cert, onset, tuple(window), [profiles[i] for i in window], joint.snr, joint


def _never_seen(geom: BevelGeometry, best: float, frame: int, why: str = "") -> Rejection:
    """The rejection of a press whose hold shows no band (best ratio `best` at `frame`)."""
    return Rejection(press=-1, reason="bevel never seen",
                     detail=f"the frames of the hold show no band of contact on the bevel "
                            f"{geom.offset_mm:g} mm from the indenter at {geom.direction_deg:g} "
                            f"deg (signal-to-noise ratio {best:.1f}, threshold "
                            f"{VERNIER_SNR:g}{why})",
                     t_frame_s=float("nan"), frame=frame, bevel_score=best)


def _edge_width(optics: dict) -> float:
    """The session's edge width, px: the least-squares edge blur of its long bands (before
    :data:`BLUR_SHRINK`), or their edge lines' sd when they carry lines, if wider."""
    blur = float(optics["blur_px"]) / (BLUR_SHRINK if optics.get("n_bands", 0) >= 2 else 1.0)
    if optics.get("lines", "none") != "none":
        blur = max(blur, float(optics.get("line_px", 0.0)))
    return round(blur, 4)


def vernier_shared_mm(band_resolved: np.ndarray, bevel: BevelGeometry, mm_per_px: float,
                      edge_px: float) -> np.ndarray:
    """The bound of the vernier's error that every read band shares: where its edges sit.

    Parameters
    ----------
    band_resolved : (N,) array_like of bool
        Which presses' bands were read (:attr:`CertifiedPress.band_resolved`);
        unresolved ones carry their whole range already.
    bevel : BevelGeometry
    mm_per_px : float
    edge_px : float
        The session's edge width, px (``Certification.bevel_optics['edge_px']``).

    Returns
    -------
    (N,) float64 ndarray
        ``EDGE_SHARED_FRACTION * edge_px * tan(theta) * mm_per_px`` for read
        bands, 0 for the others, mm: the error lies within plus or minus it.

    Notes
    -----
    The band model places each edge at the middle of a blurred step (or on a
    line). Where a renderer's or a sensor's colour edge sits against the true
    edge of contact is not known from the frames: the gel leaves the flank
    tangentially, and shadows fall outward. The read bands' mean error was
    -0.85 to +0.14 px on the Taxim cells of ``benchmarks/bench_vernier.py
    --sweep`` (edge width 3 px: at most 0.28 of it), and -0.22 and -0.05 px
    on our two simulated 50-press sessions (``bench_vernier.py``; edge widths
    2.5 and 1.75 px), one value for every press of a session: a systematic
    error, carried into E's and nu's intervals by refits at its bounds, not
    averaged over the presses.
    """
    r = np.asarray(band_resolved, bool)
    half = EDGE_SHARED_FRACTION * float(edge_px) * bevel.tan_theta * float(mm_per_px)
    return np.where(r, half, 0.0)


def readable_overshoot_mm(angle_deg: float, mm_per_px: float,
                          top_px: float = RESOLVED_PX) -> float:
    """How far past w0 the stage must stop for a vernier's band to be read, mm.

    Parameters
    ----------
    angle_deg : float
        The bevel's flank angle theta, deg (0: a drawn mark, no band: 0 returned).
    mm_per_px : float
    top_px : float, default ``RESOLVED_PX``
        The shortest half-width read, px.

    Returns
    -------
    float
        ``top_px x mm_per_px x tan(theta)`` (w = w0 + L tan(theta), formats.md §1): a
        band of half-width L shorter than `top_px` only bounds the overshoot to it.
    """
    return max(float(top_px), 0.0) * math.tan(math.radians(angle_deg)) * float(mm_per_px)


def unresolved_closure(bevel: BevelGeometry, mm_per_px: float,
                       top_px: float = RESOLVED_PX) -> tuple[float, float]:
    """The closure of a band too short to read, as a uniform over its possible range.

    Parameters
    ----------
    bevel : BevelGeometry
        Needs ``angle_deg > 0``.
    mm_per_px : float
    top_px : float, default ``RESOLVED_PX``
        The largest half-width the band may have, px.

    Returns
    -------
    closure_mm, closure_std_mm : float
        The middle of ``[0, top_px] tan(theta) mm_per_px`` and the sd of a
        uniform over it (``/ sqrt(12)``), mm: the band was seen, so the crest
        reached the gel, but its half-width is somewhere under `top_px`.
    """
    top = readable_overshoot_mm(bevel.angle_deg, mm_per_px, top_px)
    return 0.5 * top, top / math.sqrt(12.0)


def crest_consistency(crest_px: np.ndarray, std_px: np.ndarray) -> tuple[float, float]:
    """Whether the read bands' crests scatter as their stated uncertainties allow.

    The crest's place on the bevel is fixed by the block, so across a
    session's read bands it varies only by the reading's own error (and the
    footprint centre's, which adds to it). A band's crest and half-width come
    from its two edges, ``(outer + inner) / 2`` and ``(outer - inner) / 2``,
    so with independent edge errors the two share one standard uncertainty:
    the crests' scatter checks the half-widths' stated uncertainty on the
    session's own frames, with no truth.

    Parameters
    ----------
    crest_px : (N,) array_like of float
        The read bands' crest positions, px.
    std_px : (N,) array_like of float
        Their stated half-width uncertainties, px (> 0).

    Returns
    -------
    birge_ratio : float
        ``sqrt(chi2 / (N - 1))`` about the weighted mean crest (R. T. Birge,
        Phys. Rev. 40, 207, 1932): about 1 when the stated uncertainties hold,
        above 1 when the crests scatter more. NaN for fewer than 3 bands.
    p_value : float
        The chance of a chi-square with ``N - 1`` degrees of freedom at least
        that large: small when the stated uncertainties are too narrow.

    Notes
    -----
    One-sided: an error that moves both edges outward or inward alike (a
    shadow beside the band, a wrong edge blur) changes the half-width but not
    the crest, and this check does not see it.
    """
    c = np.asarray(crest_px, np.float64)
    sd = np.asarray(std_px, np.float64)
    if c.size < 3:
        return float("nan"), float("nan")
    wt = 1.0 / sd ** 2
    mean = float(np.sum(wt * c) / np.sum(wt))
    chi2 = float(np.sum(wt * (c - mean) ** 2))
    dof = c.size - 1
    return math.sqrt(chi2 / dof), float(stats.chi2.sf(chi2, dof))


def _crest_checked(out: list[CertifiedPress], optics: dict) -> list[CertifiedPress]:
    """The read bands' closure uncertainties widened by their crests' Birge ratio, if needed.

    Where :func:`crest_consistency` finds the crests scattering beyond their
    stated uncertainties (p below :data:`CREST_CHECK_P`), every read band's
    ``closure_std_mm`` is multiplied by the Birge ratio; the ratio, its p and
    the factor applied go into `optics` (``crest_birge``, ``crest_p``,
    ``read_std_factor``).
    """
    read = [p for p in out if p.band_resolved and p.reading is not None]
    ratio, pval = crest_consistency([p.reading.crest_px for p in read],
                                    [max(p.reading.half_width_std_px, 1e-6) for p in read])
    factor = ratio if (np.isfinite(pval) and pval < CREST_CHECK_P and ratio > 1.0) else 1.0
    optics["crest_birge"] = None if not np.isfinite(ratio) else round(ratio, 3)
    optics["crest_p"] = None if not np.isfinite(pval) else round(pval, 4)
    optics["read_std_factor"] = round(factor, 3)
    if factor == 1.0:
        return out
    return [replace(p, closure_std_mm=p.closure_std_mm * factor) if p.band_resolved else p
            for p in out]


def band_models_agree(profiles: list[BevelProfile], geom: BevelGeometry, s: float,
                      flanks: BevelReading, kw: dict) -> bool:
    """Whether a band read long with its flanks (`flanks`) is a band, in a session with
    lines or shadows along its edges.

    Two more band models must see it: its edges alone (``lines='only'``) give its
    half-width within :data:`AGREE_PX`, and thin edge lines with shadows cast outward
    (``lines='shadows'``) at least :data:`SHADOW_RATIO` of it. A block of colour beside
    a narrow band (Taxim's shadow) reads long with flanks and, often, by its edges too,
    while the shadows model sees the narrow band it is.

    Parameters
    ----------
    profiles : list of BevelProfile
        The press's window.
    geom : BevelGeometry
    s : float
        Scale, mm per px.
    flanks : BevelReading
        The band read with the session's model (``kw``), resolved.
    kw : dict
        :func:`read_bevel`'s options of the session (``lines``, ``blur_px``, ...).

    Returns
    -------
    bool
    """
    edges = read_bevel(profiles, geom, s, **{**kw, "lines": "only"})
    if abs(edges.half_width_px - flanks.half_width_px) > AGREE_PX:
        return False
    shadows = read_bevel(profiles, geom, s, **{**kw, "lines": "shadows"})
    return shadows.half_width_px >= SHADOW_RATIO * flanks.half_width_px


def _read_vernier_presses(pending: list[dict], geom: BevelGeometry, s: float
                          ) -> tuple[list[CertifiedPress], list[Rejection], dict]:
    """Read every press's band over its window, with the session's own optics.

    1. The session's edge blur is chosen on its longest, clearest bands
       (:func:`_session_optics`).
    2. Every press is read with it, its flank colours free.
    3. The flank colours of the long bands (half-width >= ``RESOLVED_PX``)
       are fitted as a plane over the bevel's position in the image (the
       sensor's lighting varies across it: 6% of the colours left against 19%
       for one colour, on the simulated sample session); short bands, whose
       shape the blur hides, are read again with that plane's colours at
       their position as a prior, weighted by its residual spread.
    4. Without that prior (bands carrying lines or shadows along their
       edges, or too few long bands), a band is read only when it is long
       (half-width >= ``RESOLVED_PX``), its crest lies on the block's crest
       line (within :data:`CREST_NOMINAL_PX`) and where the session's long
       bands on that line put it (within :data:`CREST_TOLERANCE_PX`, or 4
       robust sd of theirs, of their median crest; three or more such long
       bands needed),
       and, in a session with lines, two other band models see it too
       (:func:`band_models_agree`: its edges alone within :data:`AGREE_PX`,
       the shadows model at least :data:`SHADOW_RATIO` of it). With or
       without the prior, its inner edge must also lie two edge widths clear
       of the profile's end on the indenter's side
       (:data:`INDENTER_CLEARANCE_MM`). Any other band
       is *unresolved*: its width is only bounded, to ``[0, max(RESOLVED_PX,
       L)]`` pixels' worth (L plus two edge widths for a band cut off at the
       profile's end), its uncertainty that of a uniform over that range
       (:func:`unresolved_closure`), and the fit weighs it accordingly; the
       point within it is the band read with thin edge lines and shadows cast
       outward (``lines='shadows'``), clipped to the range. On
       Taxim's renders, whose shadows paint a block 10 to 25 px wide beside
       narrow bands, every band model read such bands 2 to 21 px long
       whatever their true length (1 to 7 px), at
       stated uncertainties of a fraction of that: 49 um off at 4 um stated
       on a 15 deg bevel (``benchmarks/bench_vernier.py --sweep``).
    5. A band whose colour contrast is under :data:`MIN_BAND_CONTRAST` of the
       long bands' (median, when two or more are long) is shading, not a
       band: the press is rejected as ``'bevel never seen'``.

    Returns the certified presses, those rejected in step 4 and the optics.
    """
    optics = _session_optics(pending, geom, s)
    kw = dict(max_closure_mm=MAX_CLOSURE_MM, lines=optics["lines"], blur_px=optics["blur_px"],
              line_px=optics.get("line_px", 2.0))
    first = [read_bevel(d["profiles"], geom, s, **kw) for d in pending]
    # with lines: the band seen by its edges alone must be the band seen with its flanks (a
    # block of colour beside a narrow band, such as Taxim's shadow, reads as a long band
    # only with flanks)
    agrees = np.ones(len(first), bool)
    if optics["lines"] != "none":
        for k, (d, r) in enumerate(zip(pending, first, strict=True)):
            if r.resolved:
                agrees[k] = band_models_agree(d["profiles"], geom, s, r, kw)
    long = np.array([r.resolved and r.snr >= 2 * VERNIER_SNR for r in first]) & agrees
    X = np.array([[1.0, d["press"].x_mm, d["press"].y_mm] for d in pending])
    C = np.array([r.flank_colours.ravel() for r in first])            # (N, 6)
    plane = None
    if long.sum() >= 6:
        coef, *_ = np.linalg.lstsq(X[long], C[long], rcond=None)
        res = C[long] - X[long] @ coef
        spread = float(np.sqrt(np.mean(res ** 2) / max(np.mean(C[long] ** 2), 1e-12)))
        plane = (coef, max(spread, 0.03))
    elif long.sum() >= 2:
        mean = C[long].mean(axis=0)
        spread = float(np.sqrt(np.mean((C[long] - mean) ** 2) / max(np.mean(mean ** 2), 1e-12)))
        plane = (np.vstack([mean, np.zeros((2, 6))]), max(spread, 0.1))
    if plane is not None and plane[1] > 0.5:
        plane = None       # the long bands' colours scatter too much to inform the short ones
    if optics["lines"] != "none":
        plane = None       # lines or shadows at the edges: the model reads short bands itself
    out: list[CertifiedPress] = []
    faint: list[Rejection] = []
    n_unresolved = 0
    edge = _edge_width(optics)
    crest0, crest_tol = float("nan"), float("inf")
    on_line = np.array([abs(r.crest_px) <= CREST_NOMINAL_PX for r in first])
    seen_long = [r.crest_px for r, ok, on in zip(first, agrees, on_line, strict=True)
                 if r.resolved and ok and on]
    if len(seen_long) >= 3:
        cr = np.array(seen_long)
        crest0 = float(np.median(cr))
        crest_tol = max(CREST_TOLERANCE_PX, 4.0 * 1.4826 * float(np.median(np.abs(cr - crest0))))
    contrast_long = (float(np.median([r.contrast for r, ok in zip(first, long, strict=True)
                                      if ok])) if long.sum() >= 2 else float("nan"))
    for k, (d, r) in enumerate(zip(pending, first, strict=True)):
        if r.contrast < MIN_BAND_CONTRAST * contrast_long:      # False when NaN
            p = d["press"]
            faint.append(Rejection(
                press=p.press, reason="bevel never seen",
                detail=f"the best band on the bevel ({r.half_width_px:.1f} px half-width) has "
                       f"a colour contrast of {r.contrast:.1f} grey levels, "
                       f"{100 * r.contrast / contrast_long:.0f}% of the session's long bands' "
                       f"{contrast_long:.1f} (threshold {100 * MIN_BAND_CONTRAST:.0f}%): "
                       "shading, not a band of contact",
                t_frame_s=d["t0"], frame=p.frame, bevel_score=r.snr, centre_px=d["centre"]))
            continue
        closure, closure_std = r.closure_mm, r.closure_std_mm
        if plane is not None and not r.resolved:
            # a short band: lines at its edges would trade off against L; its colours
            # come from the long bands at its position
            prior = (X[k] @ plane[0]).reshape(2, 3)
            r = read_bevel(d["profiles"], geom, s, flank_colours=prior, colour_sd=plane[1],
                           **{**kw, "lines": "none"})
            closure, closure_std = r.closure_mm, r.closure_std_mm
        # the inner edge must lie inside the profile, clear of its end by two edge widths
        to_end = r.crest_px - d["profiles"][0].u_px[0]          # crest to the profile's end
        clear = to_end - r.half_width_px >= 2.0 * edge
        read = clear and (plane is not None or (r.resolved and abs(r.crest_px - crest0)
                                                <= crest_tol and agrees[k] and on_line[k]))
        if not read:
            # no prior, and not long where the long bands are: only bounded (step 4)
            # (a band cut off at the profile's end may be longer than read; a short band
            # misread long may reach the end too, so no lower bound is drawn from it)
            top = max(RESOLVED_PX, r.half_width_px + (0.0 if clear else 2.0 * edge))
            closure, closure_std = unresolved_closure(geom, s, top)
            # the point within the bounds: the band read with thin edge lines and shadows
            # cast outward (read_bevel(lines='shadows'))
            sh = read_bevel(d["profiles"], geom, s, **{**kw, "lines": "shadows"})
            closure = float(np.clip(sh.half_width_px, 0.0, top)) * geom.tan_theta * s
            n_unresolved += 1
        out.append(replace(d["press"], rule="vernier", closure_mm=closure,
                           closure_std_mm=closure_std, reading=r, bevel_score=r.snr,
                           window_frames=d["window"], band_resolved=read))
    out = _crest_checked(out, optics)
    optics["unresolved"] = n_unresolved
    optics["shadows"] = n_unresolved          # their point: the shadows reading
    optics["edge_px"] = edge
    optics["crest_px"] = None if np.isnan(crest0) else round(crest0, 3)
    optics["prior"] = plane is not None and any(not r.resolved for r in first)
    optics["colour_spread"] = None if plane is None else round(plane[1], 4)
    optics["contrast_long"] = None if np.isnan(contrast_long) else round(contrast_long, 2)
    return out, faint, optics


def _session_optics(pending: list[dict], geom: BevelGeometry, s: float, *, n_max: int = 8
                    ) -> dict:
    """The edge blur and band model that explain the session's long bands best.

    On up to `n_max` bands at least ``RESOLVED_PX`` long (the clearest):
    the blur of :data:`_BLURS` with the least summed residual, times
    :data:`BLUR_SHRINK`; then whether
    the bands carry lines along their edges (renderers' and real optics'
    shadows): if reading them with lines moves L by more than 1 px, or
    leaves under :data:`LINES_RSS_RATIO` of the residual variance (medians
    over the bands), the session is read with lines, else without (a line
    at an edge trades off against the edge's position, so it costs
    precision where it is not needed). Defaults (1.0 px, no lines) when
    fewer than two bands are long enough.
    """
    long = sorted((d for d in pending if d["quick"].half_width_px >= RESOLVED_PX),
                  key=lambda d: -d["quick"].snr)[:n_max]
    if len(long) < 2:
        return {"blur_px": 1.0, "lines": "none", "line_px": 2.0, "n_bands": len(long)}
    totals = []
    for blur in _BLURS:
        rs = [read_bevel(d["profiles"], geom, s, max_closure_mm=MAX_CLOSURE_MM, lines="none",
                         blur_px=blur) for d in long]
        totals.append((sum(r.noise ** 2 * r.model.size for r in rs), blur, rs))
    _, blur, plain = min(totals, key=lambda t: t[0])
    lined = {sd: [read_bevel(d["profiles"], geom, s, max_closure_mm=MAX_CLOSURE_MM, lines="all",
                             blur_px=blur, line_px=sd) for d in long] for sd in _LINE_SDS}
    line_sd = min(_LINE_SDS, key=lambda sd: sum(r.noise ** 2 for r in lined[sd]))
    # do the bands carry lines? judged with the narrowest lines, which move the edges least
    # where there are none
    shift = float(np.median([abs(a.half_width_px - b.half_width_px)
                             for a, b in zip(plain, lined[_LINE_SDS[0]], strict=True)]))
    ratio = float(np.median([(b.noise / max(a.noise, 1e-12)) ** 2
                             for a, b in zip(plain, lined[line_sd], strict=True)]))
    lines = "all" if shift > 1.0 or ratio < LINES_RSS_RATIO else "none"
    return {"blur_px": round(BLUR_SHRINK * blur, 4), "lines": lines,
            "line_px": line_sd, "n_bands": len(long), "line_shift_px": round(shift, 3),
            "line_rss_ratio": round(ratio, 3)}
