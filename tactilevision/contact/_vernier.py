"""The bevel as a vernier: how far past w0 a press went, read from the bevel's contact.

The gauge block's bevel is a V-shaped ridge beside each indenter (see
:class:`BevelGeometry`): its straight crest lies in the block's reference
plane, w0 behind the indenter face, and its flanks fall away from the gel at
the angle theta. Pressed to the depth w = w0 + delta, the crest lies delta
into the gel, and the gel meets the flanks over a band of half-width

``L = (delta + b) / tan(theta)``

across the crest (b: how far the gel's own surface rises at the crest, the
bulge; :func:`bulge_at`). Measuring L to a fraction of a pixel measures
delta to a fraction of ``tan(theta)`` pixels: 0.1 px at 0.0295 mm/px and
theta = 5 deg is 0.26 um. That is the vernier.

What the camera sees of the band depends on the sensor: the flanks tilt the
gel by theta, so each flank has a uniform colour change (its own colour, as
the flanks face opposite ways), bounded by the band's edges; renderers and
real optics add lines or shadows along those edges. :func:`bevel_profile`
averages the colour change along the crest into a profile across it, and
:func:`read_bevel` fits that profile with the band's model: two flank
plateaus of free colour meeting at the crest, a line of free colour at each
edge and at the crest, over a linear background, all blurred by about a
pixel; the band's half-width L and the crest's position are found by a grid
search refined to 0.05 px (variable projection: for each (crest, L) the
colours follow by linear least squares).

Short bands (a few pixels) do not show their shape: their flanks' colours
are then taken from the session's long bands (``flank_colours``, a prior),
and the band's strength gives L.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np
from scipy.special import erf

from .._checks import InputError, check_array
from ..fem import ForceEstimator

__all__ = ["BevelGeometry", "BevelProfile", "BevelReading", "bevel_force", "bevel_profile",
           "read_bevel"]

_EDGE_BLUR_PX = 1.0      # sd of the Gaussian blur of the band's edges (optics, JPEG)
_LINE_SD_PX = 1.2        # sd of the lines at the edges and the crest
#: Standard uncertainty of the band model itself, px, added in quadrature to the noise's:
#: the flanks meet a sloping, bulging gel surface (the two edges lie at different distances
#: from the crest) and the edge shape is only approximately a blurred step. Measured on
#: simulated 50-press sessions: errors of 0.25 px sd at JPEG quality 90 and 0.6 px at 75,
#: where the noise alone gave 0.1 to 0.3 px (benchmarks/bench_vernier.py prints the
#: z-scores); 0.45 px errs on the side of honesty.
MODEL_FLOOR_PX = 0.45
#: The same for the band read with shadows cast from its edges (``lines='shadows'``): the
#: tails' shapes only approximate a renderer's shadows. Measured on a 20-press session of
#: Taxim's renderer (overshoot 0 to 50 um): errors of 1.0 px sd on the bands read so.
SHADOW_FLOOR_PX = 1.0
#: Bands at least this long (half-width, px) show their flanks' colours free of the edge
#: blur; shorter ones are read with the session's colours as a prior.
RESOLVED_PX = 10.0


@dataclass(frozen=True)
class BevelGeometry:
    """Where and how the bevel ridge sits beside each indenter (session.toml ``[gauge_block]``).

    Attributes
    ----------
    offset_mm : float
        Distance in the gel plane from the indenter axis to the crest line, mm
        (``bevel_offset_mm``).
    direction_deg : float
        Direction from the indenter axis to the bevel in the image, degrees:
        0 = +x (along the columns), 90 = +y (down the rows)
        (``bevel_direction_deg``).
    angle_deg : float
        Flank angle theta of the ridge to the block's reference plane,
        degrees (``bevel_angle_deg``); 0: a mark with no vernier.
    length_mm : float
        Length of the crest line, mm (``bevel_length_mm``).
    """

    offset_mm: float
    direction_deg: float = 0.0
    angle_deg: float = 0.0
    length_mm: float = 2.4

    @property
    def tan_theta(self) -> float:
        """tan(theta) of the flanks (0 without a vernier)."""
        return math.tan(math.radians(self.angle_deg))

    def crest_px(self, centre_px: tuple[float, float], mm_per_px: float) -> tuple[float, float]:
        """(x, y) of the crest's middle in the image for an indenter axis at `centre_px`, px."""
        t = math.radians(self.direction_deg)
        return (centre_px[0] + self.offset_mm / mm_per_px * math.cos(t),
                centre_px[1] + self.offset_mm / mm_per_px * math.sin(t))


@dataclass(frozen=True)
class BevelProfile:
    """The colour change across the bevel's crest, averaged along it.

    Attributes
    ----------
    u_px : (K,) float64 ndarray
        Position across the crest, px, from the nominal crest line, positive
        away from the indenter.
    colour : (K, 3) float64 ndarray
        Mean colour change (frame - reference) over the sampled part of the
        crest, grey levels, in the frames' channel order.
    coverage : float
        Fraction of the sampled band (crest length x profile range) inside
        the image.
    """

    u_px: np.ndarray
    colour: np.ndarray
    coverage: float


@dataclass(frozen=True)
class BevelReading:
    """The band of contact on the bevel, read from one or more profiles.

    Attributes
    ----------
    half_width_px, half_width_std_px : float
        L, the band's half-width across the crest, and its standard
        uncertainty, px.
    crest_px : float
        The crest's position found, px from the nominal line (positive away
        from the indenter).
    snr : float
        Detection strength: the square root of the drop in the residual sum
        of squares from the background alone to the band's model, in units of
        the residual noise variance (a signal-to-noise ratio); 0 when the
        best band reaches the end of the search range (smooth shading
        across the whole profile, not a band).
    closure_mm, closure_std_mm : float
        ``L tan(theta) * mm_per_px``: how far the crest is pressed into the
        gel's surface (overshoot plus bulge), and its uncertainty, mm.
    resolved : bool
        Whether the band is long enough (L >= :data:`RESOLVED_PX`) for its
        flanks' colours to be measured on it; shorter bands trade their
        colours against L through the edge blur and lean on a prior
        (``flank_colours``).
    flank_colours : (2, 3) float64 ndarray
        Fitted colour of the inner (towards the indenter) and outer flank.
    noise : float
        Residual noise of the profile, grey levels.
    model : (K, 3) float64 ndarray
        The fitted profile (for plots).
    contrast : float
        The band's colour contrast: the largest peak-to-peak, over the
        channels, of the fitted band alone (flanks, lines and shadows, the
        background left out), grey levels. The flanks tilt the gel by theta
        whatever L is, so every band of a session shows about the same
        contrast once it is a blur wide; shading with no band behind it
        shows a fraction of it.
    """

    half_width_px: float
    half_width_std_px: float
    crest_px: float
    snr: float
    closure_mm: float
    closure_std_mm: float
    resolved: bool
    flank_colours: np.ndarray
    noise: float
    model: np.ndarray
    contrast: float = float("nan")


def bevel_profile(frame: np.ndarray, reference: np.ndarray, centre_px: tuple[float, float],
                  mm_per_px: float, bevel: BevelGeometry, *, reach_px: float,
                  step_px: float = 0.5, crest_fraction: float = 0.8,
                  inner_px: float | None = None) -> BevelProfile:
    """Sample the colour change across the bevel's crest, averaged along it.

    Parameters
    ----------
    frame, reference : (H, W, 3) array_like of uint8
        The frame and the no-contact frame of the sensor.
    centre_px : (x, y)
        Indenter axis in the image (footprint centre), px.
    mm_per_px : float
    bevel : BevelGeometry
    reach_px : float
        The profile runs over ``|u| <= reach_px`` across the crest.
    step_px : float, default 0.5
        Sampling step across the crest (bilinear interpolation), px.
    crest_fraction : float, default 0.8
        Central part of the crest that is averaged (its ends are left out).
    inner_px : float, optional
        The profile runs only to ``u >= -inner_px`` on the indenter's side
        (default `reach_px`): keeps the indenter's own contact, and the
        shading beside it, out of the bevel's profile.

    Returns
    -------
    BevelProfile
        Samples outside the image are left out of the averages; a position
        with none inside keeps the average of its neighbours' background
        (zero) and lowers ``coverage``. Never NaN.

    Raises
    ------
    ShapeError
        For frames that are not (H, W, 3) or differ in shape.
    """

    f = check_array(frame, "frame", [("H", "W", 3)])
    r = check_array(reference, "reference", [f.shape])
    s = float(mm_per_px)
    t = math.radians(bevel.direction_deg)
    cu, su = math.cos(t), math.sin(t)
    bx, by = bevel.crest_px(centre_px, s)
    u = np.arange(-reach_px, reach_px + 1e-9, step_px)
    if inner_px is not None:
        u = u[u >= -max(float(inner_px), 2 * step_px) - 1e-9]
    half_v = 0.5 * crest_fraction * bevel.length_mm / s
    v = np.arange(-half_v, half_v + 1e-9, 0.5)
    uu, vv = np.meshgrid(u, v)                        # (V, K)
    x = (bx + uu * cu - vv * su).astype(np.float32)
    y = (by + uu * su + vv * cu).astype(np.float32)
    h, w = f.shape[:2]
    inside = (x >= 0) & (x <= w - 1) & (y >= 0) & (y <= h - 1)
    if not inside.any():
        return BevelProfile(u_px=u, colour=np.zeros((u.size, 3)), coverage=0.0)
    # sample only the bounding box of the band: a cheap subtraction
    x0, x1 = max(int(np.floor(x[inside].min())), 0), min(int(np.ceil(x[inside].max())) + 1, w)
    y0, y1 = max(int(np.floor(y[inside].min())), 0), min(int(np.ceil(y[inside].max())) + 1, h)
    d = f[y0:y1, x0:x1].astype(np.float32) - r[y0:y1, x0:x1].astype(np.float32)
    samp = cv2.remap(d, x - x0, y - y0, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    wgt = inside.astype(np.float64)                   # (V, K)
    n = wgt.sum(axis=0)                               # (K,)
    colour = np.einsum("vk,vkc->kc", wgt, samp.astype(np.float64)) / np.maximum(n, 1)[:, None]
    return BevelProfile(u_px=u, colour=colour, coverage=float(inside.mean()))


def _flank_boxes(u: np.ndarray, crest: np.ndarray, half: np.ndarray,
                 blur: float = _EDGE_BLUR_PX) -> tuple[np.ndarray, np.ndarray]:
    """Blurred indicators of [c - L, c] and [c, c + L] for every candidate, (G, K) each,
    edges of sd `blur` px: ``0.5 (erf((u - a) k) - erf((u - b) k))``, k = 1 / (sqrt(2) blur).

    The candidates of a search grid share their edges (crests and half-widths on a lattice),
    so erf is evaluated once per distinct edge and gathered: the same numbers as evaluating
    it per candidate, at a fraction of the cost (20 times fewer erf calls on the 1 px grid).
    """
    k = 1.0 / (math.sqrt(2.0) * blur)
    edges = np.concatenate([crest - half, crest, crest + half])
    uniq, inv = np.unique(edges, return_inverse=True)
    e = erf((u[None, :] - uniq[:, None]) * k)                # (distinct edges, K)
    g = crest.size
    e_lo, e_c, e_hi = e[inv[:g]], e[inv[g:2 * g]], e[inv[2 * g:]]
    return 0.5 * (e_lo - e_c), 0.5 * (e_c - e_hi)


def _line(u: np.ndarray, m: np.ndarray, sd: float = _LINE_SD_PX) -> np.ndarray:
    return np.exp(-0.5 * ((u - m) / sd) ** 2)


def _lines_at(u: np.ndarray, m: np.ndarray, sd: float) -> np.ndarray:
    """:func:`_line` at every centre of `m` (G,), (G, K): evaluated once per distinct
    centre (the candidates of a search grid share them) and gathered, the same numbers."""
    uniq, inv = np.unique(m, return_inverse=True)
    return _line(u[None, :], uniq[:, None], sd)[inv]


def _background(u: np.ndarray, degree: int) -> np.ndarray:
    """(K, degree + 1) Legendre polynomials over the profile: its smooth shading."""
    x = u / max(float(np.abs(u).max()), 1.0)
    return np.polynomial.legendre.legvander(x, degree)


def _basis(u: np.ndarray, crest: np.ndarray, half: np.ndarray, lines: str = "all",
           blur: float = _EDGE_BLUR_PX, degree: int = 2, line_sd: float = _LINE_SD_PX
           ) -> np.ndarray:
    """(G, K, p) design: background (degree + 1), inner and outer flank, then the lines
    (``'only'``: the background and the two edge lines)."""
    uk = u[None, :]
    c, L = crest[:, None], half[:, None]
    bg = np.broadcast_to(_background(u, degree)[None], (c.shape[0], u.size, degree + 1))
    cols = [bg[..., j] for j in range(degree + 1)]
    if lines == "only":        # lines at the edges and no flanks: renderers' shadow lines
        return np.stack([*cols, _lines_at(u, crest - half, line_sd),
                         _lines_at(u, crest + half, line_sd)], axis=-1)
    b_in, b_out = _flank_boxes(u, np.asarray(crest, np.float64).ravel(),
                               np.asarray(half, np.float64).ravel(), blur)
    cols += [b_in, b_out]
    if lines == "tilt":        # each flank's colour may drift linearly across it
        cols += [b_in * (uk - c + 0.5 * L) / np.maximum(L, 1.0),
                 b_out * (uk - c - 0.5 * L) / np.maximum(L, 1.0)]
    if lines in ("all", "edges"):
        cols += [_lines_at(u, crest - half, line_sd), _lines_at(u, crest + half, line_sd)]
    if lines in ("all", "crest"):
        cols += [_lines_at(u, crest, line_sd)]
    if lines == "shadows":
        # a renderer's cast shadows: a thin line at each edge and tails running outward
        cols += [_line(uk, c - L, _SHADOW_LINE_SD_PX), _line(uk, c + L, _SHADOW_LINE_SD_PX)]
        for ell in _SHADOW_PX:
            cols += [_tail(c - L - uk, blur, ell), _tail(uk - c - L, blur, ell)]
    return np.stack(cols, axis=-1)


#: Lengths (px) of the one-sided shadow tails of ``lines='shadows'``, and the sd of its
#: edge lines. Taxim's renderer (its shadow table, looked up in 0.1 mm bins of the
#: contact's height) paints blocks 10 to 25 px long beside bands of a few microns of
#: relief; two tail lengths explain them (benchmarks/bench_vernier.py).
_SHADOW_PX = (4.0, 12.0)
_SHADOW_LINE_SD_PX = 1.0


def _tail(x: np.ndarray, blur: float, ell: float) -> np.ndarray:
    """A shadow cast from an edge (x = 0) outward (x > 0), peaking `ell` px out:
    ``(x / ell) exp(1 - x / ell)``, its start blurred like the band's edges."""
    xp = np.maximum(x, 0.0)
    k = 1.0 / (math.sqrt(2.0) * blur)
    return 0.5 * (1.0 + erf(x * k)) * (xp / ell) * np.exp(1.0 - xp / ell)


def _flanks(degree: int) -> tuple[int, int]:
    """Columns of the design holding the inner and outer flank colours."""
    return degree + 1, degree + 2


def _solve(B: np.ndarray, R: np.ndarray, prior: np.ndarray | None, weight: float,
           flanks: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Least squares for every candidate: coefficients (G, p, 3) and residual SS (G,)."""
    Bt = B.transpose(0, 2, 1)
    BtB = Bt @ B
    BtR = Bt @ R
    A, Y = BtB.copy(), BtR.copy()
    if prior is not None:                 # pseudo-observations pulling the flank colours
        for j, col in enumerate(flanks):
            A[:, col, col] += weight
            Y[:, col, :] += weight * prior[j][None, :]
    A += 1e-9 * np.trace(A, axis1=1, axis2=2)[:, None, None] * np.eye(B.shape[2])
    coef = np.linalg.solve(A, Y)
    # ||R - B coef||^2 = ||R||^2 - 2 <BtR, coef> + <coef, BtB coef>
    rss = (float(np.sum(R * R)) - 2.0 * np.einsum("gpc,gpc->g", BtR, coef)
           + np.einsum("gpc,gpc->g", coef, BtB @ coef))
    if prior is not None:
        for j, col in enumerate(flanks):
            rss = rss + weight * np.sum((coef[:, col, :] - prior[j][None, :]) ** 2, axis=1)
    return coef, rss


def _residual_correlation(resid: np.ndarray, step: float) -> float:
    """Summed |correlation| of the residuals (K, 3) along u over 8 px (interpolation, JPEG
    blocks), `step` px apart."""
    rho = 0.0
    for lag in range(1, round(8.0 / step) + 1):
        a, b = resid[:-lag], resid[lag:]
        den = float(np.sqrt(np.sum(a * a) * np.sum(b * b)))
        r_lag = float(np.sum(a * b)) / den if den > 0 else 0.0
        rho += abs(r_lag)
    return rho


def _rss_curvature(halves: np.ndarray, rss: np.ndarray) -> float:
    """Curvature of rss(L) at its least, from the half-widths tried at one crest (0.0 with
    fewer than three around the least)."""
    order = np.argsort(halves)
    hs, rs = halves[order], rss[order]
    j = int(np.argmin(rs))
    lo, hi = max(j - 3, 0), min(j + 4, hs.size)
    if hi - lo >= 3:
        return 2.0 * float(np.polyfit(hs[lo:hi] - hs[j], rs[lo:hi], 2)[0])
    return 0.0


def read_bevel(profiles: list[BevelProfile] | BevelProfile, bevel: BevelGeometry,
               mm_per_px: float, *, max_closure_mm: float = 0.1, crest_range_px: float = 6.0,
               flank_colours: np.ndarray | None = None, colour_sd: float = 0.3,
               coarse: bool = False, lines: str = "none", blur_px: float = _EDGE_BLUR_PX,
               background_degree: int = 4, line_px: float = _LINE_SD_PX) -> BevelReading:
    """Read the band of contact on the bevel from profiles across its crest.

    Parameters
    ----------
    profiles : BevelProfile or list of BevelProfile
        Profiles of frames at the same depth (the frames of a force window);
        they are averaged.
    bevel : BevelGeometry
        Needs ``angle_deg > 0``.
    mm_per_px : float
    max_closure_mm : float, default 0.1
        Largest crest penetration looked for: L runs up to
        ``max_closure_mm / tan(theta)`` (and the profile's reach less 6 px).
    crest_range_px : float, default 6.0
        The crest is looked for within this of its nominal line (the
        footprint centre and the scale place it to a few pixels).
    flank_colours : (2, 3) array_like, optional
        Prior colours of the inner and outer flank (the session's long
        bands); they decide L when the band is too short to show its shape.
    colour_sd : float, default 0.3
        Relative standard deviation of that prior (the flanks' colours vary
        over the sensor with its lighting).
    coarse : bool, default False
        Stop at the 1 px grid (a quick look: L and the crest to +-0.5 px).
    lines : {'none', 'all', 'edges', 'crest', 'tilt', 'shadows', 'only'}, default 'none'
        Which lines the band model carries: none, or at both edges and the
        crest (renderers and optics that draw shadows along the edges), the
        edges or the crest only; 'tilt' lets each flank's colour drift
        linearly across it instead; 'shadows': thin lines at the edges and
        shadows cast outward from them (one-sided tails peaking 4 and 12 px
        out, free colours), for renderers that paint long shadows beside
        narrow bands; 'only': the two edge lines and no flanks (a band seen
        by its edges alone: a broad block of colour is no band to it, so it
        checks a reading with flanks). A line at an edge trades off against
        the edge's position: use lines only where the images have them.
        With 'only', ``flank_colours`` holds the edge lines' colours.
    blur_px : float, default 1.0
        sd of the Gaussian blur of the band's edges, px.
    background_degree : int, default 4
        Degree of the smooth background.
    line_px : float, default 1.2
        sd of the Gaussian lines, px.

    Returns
    -------
    BevelReading

    Raises
    ------
    InputError
        For a bevel without a vernier (``angle_deg`` 0), profiles of
        different samplings, or an unknown `lines`.

    Notes
    -----
    Model, for u across the crest (px) with the crest at c:
    ``R(u) = P(u) + k_in B(c - L, c) + k_out B(c, c + L)
    [+ e_in G(c - L) + e_out G(c + L) + e_c G(c)]``, B a box with edges
    blurred by a Gaussian of sd 1 px, G a Gaussian line of sd 1.2 px, the
    coefficients (3-vectors, one per colour channel) free; P, a polynomial
    of `background_degree` (Legendre, over the profile), takes up the
    press's own shading (the bulge's slopes, a renderer's broad changes). (c, L) on a grid
    of 1 px, then 0.25 px and 0.05 px around the best. The uncertainty of L comes from
    the curvature of the residual sum of squares against L (profile
    likelihood), with the residual variance and its correlation along the
    profile (interpolated, JPEG-compressed frames) counted, plus the model's
    own :data:`MODEL_FLOOR_PX` in quadrature.
    """
    if isinstance(profiles, BevelProfile):
        profiles = [profiles]
    if not profiles:
        raise InputError("read_bevel needs at least one profile")
    tan = bevel.tan_theta
    if tan <= 0:
        raise InputError("the bevel has no vernier (bevel_angle_deg = 0): nothing to read")
    u = profiles[0].u_px
    for p in profiles[1:]:
        if p.u_px.shape != u.shape or not np.allclose(p.u_px, u):
            raise InputError("read_bevel: the profiles are sampled differently")
    R = np.mean([p.colour for p in profiles], axis=0)     # (K, 3)
    s = float(mm_per_px)
    step = float(u[1] - u[0])
    reach = float(u[-1])
    l_max = max(1.0, min(max_closure_mm / (tan * s), reach - 6.0))
    prior = None if flank_colours is None else np.asarray(flank_colours, np.float64)

    # background alone
    deg = int(background_degree)
    flanks = _flanks(deg)
    B0 = _background(u, deg)
    c0, *_ = np.linalg.lstsq(B0, R, rcond=None)
    rss0 = float(np.sum((R - B0 @ c0) ** 2))

    def search(crests: np.ndarray, halves: np.ndarray, weight: float):
        cc, hh = np.meshgrid(crests, halves, indexing="ij")
        B = _basis(u, cc.ravel(), hh.ravel(), lines, blur_px, deg, line_px)
        coef, rss = _solve(B, R, prior, weight, flanks)
        return cc.ravel(), hh.ravel(), coef, rss, B

    # coarse grid (1 px; the noise level for the prior's weight comes from a first pass
    # without the prior), then 0.25 px and 0.05 px around the best
    crests = np.arange(-crest_range_px, crest_range_px + 1e-9, 1.0)
    halves = np.arange(0.5, l_max + 1e-9, 1.0)
    if lines not in ("none", "all", "edges", "crest", "tilt", "shadows", "only"):
        raise InputError(f"lines must be 'none', 'all', 'edges', 'crest', 'tilt', 'shadows' "
                         f"or 'only', got {lines!r}")
    cc, hh, coef, rss, _ = search(crests, halves, 0.0)
    k = int(np.argmin(rss))
    weight = 0.0
    if prior is not None:
        sigma2 = float(rss[k]) / max(R.size - 3 * (deg + 8), 1)
        scale = float(np.mean(np.sum(prior ** 2, axis=1)))
        weight = sigma2 / max((colour_sd ** 2) * scale, 1e-12)
        cc, hh, coef, rss, _ = search(crests, halves, weight)
        k = int(np.argmin(rss))
    refinements = () if coarse else ((1.0, 0.25, 0.25), (0.25, 0.05, 0.05))
    if coarse:
        cc, hh, coef, rss, B = search(np.array([cc[k]]), hh[np.isclose(cc, cc[k])], weight)
        k = int(np.argmin(rss))
    for span, step_c, step_h in refinements:
        cc, hh, coef, rss, B = search(cc[k] + np.arange(-span, span + 1e-9, step_c),
                                      np.clip(hh[k] + np.arange(-span, span + 1e-9, step_h),
                                              0.05, None), weight)
        k = int(np.argmin(rss))
    crest, half = float(cc[k]), float(hh[k])
    resid = R - B[k] @ coef[k]
    dof = max(R.size - 3 * (deg + 8), 1)
    sigma2 = float(np.sum(resid ** 2)) / dof
    inflate = 1.0 + 2.0 * _residual_correlation(resid, step)
    row = np.isclose(cc, crest)                 # the curvature of rss(L) at the best crest
    curv = _rss_curvature(hh[row], rss[row])
    half_std = math.sqrt(2.0 * sigma2 * inflate / curv) if curv > 0 else float(half)
    half_std = math.hypot(half_std, SHADOW_FLOOR_PX if lines == "shadows" else MODEL_FLOOR_PX)
    snr = math.sqrt(max(rss0 - float(rss[k]), 0.0) / max(sigma2 * inflate, 1e-12))
    if half >= l_max - 1.0:
        snr = 0.0        # the "band" fills the search range: smooth shading, not a band
    model = B[k] @ coef[k]
    band = B[k][:, deg + 1:] @ coef[k][deg + 1:]
    contrast = float(np.max(np.ptp(band, axis=0)))
    return BevelReading(
        half_width_px=half, half_width_std_px=half_std, crest_px=crest, snr=snr,
        closure_mm=half * tan * s, closure_std_mm=half_std * tan * s,
        resolved=half >= RESOLVED_PX, flank_colours=coef[k][list(flanks)].copy(),
        noise=math.sqrt(sigma2), model=model, contrast=contrast)


#: Crest penetrations (mm) at which :func:`bevel_force` is solved; between them it is
#: interpolated in log-log (the force grows about as the closure to the power 1.3 to 1.5).
_FORCE_CLOSURES_MM = (0.004, 0.01, 0.02, 0.035, 0.05, 0.075, 0.11)


@lru_cache(maxsize=32)
def _bevel_force_table(angle_deg: float, length_mm: float, thickness_mm: float, nu: float
                       ) -> np.ndarray:
    """Force per MPa of E of the band at each of _FORCE_CLOSURES_MM, N/MPa."""
    s = 0.08
    tan = math.tan(math.radians(angle_deg))
    half_v = 0.5 * length_mm
    size = int(2 * math.ceil((half_v + 4.0 * thickness_mm) / s / 2)) + 1
    shape = (size, max(size, int(2 * math.ceil((max(_FORCE_CLOSURES_MM) / tan
                                                 + 4.0 * thickness_mm) / s / 2)) + 1))
    # every pixel: the band's footprint is a thin wedge, its force table computed once
    est = ForceEstimator(shape, s, thickness_mm, 1.0, nu, contact="footprint", threshold_mm=0.01,
                         binning=1)
    rows, cols = np.indices(shape, dtype=np.float64)
    u = (cols - (shape[1] - 1) / 2) * s
    v = (rows - (shape[0] - 1) / 2) * s
    out = []
    for closure in _FORCE_CLOSURES_MM:
        p = np.where(np.abs(v) <= half_v, np.maximum(closure - np.abs(u) * tan, 0.0), 0.0)
        out.append(float(est(p.astype(np.float32), contact_mask=p > 0).total_n[2]))
    return np.array(out)


def bevel_force(closure_mm: np.ndarray, bevel: BevelGeometry, *, thickness_mm: float,
                E_mpa: float, nu: float) -> np.ndarray:
    """Normal force of the bevel's band of contact: what the vernier itself presses, N.

    Parameters
    ----------
    closure_mm : (N,) array_like of float
        How far the crest is pressed into the gel's surface, mm (0 or less:
        no contact).
    bevel : BevelGeometry
        Needs ``angle_deg > 0``.
    thickness_mm, E_mpa, nu : float
        The layer: h, E and nu.

    Returns
    -------
    force_n : (N,) float64 ndarray
        Zero where the crest does not reach the gel.

    Raises
    ------
    InputError
        For a bevel without a vernier.

    Notes
    -----
    The band ``|u| <= closure / tan(theta)``, ``|v| <= length / 2`` pressed
    rigidly into a bonded linear-elastic layer, frictionless, its contact
    taken as the band (the gel meets the flanks there):
    :class:`tactilevision.fem.ForceEstimator` (the layer's Fourier surface
    stiffness, ``contact='footprint'``) at 0.08 mm per node, solved at
    seven closures from 4 to 110 um, interpolated in log-log and linear in
    E. For a 3 mm, 5 deg, 3 mm-long ridge on a 3 mm gel of E = 0.2 MPa,
    nu = 0.48: 2.5 mN at 10 um, 10.4 mN at 30 um, 21.6 mN at 50 um
    (the same solve on the image's own 0.0295 mm grid: within 1%). A few per
    cent of the indenter's force at the shallow indenters: the F/T sensor
    reads it too, and certification takes it off.
    """
    if bevel.tan_theta <= 0:
        raise InputError("the bevel has no vernier (bevel_angle_deg = 0): no band of contact")
    c = np.atleast_1d(np.asarray(closure_mm, np.float64))
    # nu to 0.02: the band is small against h, its stiffness nearly the half-space's,
    # E / (1 - nu^2), which moves 1.2% from nu 0.46 to 0.48
    table = _bevel_force_table(round(bevel.angle_deg, 6), round(bevel.length_mm, 6),
                               round(float(thickness_mm), 6),
                               min(round(float(nu) / 0.02) * 0.02, 0.49))
    xs = np.log(np.array(_FORCE_CLOSURES_MM))
    ys = np.log(np.maximum(table, 1e-15))
    pos = c > 0
    out = np.zeros_like(c)
    if pos.any():
        lc = np.log(c[pos])
        slope_lo = (ys[1] - ys[0]) / (xs[1] - xs[0])
        slope_hi = (ys[-1] - ys[-2]) / (xs[-1] - xs[-2])
        val = np.interp(lc, xs, ys)
        val = np.where(lc < xs[0], ys[0] + slope_lo * (lc - xs[0]), val)
        val = np.where(lc > xs[-1], ys[-1] + slope_hi * (lc - xs[-1]), val)
        out[pos] = np.exp(val)
    return out * float(E_mpa)
