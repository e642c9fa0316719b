"""The accuracy report of a photometric calibration: what ``optics calibrate`` prints and
saves after every calibration."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .._checks import InputError
from ._ball import ball_gradients, ball_press_metrics, normal_angle_deg
from ._reconstructor import DepthReconstructor

__all__ = ["CIRCLE_ERROR", "CircleError", "calibration_accuracy", "cap_prediction", "edge_cut",
           "holdout_presses", "max_tilt_deg", "press_folds"]


@dataclass(frozen=True)
class CircleError:
    """How far a contact circle may lie from the true contact, as fractions of its radius r.

    Attributes
    ----------
    centre_sd, radius_sd : float
        The random part: sd of the centre's offset along each axis (fraction of r) and
        of the radius's relative error, drawn independently for every press.
    centre_bias, radius_bias : float
        The systematic part, shared by every press: the centre off by up to
        `centre_bias` r along either axis, the radius by up to a `radius_bias` fraction
        either way (evaluated at those bounds).
    source : str
        Where the figures were measured.
    """

    centre_sd: float
    radius_sd: float
    centre_bias: float
    radius_bias: float
    source: str


#: The contact-edge detector (``detect_contact_circles(edge='contact')``) against the 48
#: hand-annotated circles of ``taxim``'s real GelSight presses (no code of ours drew them):
#: centre off by +0.002 and +0.021 r (mean, x and y) with sds 0.033 and 0.025 r, radius
#: 1.002 with sd 0.023 (``python benchmarks/bench_circle_uncertainty.py``, 2026-11-25).
#: Taken up: 0.035 r and 0.025 random, 0.025 r and 0.025 shared. On Taxim's renders with its
#: shadows the detector does about twice worse (centre sd 0.054 and 0.059 r, radius +6 %
#: sd 10 %, the same benchmark), so on a sensor with strong shading these are too narrow.
CIRCLE_ERROR = CircleError(
    centre_sd=0.035, radius_sd=0.025, centre_bias=0.025, radius_bias=0.025,
    source="the contact-edge detector against taxim's 48 hand-annotated real GelSight "
           "circles (benchmarks/bench_circle_uncertainty.py)")


def edge_cut(centers_px: np.ndarray, radii_px: np.ndarray, shape: tuple[int, int]
             ) -> np.ndarray:
    """Whether each contact disc reaches past the image edge.

    Parameters
    ----------
    centers_px : (N, 2) float ndarray
        Circle centres (x, y), px.
    radii_px : (N,) float ndarray
        Circle radii, px.
    shape : (H, W)
        Image size.

    Returns
    -------
    cut : (N,) bool ndarray
        True where part of the disc lies outside the pixel centres 0..W-1,
        0..H-1: its rim, and so its steepest slopes, are not in the frame.
    """
    c = np.asarray(centers_px, np.float64).reshape(-1, 2)
    r = np.asarray(radii_px, np.float64).reshape(-1)
    h, w = shape
    return ((c[:, 0] - r < 0) | (c[:, 0] + r > w - 1) | (c[:, 1] - r < 0)
            | (c[:, 1] + r > h - 1))


def holdout_presses(centers_px: np.ndarray, radii_px: np.ndarray,
                    ball_radius_px: np.ndarray, shape: tuple[int, int],
                    share: float = 0.25) -> np.ndarray:
    """Presses held out of training for the accuracy report, stratified over the pad and
    the ball sizes.

    Only presses the report can score are held out: those whose contact disc lies
    inside the image (:func:`edge_cut`; the others are always trained on). Each ball
    size's such presses are ordered along the pad (in bands of a third of its height,
    left to right, alternate bands right to left), and every ``1 / share``-th of them is
    held out starting from the middle of the first stride, so the held-out presses
    spread over the pad and every ball size with two or more such presses has at least
    one.

    Parameters
    ----------
    centers_px : (N, 2) float ndarray
        Contact-circle centres (x, y), px.
    radii_px : (N,) float ndarray
        Contact-circle radii, px.
    ball_radius_px : (N,) float ndarray
        Each press's ball radius (the strata).
    shape : (H, W)
        Image size.
    share : float, default 0.25
        The share held out, 0 < share < 1.

    Returns
    -------
    held_out : (N,) bool ndarray

    Raises
    ------
    InputError
        For a share outside (0, 1) or arrays of different lengths.
    """
    if not 0 < share < 1:
        raise InputError(f"the held-out share must lie between 0 and 1, got {share!r}")
    held = np.zeros(len(np.asarray(centers_px).reshape(-1, 2)), bool)
    stride = 1.0 / share
    for order in _snake(centers_px, radii_px, ball_radius_px, shape):
        if order.size < 2:
            continue
        picks = np.arange(stride / 2 - 0.5, order.size, stride).astype(int)
        held[order[np.unique(np.clip(picks, 0, order.size - 1))]] = True
    return held


def press_folds(centers_px: np.ndarray, radii_px: np.ndarray, ball_radius_px: np.ndarray,
                shape: tuple[int, int], k: int) -> np.ndarray:
    """Cross-validation folds of ball presses, spread over the pad and the ball sizes as
    :func:`holdout_presses` spreads its held-out presses.

    Parameters
    ----------
    centers_px, radii_px, ball_radius_px, shape
        As :func:`holdout_presses`.
    k : int
        Folds (>= 2).

    Returns
    -------
    fold : (N,) int64 ndarray
        Each press's fold, 0 to k - 1, round the snake over the pad within each ball size;
        -1 for a press whose disc runs past the image edge (:func:`edge_cut`: never scored,
        always trained on).

    Raises
    ------
    InputError
        For k < 2 or arrays of different lengths.
    """
    if k < 2:
        raise InputError(f"cross-validation needs at least two folds, got {k}")
    fold = np.full(len(np.asarray(centers_px).reshape(-1, 2)), -1, np.int64)
    start = 0
    for order in _snake(centers_px, radii_px, ball_radius_px, shape):
        fold[order] = (start + np.arange(order.size)) % k
        start += order.size
    return fold


def _snake(centers_px, radii_px, ball_radius_px, shape: tuple[int, int]) -> list[np.ndarray]:
    """For each ball size, its presses whose disc lies inside the image, in order along a
    snake over the pad (bands of a third of its height, left to right, alternate bands
    right to left). Raises InputError for arrays of different lengths."""
    c = np.asarray(centers_px, np.float64).reshape(-1, 2)
    ball = np.asarray(ball_radius_px, np.float64).reshape(-1)
    r = np.asarray(radii_px, np.float64).reshape(-1)
    if ball.size != len(c) or r.size != len(c):
        raise InputError(f"{len(c)} centres, {r.size} radii and {ball.size} ball radii: one "
                         "each per press")
    inside = ~edge_cut(c, r, shape)
    band = np.clip((c[:, 1] * 3 // max(shape[0], 1)).astype(int), 0, 2)
    x = np.where(band % 2 == 0, c[:, 0], -c[:, 0])
    out = []
    for b in np.unique(ball):
        idx = np.flatnonzero((ball == b) & inside)
        out.append(idx[np.lexsort((x[idx], band[idx]))])
    return out


def cap_prediction(caps: np.ndarray, confidence: float = 0.95) -> dict | None:
    """The inner cap error a new press is expected to read, from presses scored alike.

    The presses' inner caps (:func:`_inner_cap`, relative errors) taken as draws of one
    normal distribution: their mean, and the prediction interval a new press's cap lies
    in with probability `confidence`, ``mean +- t_(n-1) s sqrt(1 + 1/n)`` (s the sample
    sd; the normal-theory prediction interval for one future observation, as in Hahn and
    Meeker, Statistical Intervals, Wiley 1991). The scoring circles' shared error
    (``circle_uncertainty``) is not in it.

    Parameters
    ----------
    caps : (N,) array_like of float
        The presses' inner caps (NaN left out).
    confidence : float, default 0.95

    Returns
    -------
    dict or None
        ``mean``, ``low``, ``high``, ``n``, ``confidence`` and ``sd`` (s, one press's
        scatter); None with fewer than three finite caps.

    Raises
    ------
    InputError
        For a confidence outside (0, 1).
    """
    if not 0 < confidence < 1:
        raise InputError(f"confidence must lie in (0, 1), got {confidence!r}")
    c = np.asarray(caps, np.float64)
    c = c[np.isfinite(c)]
    if c.size < 3:
        return None
    m, sd = float(c.mean()), float(c.std(ddof=1))
    half = float(stats.t.ppf(0.5 + confidence / 2, c.size - 1)) * sd * math.sqrt(1 + 1 / c.size)
    return {"mean": m, "low": m - half, "high": m + half, "n": int(c.size),
            "confidence": float(confidence), "sd": sd}


def _inner_cap(height_px: np.ndarray, d: np.ndarray, radius: float, ball_px: float,
               fraction: float = 0.8) -> float:
    """The inner cap's depth over the ball's, less one: the height at the disc's centre
    (mean within 1.5 px) above the median on the circle at `fraction` of the radius,
    against the sphere's drop there, R - sqrt(R^2 - (fraction r)^2). Inside the contact
    the ball surely touches the gel, so the rim's unknown shape does not enter. `d`: each
    pixel's distance from the disc's centre, px (:func:`_distances`)."""
    rho = fraction * radius
    middle = d <= 1.5
    ring = np.abs(d - rho) <= 1.0
    if not middle.any() or not ring.any():
        return math.nan
    drop = ball_px - math.sqrt(max(ball_px * ball_px - rho * rho, 0.0))
    return float((height_px[middle].mean() - np.median(height_px[ring])) / drop - 1.0)


def max_tilt_deg(radius_px: np.ndarray | float, ball_radius_px: np.ndarray | float
                 ) -> np.ndarray:
    """Tilt of a sphere of radius R at distance r from its axis, degrees:
    ``atan(r / sqrt(R^2 - r^2))`` (the slope at a contact disc's rim)."""
    r = np.asarray(radius_px, np.float64)
    big = np.asarray(ball_radius_px, np.float64)
    return np.degrees(np.arctan2(r, np.sqrt(np.maximum(big * big - r * r, 0.0))))


def _distances(shape: tuple[int, int], centre: np.ndarray) -> np.ndarray:
    """(H, W) distance of each pixel from `centre` (x, y), px."""
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]]
    return np.hypot(xx - centre[0], yy - centre[1])


def _deepest_point(height_px: np.ndarray, d: np.ndarray, radius: float,
                   ball_px: float) -> float:
    """Reconstructed cap depth over the ball's, less one: the height at the disc's deepest
    point above the median height on its rim circle, against R - sqrt(R^2 - r^2). `d`:
    each pixel's distance from the disc's centre, px (:func:`_distances`)."""
    inside = d <= radius
    ring = np.abs(d - radius) <= 1.0
    if not inside.any() or not ring.any():
        return math.nan
    cap = ball_px - math.sqrt(max(ball_px * ball_px - radius * radius, 0.0))
    return float((height_px[inside].max() - np.median(height_px[ring])) / cap - 1.0)


def _inner_scores(gx: np.ndarray, gy: np.ndarray, height_px: np.ndarray, centre: np.ndarray,
                  radius: float, ball_px: float, d: np.ndarray | None = None
                  ) -> tuple[float, float]:
    """The mean normal-angle error inside 0.8 of the radius (deg; as
    :func:`ball_press_metrics` gives it there) and the inner cap's relative error
    (:func:`_inner_cap`) of one press for one circle. `d`: the pixels' distances from
    `centre` (:func:`_distances`), computed when not given."""
    tgx, tgy, inside = ball_gradients(gx.shape, centre, 0.8 * radius, ball_px)
    if not inside.any():
        return math.nan, math.nan
    angle = float(normal_angle_deg(gx[inside], gy[inside], tgx[inside], tgy[inside]).mean())
    if d is None:
        d = _distances(height_px.shape, centre)
    return angle, _inner_cap(height_px, d, radius, ball_px)


def _circle_propagation(maps: list[tuple[np.ndarray, np.ndarray, np.ndarray]],
                        centres: np.ndarray, radii: np.ndarray, ball_px: float,
                        err: CircleError, nominal: np.ndarray, draws: int = 16,
                        seed: int = 0) -> dict:
    """How the circles' own error moves the median inner angle and inner cap.

    Random: `draws` sets of circles, each press's centre and radius drawn about its
    own with `err`'s sds (seeded); the sd of the medians over the sets. Systematic:
    every circle moved at once to each bound of `err` (centre along +-x and +-y,
    radius scaled either way); the largest change of the medians from `nominal` (the
    median angle and inner cap on the circles as given).
    """
    def medians(cs: np.ndarray, rs: np.ndarray) -> np.ndarray:
        sc = np.array([_inner_scores(gx, gy, hp, c, r, ball_px)
                       for (gx, gy, hp), c, r in zip(maps, cs, rs, strict=True)])
        return np.nanmedian(sc, axis=0)

    nominal = np.asarray(nominal, np.float64)
    rng = np.random.default_rng(seed)
    rand = np.array([medians(centres + rng.normal(0.0, err.centre_sd, centres.shape)
                             * radii[:, None],
                             radii * (1.0 + rng.normal(0.0, err.radius_sd, radii.shape)))
                     for _ in range(draws)])
    shifts = [(np.array([sx, sy]) * err.centre_bias, 1.0) for sx, sy in
              ((1, 0), (-1, 0), (0, 1), (0, -1))]
    shifts += [(np.zeros(2), 1.0 + err.radius_bias), (np.zeros(2), 1.0 - err.radius_bias)]
    sys_ = np.array([medians(centres + d[None, :] * radii[:, None], radii * k)
                     for d, k in shifts])
    spread = np.nanstd(rand, axis=0, ddof=1)
    worst = np.nanmax(np.abs(sys_ - nominal[None, :]), axis=0)
    return {"normal_angle_08_deg": {"random_sd": float(spread[0]),
                                    "systematic": float(worst[0])},
            "inner_cap": {"random_sd": float(spread[1]), "systematic": float(worst[1])}}


def calibration_accuracy(recon: DepthReconstructor, frames: np.ndarray,
                         centers_px: np.ndarray, radii_px: np.ndarray,
                         ball_radius_px: np.ndarray, *, trained: np.ndarray,
                         label_fraction: float, circles: str = "given",
                         edge: str | None = None,
                         circle_error: CircleError | None = None) -> dict:
    """Accuracy of a calibration on its ball presses, by ball size.

    Held-out presses (not `trained`) are scored; when every press was trained on, the
    training presses are, and the report says it is in sample. Presses whose disc
    reaches past the image edge are left out and counted.

    Parameters
    ----------
    recon : DepthReconstructor
        The calibration under test (its own reference).
    frames : (N, H, W, 3) uint8 ndarray
        All ball presses, BGR.
    centers_px : (N, 2) float ndarray
        Contact-circle centres (x, y), px.
    radii_px : (N,) float ndarray
        Circle radii, px: the contact's, or the colour edge's (``edge``).
    ball_radius_px : (N,) float ndarray
        Each press's ball radius, px.
    trained : (N,) bool ndarray
        The presses the calibration was trained on.
    label_fraction : float
        The fraction of each radius trained on: the slope range covered is
        read at ``label_fraction * radius`` of the training presses.
    circles : {'given', 'detected'}, default 'given'
        Where the circles came from (written into the report).
    edge : {'contact', 'colour'}, optional
        What the radii mark. ``'contact'`` (given circles; circles detected at
        the contact edge, :func:`locate_contact_edge`): they are scored as
        they are. ``'colour'`` (circles detected at the colour edge, outside
        the contact): scored at ``label_fraction`` of themselves, the contact
        the calibration assumed. Default: ``'contact'`` for given circles,
        ``'colour'`` for detected ones (the behaviour before the contact edge).
    circle_error : CircleError, optional
        The scoring circles' own error (:data:`CIRCLE_ERROR` for detected
        contact-edge circles). Given, each ball's entry gains
        ``circle_uncertainty``: for ``normal_angle_08_deg`` and ``inner_cap``,
        the sd of the median from the circles' random error and the largest
        change from their systematic error (:func:`_circle_propagation`), and
        the report ``circle_error`` (the figures and their source). None
        (default): not propagated, ``circle_error`` None.

    Returns
    -------
    report : dict
        JSON-ready: ``in_sample`` (bool), ``circles``, ``edge``, ``label_fraction``, and
        ``balls``, one entry per ball radius (mm-free, px): ``ball_radius_px``,
        ``n_scored``, ``n_edge_cut`` (left out), ``normal_angle_deg`` (median
        over presses of the mean normal-angle error inside 0.9 of the radius),
        ``deepest_point`` (median relative error of the cap depth: reconstructed
        height at the deepest point above the rim, over R - sqrt(R^2 - r^2)),
        ``inner_cap`` (the same for the centre against 0.8 of the radius, where
        the ball surely touches: :func:`_inner_cap`), ``normal_angle_08_deg``
        (as ``normal_angle_deg``, inside 0.8 of the radius), ``presses`` (the
        scored presses' indices),
        ``trained_tilt_deg`` (the steepest slope the training labels reached,
        at ``label_fraction`` of the radius) and ``rim_tilt_deg`` (the steepest
        slope of the scored presses' rims), ``shape_rms_px``,
        ``fitted_radius_px`` and ``fitted_radius_std_px`` (means over the
        scored presses, as :func:`evaluate_ball_presses` gives them, inside 0.9
        of the radius), ``circle_uncertainty`` (with `circle_error`, else None);
        None where nothing is scored. ``circle_error``: the figures propagated
        and their source, or None.
    """
    frames = np.asarray(frames)
    centers = np.asarray(centers_px, np.float64)
    radii = np.asarray(radii_px, np.float64)
    if edge is None:
        edge = "colour" if circles == "detected" else "contact"
    if edge not in ("contact", "colour"):
        raise InputError(f"edge must be 'contact' or 'colour', got {edge!r}")
    colour_edge = edge == "colour"
    if colour_edge:
        # the colour edge lies outside the contact: the calibration took label_fraction of
        # it as the contact, and so does its score
        radii = label_fraction * radii
    ball = np.broadcast_to(np.asarray(ball_radius_px, np.float64), radii.shape)
    trained = np.asarray(trained, bool)
    in_sample = bool(trained.all())
    scored = trained if in_sample else ~trained
    cut = edge_cut(centers, radii, frames.shape[1:3])
    mm = recon.calibration.mm_per_px
    balls = []
    for b in np.unique(ball):
        same = ball == b
        use = np.flatnonzero(same & scored & ~cut)
        entry = {"ball_radius_px": float(b), "n_scored": int(use.size),
                 "n_edge_cut": int(np.count_nonzero(same & scored & cut)),
                 "trained_tilt_deg": (float(max_tilt_deg(
                     radii[same & trained] * (1.0 if colour_edge else label_fraction),
                     b).max())
                                      if np.any(same & trained) else None),
                 "presses": [int(i) for i in use],
                 "normal_angle_deg": None, "normal_angle_08_deg": None,
                 "deepest_point": None, "inner_cap": None, "inner_cap_expected": None,
                 "normal_angle_08_per_press_deg": [], "inner_cap_per_press": [],
                 "rim_tilt_deg": None,
                 "shape_rms_px": None, "fitted_radius_px": None, "fitted_radius_std_px": None}
        entry["circle_uncertainty"] = None
        if use.size:
            per, inner, deepest, caps, maps = [], [], [], [], []
            for i in use:       # each press reconstructed once, for every measure
                gx, gy = recon.gradients(frames[i])
                height_px = recon(frames[i]) / mm
                if circle_error is not None:
                    maps.append((gx, gy, height_px))
                per.append(ball_press_metrics(gx, gy, height_px, centers[i], 0.9 * radii[i],
                                              float(b)))
                d = _distances(height_px.shape, centers[i])
                angle08, cap = _inner_scores(gx, gy, height_px, centers[i], radii[i],
                                             float(b), d)
                inner.append(angle08)
                caps.append(cap)
                deepest.append(_deepest_point(height_px, d, radii[i], float(b)))
            fitted = np.array([p.fitted_radius_px for p in per])
            entry["normal_angle_deg"] = float(np.median([p.normal_angle_deg for p in per]))
            entry["normal_angle_08_deg"] = float(np.median(inner))
            entry["deepest_point"] = float(np.nanmedian(deepest))
            entry["inner_cap"] = float(np.nanmedian(caps))
            entry["inner_cap_expected"] = cap_prediction(caps)
            # each scored press's own, in `presses` order: what pooled folds take their
            # medians of (:func:`~tactilevision.optics.pooled_cost`)
            entry["normal_angle_08_per_press_deg"] = [float(v) for v in inner]
            entry["inner_cap_per_press"] = [float(v) for v in caps]
            entry["rim_tilt_deg"] = float(max_tilt_deg(radii[use], b).max())
            entry["shape_rms_px"] = float(np.mean([p.shape_rms_px for p in per]))
            entry["fitted_radius_px"] = float(fitted.mean())
            entry["fitted_radius_std_px"] = float(fitted.std())
            if circle_error is not None:
                entry["circle_uncertainty"] = _circle_propagation(
                    maps, centers[use], radii[use], float(b), circle_error,
                    nominal=np.array([np.nanmedian(inner), entry["inner_cap"]]))
        balls.append(entry)
    return {"in_sample": in_sample, "circles": circles, "edge": edge,
            "label_fraction": float(label_fraction),
            "circle_error": (None if circle_error is None else
                             {"centre_sd_r": circle_error.centre_sd,
                              "radius_sd": circle_error.radius_sd,
                              "centre_bias_r": circle_error.centre_bias,
                              "radius_bias": circle_error.radius_bias,
                              "source": circle_error.source}),
            "balls": balls}
