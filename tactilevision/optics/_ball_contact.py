"""A ball's contact circle on frames that are not clean: a textured ball, a drifted
illumination, a contact that covers much of the pad or runs past the image's edge.

A ball pressed into the gel tilts its surface radially: the tilt points away from the
contact's centre everywhere (the ball's cap inside the contact, the sink-in outside) and is
largest at the rim. The colour change against the reference is, to first order, linear in
the tilt, so on every ring about the true centre it varies with the ring's angle theta as
``B cos(theta) + C sin(theta)``: a dipole. A ball's texture (dimples, knurling, a print)
tilts the gel in every direction and a drift of the illumination changes every pixel
alike, so neither projects on the dipole consistently; they hide a contact from a
threshold of the colour change's magnitude (the old detector's blob: on a dimpled golf
ball it took a bright patch of dimples for the contact) but not from the dipole.

The steps (:func:`find_contact_circle`):

1. **Drift.** The frame less the reference as the frame's camera sees it: per channel
   ``frame = g reference + o`` fitted by trimmed least squares (:func:`drift_free_change`),
   refitted without the contact once it is found. A global change of brightness or colour
   (exposure, white balance, an LED's output) is no contact.
2. **Centre.** The dipole's energy summed over rings about every candidate centre (a
   circular transform by FFT on a coarse copy, centres up to 30 % of the image outside
   it): its peak is near the contact's centre (within 5 to 10 % of the radius on the
   renders of ``tests/test_ball_texture.py``; the colour response is not symmetric).
3. **Colour edge.** Rays from the centre; on each, the steepest fall of the colour change's
   magnitude in a window about the rim (first the radius where the dipole's amplitude
   peaks, then the circle's own); a circle fitted to those points (robust least squares,
   the 60 % nearest), the centre moved at most 15 % of the radius a round, until it stays.
   A ray that leaves the image before the window's end is not used.
4. **Contact edge.** The radial profile of the colour change about that centre (the median
   over 360 rays at each radius: a texture, which varies round the rim, does not move a
   median) and its shoulder before the fall (:func:`profile_radius`), with its bootstrap
   uncertainty over the rays; checked against the circle read ray by ray
   (:func:`~tactilevision.optics.locate_contact_edge`), their disagreement added to it.
5. **Checks** (:class:`ContactCircle`): the rim's share inside the image
   (:data:`MIN_RIM_IN_FRAME`), its contrast against the pad outside
   (:data:`MIN_RIM_CONTRAST`; against the camera's noise where too little pad lies beyond
   the contact to read the pad's own, :data:`PAD_SHARE`; a lower one where the change falls
   past the rim on nearly every ray, :data:`STEADY_RIM_CONTRAST`) and, sector by sector,
   that the change falls past it (:data:`MAX_SECTORS_BEYOND_RIM`, fewer sectors where it
   falls on fewer rays, :data:`MAX_SECTORS_BEYOND_UNSTEADY_RIM`): a circle inside a larger
   contact whose own rim is mostly outside the image has an edge where it touches that rim
   and none elsewhere.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np
from scipy import fft as sfft
from scipy.ndimage import gaussian_filter1d, map_coordinates, maximum_filter

from .._checks import InputError, check_array
from ._circles import fit_circle, locate_contact_edge

__all__ = ["MAX_SECTORS_BEYOND_RIM", "MAX_SECTORS_BEYOND_UNSTEADY_RIM", "MIN_RIM_CONTRAST",
           "MIN_RIM_IN_FRAME", "PAD_SHARE", "PROFILE_AGREEMENT", "PROFILE_RULES",
           "PROFILE_SHOULDER", "STEADY_RIM_CONTRAST", "STEADY_RIM_SHARE",
           "ContactCircle",
           "colour_edge_circle", "drift_free_change", "find_contact_circle", "profile_radius",
           "rim_drop", "rim_fall_share", "rim_in_frame", "sectors_beyond_rim"]

#: The least share of a contact circle's rim that must lie inside the image for its radius
#: to be read. A rim cut by the image's edge is fitted on the arc that is left; on the renders
#: of ``tests/test_ball_texture.py`` (dev seeds) circles with less than 70 % of their rim in
#: view were read 10 to 30 % wrong when their arc held a texture.
MIN_RIM_IN_FRAME = 0.7
#: The least contrast of the rim, in noise sigmas of the pad outside the contact: the
#: radial profile at the contact edge less at 1.3 colour-edge radii, over 1.4826 MAD of the
#: colour change beyond 1.6 radii (where less than :data:`PAD_SHARE` of the image lies
#: there, the drop past the rim over the camera's noise, :func:`rim_drop`). On the real
#: presses of ``taxim``'s GelSight, GelSlim 3.0 and the GelSight Mini it is 10 to 86 (all 184;
#: ``benchmarks/bench_ball_circles_real.py``); on renders of
#: ``tests/test_ball_texture.py`` (dev seeds) 3.8 to 10 where the circle was right and -0.3
#: to 3.5 where it was put on the background or on half a rim.
MIN_RIM_CONTRAST = 4.0
#: A rim of lower contrast is trusted where it stands at least this many noise sigmas (of
#: the pad or the camera, as :data:`MIN_RIM_CONTRAST`) and the colour change falls past it
#: on at least :data:`STEADY_RIM_SHARE` of the rays (:func:`rim_fall_share`): a contact's
#: edge falls all round, a circle on a print, a texture's edge or the background on about
#: half to three quarters of the rays. On the renders of ``tests/test_ball_texture.py``,
#: seeds 2000 to 2439 (200 presses, seen when the rule was set), the circles refused at 3
#: to 4 sigmas that fell on 90 % of their rays or more were all within 10 % of the true
#: radius (nine); of the 43 circles more than 10 % off, none stood at 3 to 4 sigmas with
#: its change falling on 90 % of its rays (seeds 2007 and 2128, which a plain 3-sigma rule
#: let through, fall on 60 and 78 %).
STEADY_RIM_CONTRAST = 3.0
#: See :data:`STEADY_RIM_CONTRAST`.
STEADY_RIM_SHARE = 0.9
#: The least share of the image beyond 1.6 radii of a circle for the pad's own noise to be
#: read there (the share :func:`drift_free_change` needs to fit the drift without the
#: contact; with less, the drift is fitted on the contact too and what is left on the pad
#: beyond it is that fit's error, not the pad's). Where less lies beyond a circle, its rim's
#: contrast is the median over the rays of the change's drop from 0.9 to 1.0 radii to 1.2 to
#: 1.4 radii (:func:`rim_drop`), in sigmas of the camera's pixel noise, against the same
#: :data:`MIN_RIM_CONTRAST`. On the renders of ``tests/test_ball_texture.py``, seeds 2000 to
#: 2039, 2100 to 2139 and 2200 to 2239 (seen when the rule was set), the pad's rule refused
#: 25 circles within their bound whose pad beyond was 0 to 12 % of the image (contacts of
#: 107 px or more, at 1.3 to 3.8 pad sigmas); the drop read 4.5 to 13.5 camera sigmas on 21
#: of those and 1.2 to 2.3 on the three wrong circles whose pad was as small.
PAD_SHARE = 0.2
#: The largest share of a circle's sectors (12 about its centre, those the image shows both
#: sides of the rim in) where the colour change just past the rim (median over 1.15 to 1.4
#: radii) stays at :data:`BEYOND_RIM_LEVEL` or more of its level just inside (0.75 to 0.95
#: radii). A contact's edge falls in every direction; a circle put inside a larger contact,
#: tangent to the part of its rim the image shows, falls only where it touches. On the
#: renders of ``tests/test_ball_texture.py``, seeds 2000 to 2039 (seen when the rule was
#: set): 0 to 0.40 of the sectors where the circle was within 10 % of the truth, 0.40 to
#: 0.92 where it was a larger contact's inner part (six of seven over 0.5). On the real
#: presses of ``taxim``'s GelSight, GelSlim 3.0 and the GelSight Mini (184 circles) 0 to
#: 0.50, one of taxim's at 0.50: none refused, the margin thin there
#: (``benchmarks/bench_ball_circles_real.py``).
MAX_SECTORS_BEYOND_RIM = 0.5
#: See :data:`MAX_SECTORS_BEYOND_RIM`.
BEYOND_RIM_LEVEL = 0.8
#: The largest share of sectors (:data:`MAX_SECTORS_BEYOND_RIM`) where the colour change
#: does not fall past a rim that falls on fewer than :data:`STEADY_RIM_SHARE` of its rays:
#: the two signs of a circle inside a larger contact together (with 12 sectors: half of
#: them or more). On the renders of ``tests/test_ball_texture.py``, seeds 2000 to 2439 and
#: 2700 to 2739 (seen when it was set), two circles inside contacts the image cuts (seeds
#: 2304 and 2714, 35 and 45 % small) were trusted at 0.50 of their sectors with the change
#: falling on 79 and 81 % of their rays; the rule refuses them, and one circle 4 % small
#: (seed 2728, 0.50 and 87 %). On the 184 real presses of
#: ``benchmarks/bench_ball_circles_real.py`` the sectors' share is at most 0.42 (one of
#: ``taxim``'s, its change falling on 82 % of the rays: the margin thin), none refused.
MAX_SECTORS_BEYOND_UNSTEADY_RIM = 0.45

#: The radial profile's edge and the circle read ray by ray agree when they differ by at
#: most this many of the profile's bootstrap standard deviations ...
PROFILE_AGREEMENT = 3.0
#: ... plus this share of the radius: the two rules read the same edge differently (on the 48
#: real GelSight presses of ``taxim`` the profile's edge lies 0.4 % outside the rays',
#: median, 5 to 95 % range -1.5 to +3.4 %). Beyond, half their difference is added to the
#: radius's uncertainty.
PROFILE_RULES = 0.035
#: The radial profile's contact edge (:func:`profile_radius`) is the outermost radius
#: before its fall at which it lies at most this share of the rim's contrast below its
#: peak. A share of the contrast, not of the peak (the rule of
#: :func:`~tactilevision.optics.locate_contact_edge`, 3 % of the peak): the magnitude's
#: floor outside the contact (noise, a drift's rest) raises the peak but not the rim. On
#: the 48 hand-annotated real GelSight presses of ``taxim``: 1.007 +- 0.028 of the
#: annotated radius, 45 within 5 % (3 % of the peak: 0.992 +- 0.027, 43); on renders of
#: ``tests/test_ball_texture.py``, seeds 2000 to 2439 (200 presses, seen when it was set),
#: 180 right answers and 2 confidently wrong (3 % of the peak: 179 and 4; 5 % of the
#: contrast 181 and 3, 10 % 179 and 1 but 1.017 on the real presses, 41 within 5 %): large
#: contacts of shallow tilt have a broad peak, and 3 % of it fell 6 to 15 % inside the
#: rim on dimpled balls.
PROFILE_SHOULDER = 0.075
_SHORT_SIDE = 64          # px: the coarse copy the centre is looked for on
_RAYS = 180
_SECTORS = 12


@dataclass(frozen=True)
class ContactCircle:
    """A ball's contact circle in one frame, with what it rests on.

    Attributes
    ----------
    centre_px : (2,) float64 ndarray
        (x = column, y = row), px.
    radius_px, radius_sd_px : float
        The contact edge, px, and the standard deviation its reading carries beyond the
        detector's own error (:data:`~tactilevision.optics.CIRCLE_ERROR`): the radial
        profile's edge about the centre and its bootstrap sd, with half the difference from
        the circle read ray by ray added in quadrature where the two disagree.
    colour_radius_px : float
        The colour edge: the circle fitted to where the colour change falls fastest going
        out along each ray, px.
    ray_radius_px, profile_radius_px, profile_sd_px : float
        The two readings of the contact edge: ray by ray, and the radial profile's (its
        bootstrap sd), px (NaN where not read).
    rim_contrast : float
        The rim's contrast in noise sigmas of the pad outside the contact (see
        :data:`MIN_RIM_CONTRAST`), or of the camera where too little pad lies beyond it
        (:data:`PAD_SHARE`); NaN where it cannot be read.
    rim_in_frame : float
        Share of the circle's rim inside the image.
    edge_scatter : float
        Robust sd (1.4826 MAD) of the colour edge's points about their circle, as a share
        of its radius (a measure of the edge's clarity; no check is made on it: real
        sensors' anisotropic colour response scatters it by 4 to 9 % of the radius,
        median by set).
    problems : tuple of str
        Why the circle cannot be trusted (empty when it can): each one sentence.
    notes : tuple of str
        What was done that a reader should know (the profile's edge used).
    sectors_beyond_rim : float
        Share of the sectors seen where the colour change past the rim stays at
        :data:`BEYOND_RIM_LEVEL` of its level inside (see :data:`MAX_SECTORS_BEYOND_RIM`);
        NaN where fewer than 4 sectors show both sides.
    rim_fall_share : float
        Share of the rays on which the colour change falls past the rim
        (:func:`rim_fall_share`; see :data:`STEADY_RIM_CONTRAST`); NaN where fewer than
        24 rays reach past 1.2 radii.
    """

    centre_px: np.ndarray
    radius_px: float
    radius_sd_px: float
    colour_radius_px: float
    ray_radius_px: float
    profile_radius_px: float
    profile_sd_px: float
    rim_contrast: float
    rim_in_frame: float
    edge_scatter: float
    problems: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    sectors_beyond_rim: float = float("nan")
    rim_fall_share: float = float("nan")

    @property
    def trusted(self) -> bool:
        """True when no check found a problem."""
        return not self.problems


def drift_free_change(frame: np.ndarray, reference: np.ndarray, *, sigma: float = 1.5,
                      exclude: np.ndarray | None = None) -> np.ndarray:
    """The frame's colour change against the reference, a global drift taken off.

    Each channel of the frame is fitted as ``g reference + o`` (gain and offset: the
    camera's exposure and white balance, an LED's output) by least squares over the pixels
    nearest the fit (four rounds, each keeping the half of the pixels with the smallest
    residuals, on every third row and column), and the change is the frame less that fit.
    Without a drift, g = 1 and o is the median difference (the old rule).

    Parameters
    ----------
    frame, reference : (H, W, 3) uint8 ndarray
        BGR.
    sigma : float, default 1.5
        Gaussian blur (px) of both before the difference (0: none).
    exclude : (H, W) bool ndarray, optional
        Pixels left out of the fit (a contact found before); ignored where it would leave
        less than :data:`PAD_SHARE` of the image.

    Returns
    -------
    change : (H, W, 3) float32 ndarray
        Grey levels.
    """
    frame = check_array(frame, "frame", [("H", "W", 3)], dtype=np.uint8)
    reference = check_array(reference, "reference", [frame.shape], dtype=np.uint8)
    if sigma > 0:
        frame = cv2.GaussianBlur(frame, (0, 0), sigma)
        reference = cv2.GaussianBlur(reference, (0, 0), sigma)
    f = frame.astype(np.float32)
    r = reference.astype(np.float32)
    use = np.ones(frame.shape[:2], bool)
    if exclude is not None and np.count_nonzero(~exclude) >= PAD_SHARE * exclude.size:
        use = ~exclude
    use = use[::3, ::3]
    change = np.empty_like(f)
    for c in range(3):
        x = r[::3, ::3, c][use].astype(np.float64)
        y = f[::3, ::3, c][use].astype(np.float64)
        a = np.stack([x, np.ones_like(x)], axis=1)
        keep = np.ones(y.size, bool)
        for _ in range(4):
            sol = np.linalg.lstsq(a[keep], y[keep], rcond=None)[0]
            res = np.abs(y - a @ sol)
            keep = res <= np.percentile(res, 50)
        change[..., c] = f[..., c] - (np.float32(sol[0]) * r[..., c] + np.float32(sol[1]))
    return change


def _magnitude(change: np.ndarray) -> np.ndarray:
    return np.sqrt(np.sum(change * change, axis=-1))


def _chroma(change: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """The colour change's magnitude across the reference's colour at each pixel: a change
    of brightness alone (a print seen through the gel, a shadow, the rest of a drift)
    scales the three channels together and drops out; a tilt changes the colour, the
    lights coming from different sides."""
    r = reference.astype(np.float32) + 1.0
    u = r / np.sqrt(np.sum(r * r, axis=-1, keepdims=True))
    along = np.sum(change * u, axis=-1, keepdims=True)
    return _magnitude(change - along * u)


def _ring_edges(rmax: float) -> np.ndarray:
    """Ring boundaries, px: 1 px wide, then 6 % of the radius."""
    e = [1.5]
    while e[-1] < rmax:
        e.append(e[-1] + max(1.0, 0.06 * e[-1]))
    return np.array(e)


@lru_cache(maxsize=8)
def _ring_kernels(radius: int, shape: tuple[int, int]) -> tuple[tuple[np.ndarray, float], ...]:
    """FFTs of the complex ring kernels exp(i theta) on each ring, and each ring's size."""
    ky, kx = np.mgrid[-radius:radius + 1, -radius:radius + 1].astype(np.float64)
    kr = np.hypot(kx, ky)
    with np.errstate(invalid="ignore", divide="ignore"):
        phase = np.where(kr > 0, (kx + 1j * ky) / kr, 0.0)
    edges = _ring_edges(radius)
    out = []
    for lo, hi in itertools.pairwise(edges):
        ring = (kr >= lo) & (kr < hi)
        # correlation by convolution: the kernel reversed
        out.append((sfft.fft2((phase * ring)[::-1, ::-1], shape), float(ring.sum())))
    return tuple(out)


def _dipole_energy(change: np.ndarray, margin: float = 0.3
                   ) -> tuple[tuple[np.ndarray, np.ndarray], float, int]:
    """The dipole's energy summed over rings about every centre of a coarse copy of
    `change`, two ways: each ring weighed by its size (a large contact's rings count most)
    and each ring's squared amplitude alone (a small, strong contact beside a wide faint
    change counts most). Returns the two maps, the copy's px in image px and the maps'
    margin in copy px."""
    h, w = change.shape[:2]
    f = max(1.0, min(h, w) / _SHORT_SIDE)
    small = cv2.resize(change, (max(8, round(w / f)), max(8, round(h / f))),
                       interpolation=cv2.INTER_AREA).astype(np.float64)
    hh, ww = small.shape[:2]
    pad = int(np.ceil(margin * max(hh, ww)))
    radius = int(np.ceil(0.9 * max(hh, ww)))
    shape = (sfft.next_fast_len(hh + 2 * radius + 1), sfft.next_fast_len(ww + 2 * radius + 1))
    spectra = [sfft.fft2(small[..., c], shape) for c in range(small.shape[2])]
    total = np.zeros(shape)
    amp2 = np.zeros(shape)
    for kernel, size in _ring_kernels(radius, shape):
        ring = np.zeros(shape)
        for s in spectra:
            z = sfft.ifft2(s * kernel)
            ring += z.real ** 2 + z.imag ** 2
        total += ring * (2.0 / size)
        amp2 += ring * (2.0 / size ** 2)
    lo = radius - pad
    cut = (slice(lo, lo + hh + 2 * pad), slice(lo, lo + ww + 2 * pad))
    return (total[cut], amp2[cut]), f, pad


def _seeds(change: np.ndarray, k: int = 2) -> list[tuple[float, float]]:
    """The `k` strongest peaks of each of the dipole's energy maps, as centres in image px
    (those within 3 coarse px of one already taken left out)."""
    maps, f, pad = _dipole_energy(change)
    out: list[tuple[float, float]] = []
    taken: list[tuple[int, int]] = []
    for energy in maps:
        peak = (energy == maximum_filter(energy, size=7)) & (energy > 0)
        ys, xs = np.nonzero(peak)
        for i in np.argsort(energy[ys, xs])[::-1][:k]:
            if any(abs(xs[i] - x) <= 3 and abs(ys[i] - y) <= 3 for x, y in taken):
                continue
            taken.append((xs[i], ys[i]))
            out.append(((xs[i] - pad + 0.5) * f - 0.5, (ys[i] - pad + 0.5) * f - 0.5))
    return out


def _dipole_profile(change: np.ndarray, cx: float, cy: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per 1 px ring about (cx, cy): its radius, its pixel count, and the amplitude of the
    colour change's first angular harmonic (a least-squares fit of A + B cos + C sin)."""
    h, w, k = change.shape
    step = 2 if min(h, w) > 320 else 1
    ch = change[::step, ::step].astype(np.float64)
    yy, xx = np.indices(ch.shape[:2], dtype=np.float64)
    dx, dy = xx * step - cx, yy * step - cy
    rho = np.hypot(dx, dy)
    idx = (rho / step).astype(np.int64).ravel()
    nb = int(idx.max()) + 1
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.where(rho > 0, dx / rho, 0.0).ravel()
        s = np.where(rho > 0, dy / rho, 0.0).ravel()
    v = ch.reshape(-1, k)

    def bc(x):
        return np.bincount(idx, x, minlength=nb)

    n = bc(np.ones_like(c))
    gram = np.stack([np.stack([n, bc(c), bc(s)], -1), np.stack([bc(c), bc(c * c), bc(c * s)], -1),
                     np.stack([bc(s), bc(c * s), bc(s * s)], -1)], -2)
    rhs = np.stack([np.stack([bc(v[:, j]), bc(v[:, j] * c), bc(v[:, j] * s)], -1)
                    for j in range(k)], -1)
    ok = n >= 8
    coef = np.zeros_like(rhs)
    gram = gram + np.eye(3)[None] * 1e-6 * np.maximum(n, 1)[:, None, None]
    coef[ok] = np.linalg.solve(gram[ok], rhs[ok])
    amp = np.sqrt(np.where(ok, np.sum(coef[:, 1:, :] ** 2, axis=(1, 2)) / 2, 0.0))
    return (np.arange(nb) + 0.5) * step, n, amp


def _dipole_peak(change: np.ndarray, cx: float, cy: float) -> float | None:
    """The radius where the dipole's amplitude peaks about (cx, cy), over rings at least
    at least 35 % inside the image (None where none is)."""
    rho, n, amp = _dipole_profile(change, cx, cy)
    ok = (n >= 0.7 * np.pi * rho) & (rho >= 5.0)       # 35 % of the ring in the image
    if not ok.any():
        return None
    smooth = gaussian_filter1d(np.where(ok, amp, 0.0), 1.5)
    return float(rho[int(np.argmax(np.where(ok, smooth, -1.0)))])


def _rays(mag: np.ndarray, cx: float, cy: float, rs: np.ndarray, n_rays: int
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Samples of `mag` along rays from (cx, cy) at radii `rs`: x, y, value, and whether
    the ray is still inside the image there."""
    h, w = mag.shape
    theta = np.linspace(0.0, 2.0 * np.pi, n_rays, endpoint=False)
    xs = cx + np.cos(theta)[:, None] * rs[None, :]
    ys = cy + np.sin(theta)[:, None] * rs[None, :]
    inside = (xs >= 0) & (xs <= w - 1) & (ys >= 0) & (ys <= h - 1)
    run = np.cumprod(inside, axis=1).astype(bool)
    p = map_coordinates(mag, [ys.ravel(), xs.ravel()], order=1, mode="nearest")
    return xs, ys, p.reshape(xs.shape), run


def fit_circle_robust(x: np.ndarray, y: np.ndarray, keep: float = 0.6
                      ) -> tuple[float, float, float]:
    """A circle through points, least squares over the `keep` share nearest it (three
    rounds; :func:`~tactilevision.optics.fit_circle` each)."""
    cx, cy, r = fit_circle(x, y)
    for _ in range(3):
        d = np.abs(np.hypot(x - cx, y - cy) - r)
        sel = d <= max(float(np.percentile(d, 100 * keep)), 0.5)
        cx, cy, r = fit_circle(x[sel], y[sel])
    return cx, cy, r


def _edge_points(mag: np.ndarray, cx: float, cy: float, lo: float, hi: float,
                 need: float) -> tuple[np.ndarray, np.ndarray, float]:
    """On each ray, the steepest fall of `mag` between radii `lo` and `hi`; rays that leave
    the image before `need` (or less than 3 px after the fall) give none. Returns the
    points and the share of rays that gave one."""
    step = 0.5
    rs = np.arange(lo, hi, step)
    if rs.size < 5:
        return np.zeros(0), np.zeros(0), 0.0
    xs, ys, p, run = _rays(mag, cx, cy, rs, _RAYS)
    p = gaussian_filter1d(p, max(1.0, 0.012 * hi / step), axis=1)   # 0.5 px, 1 % of r
    fall = np.gradient(p, axis=1)
    j = np.where(run, fall, np.inf).argmin(axis=1)
    rows = np.arange(_RAYS)
    jn = min(rs.size - 1, int(np.searchsorted(rs, need)))
    ok = (run[:, jn] & run[rows, np.minimum(j + 6, rs.size - 1)] & (fall[rows, j] < 0)
          & (j > 0) & (j < rs.size - 1))
    return xs[rows, j][ok], ys[rows, j][ok], float(ok.mean())


def _colour_edge(change: np.ndarray, mag: np.ndarray, cx: float, cy: float
                 ) -> tuple[float, float, float, float] | None:
    """The colour-edge circle from a centre near it: (cx, cy, r, share of rays used), or
    None where too few rays find an edge."""
    rp = _dipole_peak(change, cx, cy)
    if rp is None:
        return None
    lo, hi, r = 0.8 * rp, 1.45 * rp + 3.0, 1.1 * rp
    used = 0.0
    for _ in range(8):
        px, py, used = _edge_points(mag, cx, cy, lo, hi, 1.12 * r)
        if px.size < 12:
            return None
        ncx, ncy, nr = fit_circle_robust(px, py)
        if not (np.isfinite(nr) and nr > 3):
            return None
        moved = float(np.hypot(ncx - cx, ncy - cy))
        if moved > 0.15 * nr:                  # at most 15 % of the radius a round
            ncx = cx + (ncx - cx) * 0.15 * nr / moved
            ncy = cy + (ncy - cy) * 0.15 * nr / moved
        cx, cy, r = ncx, ncy, nr
        lo, hi = 0.85 * r, 1.18 * r + 3.0
        if moved < 0.25:
            break
    return cx, cy, r, used


def profile_radius(change: np.ndarray, centre_px: tuple[float, float] | np.ndarray,
                   colour_radius_px: float, *, shoulder: float = PROFILE_SHOULDER,
                   floor: float = 0.85, n_boot: int = 40) -> tuple[float, float, float]:
    """The contact edge read from the radial profile of the colour change about a centre.

    The profile is the median over 360 rays of the colour change's magnitude at each
    radius (a ball's texture, which varies round the rim, does not move a median). Its
    contact edge is the shoulder before its steepest fall within 20 % of
    `colour_radius_px`: the outermost radius where it has fallen from the peak nearest
    inside the fall by at most `shoulder` of the rim's contrast (that peak less the
    profile at 1.3 `colour_radius_px`, its last radius seen, or the steepest fall's
    point, the lowest; :data:`PROFILE_SHOULDER`), from the nearest peak, not the largest
    (a texture's bumps deeper in are not the rim's), never inside `floor` times
    `colour_radius_px` (as :func:`~tactilevision.optics.locate_contact_edge`). Its
    uncertainty is the bootstrap over the rays (`n_boot` resamples, a fixed seed). Rays are
    used up to where they leave the image; only rays that reach past the colour edge, and
    radii that half of them see, are used.

    Parameters
    ----------
    change : (H, W, 3) float ndarray
        The colour change (:func:`drift_free_change`).
    centre_px : (2,) float
        (x, y), px.
    colour_radius_px : float
        The colour edge's radius, px.
    shoulder : float, default :data:`PROFILE_SHOULDER`
        The share of the rim's contrast the shoulder may lie below the peak, in (0, 1).
    floor : float, default 0.85
    n_boot : int, default 40

    Returns
    -------
    radius_px, sd_px : float
        NaN where fewer than 24 rays reach past the colour edge or the profile has no fall
        near it.
    contrast : float
        The profile's value at the contact edge less its value at 1.3 `colour_radius_px`
        (or its last radius seen), grey levels.
    """
    if not 0.0 < shoulder < 1.0:
        raise InputError(f"shoulder must lie in (0, 1), got {shoulder!r}")
    mag = _magnitude(np.asarray(change, np.float32))
    cx, cy = float(centre_px[0]), float(centre_px[1])
    rc = float(colour_radius_px)
    step = 0.25
    rs = np.arange(0.5 * rc, 1.4 * rc, step)
    _, _, p, run = _rays(mag, cx, cy, rs, 360)
    near = np.abs(rs - rc) <= 0.2 * rc
    reach = run[:, int(np.flatnonzero(near).max())]       # rays past the colour edge
    p = np.where(run, p, np.nan)[reach]
    nan3 = (float("nan"), float("nan"), float("nan"))
    if p.shape[0] < 24:
        return nan3
    smooth = max(0.5, 0.01 * rc) / step
    smooth_fall = max(0.5, 0.012 * (1.18 * rc + 3.0)) / step    # as the rays' (_edge_points)

    def read(sub: np.ndarray, contrast: bool = False):
        enough = np.mean(np.isfinite(sub), axis=0) >= 0.5
        if not enough.any():
            return float("nan")
        last = int(np.flatnonzero(enough).max())
        win = np.flatnonzero(near[:last + 1] & enough[:last + 1])
        if win.size < 3:
            return float("nan")
        med = np.nanmedian(np.where(enough[None, :last + 1], sub[:, :last + 1], 0.0), axis=0)
        prof = gaussian_filter1d(med, smooth)
        fall = np.gradient(gaussian_filter1d(med, smooth_fall))
        jf = int(win[np.argmin(fall[win])])
        if fall[jf] >= 0:
            return float("nan")
        jp = jf                   # the peak nearest inside the fall
        while jp > 0 and prof[jp - 1] >= prof[jp]:
            jp -= 1
        j = np.arange(prof.size)
        out = min(last, int(np.searchsorted(rs, 1.3 * rc)))
        level = prof[jp] - shoulder * (prof[jp] - min(prof[out], prof[jf]))
        on = (j >= jp) & (j <= jf) & (prof >= level)
        r = max(float(rs[int(np.flatnonzero(on).max())]), floor * rc)
        if contrast:
            return r, float(np.interp(r, rs[:last + 1], prof) - prof[out])
        return r

    got = read(p, contrast=True)
    if not isinstance(got, tuple):
        return nan3
    radius, contrast = got
    if n_boot < 3:
        return radius, float("nan"), contrast
    rng = np.random.default_rng(0)
    boot = np.array([read(p[rng.integers(0, p.shape[0], p.shape[0])]) for _ in range(n_boot)])
    boot = boot[np.isfinite(boot)]
    return radius, float(np.std(boot, ddof=1)) if boot.size > 2 else float("nan"), contrast


def rim_in_frame(centre_px, radius_px: float, shape: tuple[int, int]) -> float:
    """Share of a circle's rim inside the image (its pixel centres), from 720 points."""
    theta = np.linspace(0.0, 2.0 * np.pi, 720, endpoint=False)
    x = float(centre_px[0]) + radius_px * np.cos(theta)
    y = float(centre_px[1]) + radius_px * np.sin(theta)
    h, w = shape
    return float(np.mean((x >= 0) & (x <= w - 1) & (y >= 0) & (y <= h - 1)))


def _pad_noise(mag: np.ndarray, cx: float, cy: float, r: float) -> float:
    """The colour change's noise on the pad beyond 1.6 radii of a circle (1.4826 MAD; the
    quieter half of the image where the circle leaves too little beyond it), >= 0.5."""
    yy, xx = np.indices(mag.shape)
    far = np.hypot(xx - cx, yy - cy) > 1.6 * r
    bg = mag[far] if np.count_nonzero(far) >= 500 else mag[mag <= np.median(mag)]
    return max(1.4826 * float(np.median(np.abs(bg - np.median(bg)))), 0.5)


def _pixel_noise(change: np.ndarray) -> float:
    """The camera's noise in the colour change, grey levels: the robust sd (1.4826 MAD) of
    what a 2 px Gaussian blur takes off each channel, the channels added in quadrature. A
    contact's change, and a ball's texture, are smooth on that scale, so this reads the
    pixels' noise even where a contact covers most of the image (the quieter half of the
    image, the rule before, lay inside such a contact and refused it as no contact)."""
    change = np.asarray(change, np.float32)
    fine = change - cv2.GaussianBlur(change, (0, 0), 2.0)
    per = [1.4826 * float(np.median(np.abs(c - np.median(c)))) for c in np.moveaxis(fine, -1, 0)]
    return float(np.sqrt(np.sum(np.square(per))))


def _rim_contrast(change: np.ndarray, cx: float, cy: float, r: float) -> float:
    """A circle's rim contrast in noise sigmas of the pad beyond it (:func:`profile_radius`'s
    contrast, without its bootstrap; -inf where it cannot be read)."""
    _, _, contrast = profile_radius(change, (cx, cy), r, n_boot=0)
    if not np.isfinite(contrast):
        return -np.inf
    return contrast / _pad_noise(_magnitude(change), cx, cy, r)


def _ray_drops(change: np.ndarray, centre_px, radius_px: float) -> np.ndarray:
    """Each ray's drop of the colour change's magnitude from just inside a circle's rim
    (mean over 0.9 to 1.0 radii) to just past it (mean over 1.2 to 1.4 radii, the samples
    the image shows), grey levels, over 360 rays; only rays that reach past 1.2 radii
    inside the image (at least two samples there)."""
    mag = _magnitude(np.asarray(change, np.float32))
    r = float(radius_px)
    rs = r * np.arange(0.85, 1.4 + 1e-9, 0.025)
    _, _, p, run = _rays(mag, float(centre_px[0]), float(centre_px[1]), rs, 360)
    past = rs >= 1.2 * r
    ok = np.count_nonzero(run[:, past], axis=1) >= 2
    p = np.where(run, p, np.nan)[ok]
    inside = np.mean(p[:, (rs >= 0.9 * r) & (rs <= r)], axis=1)
    return inside - np.nanmean(p[:, past], axis=1)


def rim_drop(change: np.ndarray, centre_px: tuple[float, float] | np.ndarray,
             radius_px: float) -> float:
    """A circle's rim contrast read ray by ray: the median over 360 rays of the colour
    change's magnitude just inside the rim (mean over 0.9 to 1.0 radii) less just past it
    (mean over 1.2 to 1.4 radii, the samples the image shows), grey levels.

    Only rays that reach past 1.2 radii inside the image count. This is the contrast
    :func:`find_contact_circle` reads where too little pad lies beyond the contact to read
    the pad's own noise (:data:`PAD_SHARE`).

    Parameters
    ----------
    change : (H, W, 3) float ndarray
        The colour change (:func:`drift_free_change`), grey levels.
    centre_px : (2,) float
        (x, y), px.
    radius_px : float
        The circle's radius, px.

    Returns
    -------
    float
        Grey levels; NaN where fewer than 24 rays reach past 1.2 radii.
    """
    drops = _ray_drops(change, centre_px, radius_px)
    return float(np.median(drops)) if drops.size >= 24 else float("nan")


def rim_fall_share(change: np.ndarray, centre_px: tuple[float, float] | np.ndarray,
                   radius_px: float) -> float:
    """Share of the rays on which the colour change falls past a circle's rim: those whose
    drop from just inside the rim (0.9 to 1.0 radii) to just past it (1.2 to 1.4 radii) is
    positive, over the 360 rays of :func:`rim_drop` that reach past 1.2 radii.

    A contact's edge falls on every ray (its tilt is largest at the rim all round); a
    circle put on a texture's edge, a print or the background's structure falls on some
    rays and rises on others (about half, for noise alone). :func:`find_contact_circle`
    trusts a rim of lower contrast where it falls on nearly every ray
    (:data:`STEADY_RIM_SHARE`).

    Parameters
    ----------
    change : (H, W, 3) float ndarray
        The colour change (:func:`drift_free_change`), grey levels.
    centre_px : (2,) float
        (x, y), px.
    radius_px : float
        The circle's radius, px.

    Returns
    -------
    float
        The share in [0, 1]; NaN where fewer than 24 rays reach past 1.2 radii.
    """
    drops = _ray_drops(change, centre_px, radius_px)
    return float(np.mean(drops > 0.0)) if drops.size >= 24 else float("nan")


def sectors_beyond_rim(change: np.ndarray, centre_px: tuple[float, float] | np.ndarray,
                       radius_px: float, *, n_sectors: int = 12) -> float:
    """Share of a circle's sectors where the colour change does not fall past its rim.

    In each of `n_sectors` equal sectors about the centre, the median of the colour
    change's magnitude just past the rim (1.15 to 1.4 radii) against just inside it (0.75
    to 0.95 radii); a sector counts where the outside holds :data:`BEYOND_RIM_LEVEL` or
    more of the inside. Only sectors with at least 20 image pixels in both bands are read.

    Parameters
    ----------
    change : (H, W, 3) float ndarray
        The colour change (:func:`drift_free_change`).
    centre_px : (2,) float
        (x, y), px.
    radius_px : float
    n_sectors : int, default 12

    Returns
    -------
    float
        The share in [0, 1]; NaN where fewer than 4 sectors are read.
    """
    mag = _magnitude(np.asarray(change, np.float32))
    yy, xx = np.indices(mag.shape)
    dx, dy = xx - float(centre_px[0]), yy - float(centre_px[1])
    rho = np.hypot(dx, dy) / float(radius_px)
    sector = ((np.arctan2(dy, dx) + np.pi) / (2.0 * np.pi) * n_sectors).astype(int) % n_sectors
    inner = (rho > 0.75) & (rho < 0.95)
    outer = (rho > 1.15) & (rho < 1.4)
    held = []
    for k in range(n_sectors):
        ins, out = mag[inner & (sector == k)], mag[outer & (sector == k)]
        if ins.size >= 20 and out.size >= 20:
            held.append(np.median(out) >= BEYOND_RIM_LEVEL * max(float(np.median(ins)), 1e-6))
    return float(np.mean(held)) if len(held) >= 4 else float("nan")


def colour_edge_circle(frame: np.ndarray, reference: np.ndarray, *, min_change: float = 12.0
                       ) -> tuple[np.ndarray, float, np.ndarray, float]:
    """The colour-edge circle of a ball press (steps 1 to 3 of the module's notes).

    Returns
    -------
    centre : (2,) float64 ndarray
    radius : float
    change : (H, W, 3) float32 ndarray
        The colour change, the drift fitted without the contact.
    rays_used : float

    Raises
    ------
    InputError
        When the frame holds no colour change above `min_change` grey levels and 4 sigmas
        of the camera's pixel noise (99.9th percentile), or no circle is found.
    """
    change = drift_free_change(frame, reference)
    mag = _magnitude(change)
    peak = float(np.percentile(mag, 99.9))
    ref = cv2.GaussianBlur(reference, (0, 0), 1.5)
    noise = _pixel_noise(change)
    if peak < max(min_change, 4.0 * noise):
        raise InputError(f"no contact found in frame (largest colour change {peak:.1f} is "
                         f"below {max(min_change, 4.0 * noise):.1f})")
    mag = _chroma(change, ref)          # the rays read the colour, not the brightness
    # each seed's circle; the one whose rim stands out most against the pad beyond it, by
    # the square root of the share of its rays that reach it (a circle mostly outside the
    # image is read on a sliver)
    found, best = None, -np.inf
    for cx, cy in _seeds(change):
        got = _colour_edge(change, mag, cx, cy)
        if got is None:
            continue
        score = _rim_contrast(change, got[0], got[1], got[2]) * np.sqrt(got[3])
        if score > best:
            found, best = got, score
    if found is None:
        raise InputError("no contact circle found in frame: no centre about which the colour "
                         "change falls on a circle")
    cx, cy, r, _ = found
    # the drift fitted again without the contact and its sink-in, and the circle read again
    yy, xx = np.indices(mag.shape)
    change = drift_free_change(frame, reference,
                               exclude=np.hypot(xx - cx, yy - cy) < 1.6 * r)
    mag = _chroma(change, ref)
    again = _colour_edge(change, mag, cx, cy)
    if again is not None:
        found = again
    cx, cy, r, used = found
    return np.array([cx, cy]), float(r), change, float(used)


def find_contact_circle(frame: np.ndarray, reference: np.ndarray, *, min_change: float = 12.0
                        ) -> ContactCircle:
    """A ball's contact circle in one frame, read twice and checked (see the module's notes).

    The colour edge's circle (:func:`colour_edge_circle`) gives the centre, the radial
    profile of the colour change about it the radius (:func:`profile_radius`: a median
    over the rays, which a ball's texture does not move, with its bootstrap uncertainty;
    1.007 +- 0.028 of 48 hand-annotated real GelSight circles, where the rays' rule reads
    1.005 +- 0.022). The radius is checked against the circle read ray by ray
    (:func:`~tactilevision.optics.locate_contact_edge`): where they differ by more than
    :data:`PROFILE_AGREEMENT` of the profile's sd plus :data:`PROFILE_RULES` of the radius,
    half their difference is added to the radius's uncertainty and a note says so (on
    textured renders the rays' shoulders fall 5 to 15 % inside: a texture's bumps).

    Parameters
    ----------
    frame, reference : (H, W, 3) uint8 ndarray
        The ball at rest and the no-contact reference, BGR.
    min_change : float, default 12.0
        A frame whose 99.9th-percentile colour change (grey levels) is below this, or
        below 4 sigmas of the camera's pixel noise, has no contact.

    Returns
    -------
    ContactCircle
        Its ``problems`` say why it cannot be trusted: less than
        :data:`MIN_RIM_IN_FRAME` of its rim in the image; no edge in the radial profile
        near the colour edge; a rim whose contrast is under :data:`MIN_RIM_CONTRAST` noise
        sigmas of the pad outside it, or of the camera where less than :data:`PAD_SHARE` of
        the image lies beyond it (a circle put on the background's structure, or on part of
        a contact whose edge is not in the image), unless it stands
        :data:`STEADY_RIM_CONTRAST` sigmas and the change falls past it on
        :data:`STEADY_RIM_SHARE` of the rays, or whose contrast cannot be read (fewer
        than 24 rays reach past 1.2 radii); a change that does not fall past
        the rim in more than :data:`MAX_SECTORS_BEYOND_RIM` of its sectors, or
        :data:`MAX_SECTORS_BEYOND_UNSTEADY_RIM` where it falls on fewer than
        :data:`STEADY_RIM_SHARE` of the rays (a larger contact's inner part).

    Raises
    ------
    InputError
        When no contact, or no circle, is found.
    """
    frame = check_array(frame, "frame", [("H", "W", 3)], dtype=np.uint8)
    reference = check_array(reference, "reference", [frame.shape], dtype=np.uint8)
    centre, rc, change, _ = colour_edge_circle(frame, reference, min_change=min_change)
    mag = _chroma(change, cv2.GaussianBlur(reference, (0, 0), 1.5))
    px, py, _ = _edge_points(mag, centre[0], centre[1], 0.85 * rc, 1.18 * rc + 3.0,
                             1.12 * rc)
    d = np.hypot(px - centre[0], py - centre[1]) - rc
    scatter = (1.4826 * float(np.median(np.abs(d - np.median(d)))) / rc if d.size >= 12
               else float("nan"))
    yy, xx = np.indices(mag.shape)
    fine = drift_free_change(frame, reference, sigma=1.0,
                             exclude=np.hypot(xx - centre[0], yy - centre[1]) <= 1.6 * rc)
    rp, sd, contrast = profile_radius(fine, centre, rc)
    try:
        ray_r = locate_contact_edge(frame, reference, centre, rc, change=fine)[1]
    except InputError:
        ray_r = float("nan")
    # each ray's drop past the rim, read once: its median is the contrast where little pad
    # is left (rim_drop), its positive share the fall's steadiness (rim_fall_share)
    drops = _ray_drops(fine, centre, rp if np.isfinite(rp) else rc)
    read = drops.size >= 24
    falls = float(np.mean(drops > 0.0)) if read else float("nan")
    if np.mean(np.hypot(xx - centre[0], yy - centre[1]) > 1.6 * rc) >= PAD_SHARE:
        noise = _pad_noise(_magnitude(fine), centre[0], centre[1], rc)
        against = "the pad outside it"
    else:              # too little pad beyond it: the drop past the rim, in camera sigmas
        contrast = float(np.median(drops)) if read else float("nan")
        noise = max(_pixel_noise(fine), 0.5)
        against = ("the gel just past it, in sigmas of the camera's noise (too little pad "
                   "lies beyond it to read the pad's own)")
    notes = []
    radius, radius_sd = rp, sd
    if np.isfinite(rp) and np.isfinite(sd) and np.isfinite(ray_r):
        tol = PROFILE_AGREEMENT * sd + PROFILE_RULES * rp
        if abs(ray_r - rp) > tol:
            radius_sd = float(np.hypot(sd, 0.5 * abs(ray_r - rp)))
            notes.append(f"the circle read ray by ray ({ray_r:.1f} px) and the radial profile "
                         f"({rp:.1f} +- {sd:.1f} px) disagree by {abs(ray_r - rp):.1f} px, "
                         f"more than {tol:.1f} px: half the difference is added to the "
                         "radius's uncertainty")
    inside = rim_in_frame(centre, radius if np.isfinite(radius) else rc, mag.shape)
    problems = []
    if inside < MIN_RIM_IN_FRAME:
        problems.append(f"only {100 * inside:.0f} % of its rim is in the image (cut by the "
                        f"image's edge; {100 * MIN_RIM_IN_FRAME:.0f} % needed)")
    if not (np.isfinite(rp) and np.isfinite(sd)):
        problems.append("the radial profile of the colour change about its centre has no "
                        "edge near the colour edge")
    elif not np.isfinite(contrast):
        problems.append("fewer than 24 rays from its centre reach past 1.2 radii inside the "
                        "image: its rim's contrast cannot be read")
    elif contrast < MIN_RIM_CONTRAST * noise and not (
            contrast >= STEADY_RIM_CONTRAST * noise and falls >= STEADY_RIM_SHARE):
        problems.append(f"its rim stands {contrast / noise:.1f} noise sigmas above {against} "
                        f"({MIN_RIM_CONTRAST:g} needed, or {STEADY_RIM_CONTRAST:g} where the "
                        f"change falls past it on {100 * STEADY_RIM_SHARE:.0f} % of the rays: "
                        + (f"it does on {100 * falls:.0f} %" if np.isfinite(falls)
                           else "too few rays to tell") + "): not a contact's edge")
    beyond = sectors_beyond_rim(fine, centre, radius if np.isfinite(radius) else rc)
    steady = falls >= STEADY_RIM_SHARE
    most = MAX_SECTORS_BEYOND_RIM if steady else MAX_SECTORS_BEYOND_UNSTEADY_RIM
    if beyond > most:
        problems.append(f"the colour change does not fall past its rim in {100 * beyond:.0f} % "
                        f"of the sectors seen (past the rim it holds {100 * BEYOND_RIM_LEVEL:.0f}"
                        f" % of its level inside; at most {100 * most:.0f} % allowed"
                        + ("" if steady else f" where it falls on fewer than "
                           f"{100 * STEADY_RIM_SHARE:.0f} % of the rays, here "
                           + (f"{100 * falls:.0f} %" if np.isfinite(falls) else "unread"))
                        + "): part of a larger contact, whose rim the image cuts, or a "
                        "texture's edge, not the contact's")
    return ContactCircle(centre_px=np.asarray(centre, np.float64), radius_px=float(radius),
                         radius_sd_px=float(radius_sd), colour_radius_px=float(rc),
                         ray_radius_px=float(ray_r), profile_radius_px=float(rp),
                         profile_sd_px=float(sd), rim_contrast=float(contrast / noise),
                         rim_in_frame=inside, edge_scatter=scatter,
                         problems=tuple(problems), notes=tuple(notes),
                         sectors_beyond_rim=beyond, rim_fall_share=falls)
