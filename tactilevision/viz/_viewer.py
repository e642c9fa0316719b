"""An interactive, self-contained HTML viewer of height (and force) maps, with Plotly.

The page holds the tactile frame beside its height map, a 3D surface of the
height map that can be rotated, the force map (pressure, kPa) when given, the
colour scales in mm and kPa, and a slider over the frames (Plotly frames and
sliders; no hand-written JavaScript). Plotly's JavaScript is embedded in the
page: it opens without a network.
"""

from __future__ import annotations

import base64
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .._checks import InputError

__all__ = ["downsample_map", "viewer_figure", "write_viewer"]

#: colour scale of the height maps (and the 3D surface)
HEIGHT_COLORSCALE = "Viridis"
#: colour scale of the pressure maps
PRESSURE_COLORSCALE = "Inferno"
#: the figure's height in CSS px
FIGURE_HEIGHT_PX = 900


def _plotly():
    try:
        import plotly.graph_objects as go
    except ImportError:
        raise InputError("the viewer needs Plotly: pip install 'tactilevision[view]'") from None
    return go


def _target_size(h: int, w: int, max_px: int | None) -> tuple[int, int]:
    if max_px is None or max(h, w) <= max_px:
        return h, w
    s = max_px / max(h, w)
    return max(1, round(h * s)), max(1, round(w * s))


def downsample_map(a: np.ndarray, max_px: int | None) -> np.ndarray:
    """Shrink an image or map so that its long side is at most `max_px` (area averaging).

    Parameters
    ----------
    a : (H, W) or (H, W, C) ndarray
        Height map (float, mm), pressure map (kPa) or uint8 frame.
    max_px : int or None
        Longest side after shrinking; None (or a smaller image) keeps `a`.

    Returns
    -------
    out : (h, w) or (h, w, C) ndarray
        float32 for a float map, uint8 for a uint8 image; ``cv2.resize`` with
        ``INTER_AREA`` to ``round(H * s), round(W * s)``, ``s = max_px / max(H, W)``.
    """
    a = np.asarray(a)
    h, w = _target_size(a.shape[0], a.shape[1], max_px)
    if a.dtype != np.uint8:
        a = a.astype(np.float32, copy=False)
    if (h, w) == a.shape[:2]:
        return a
    return cv2.resize(a, (w, h), interpolation=cv2.INTER_AREA)


def _png_uri(frame_bgr: np.ndarray) -> str:
    ok, buf = cv2.imencode(".png", np.ascontiguousarray(frame_bgr))
    if not ok:  # pragma: no cover - OpenCV encodes any uint8 image
        raise InputError("could not encode a frame as PNG")
    return "data:image/png;base64," + base64.b64encode(buf.tobytes()).decode("ascii")


def _axis_mm(n: int, extent: float) -> np.ndarray:
    return np.linspace(0.0, extent, n, dtype=np.float64) if n > 1 else np.zeros(1)


def viewer_figure(frames_bgr: np.ndarray | Sequence[np.ndarray] | None,
                  heights_mm: np.ndarray, *, mm_per_px: float | None,
                  pressure_kpa: np.ndarray | None = None,
                  titles: Sequence[str] | None = None, max_px: int | None = 160,
                  active: int = 0):
    """The viewer's Plotly figure: frame, height map, 3D surface, force map, frame slider.

    Parameters
    ----------
    frames_bgr : (N, H, W, 3) uint8 array_like or None
        The tactile frames, BGR (as :func:`tactilevision.io.read_frame`); None
        shows the height maps alone.
    heights_mm : (N, H, W) array_like
        Height maps, mm, positive into the gel (NaN shown as gaps).
    mm_per_px : float or None
        Pixel size of the height maps, mm; None labels the axes in pixels.
    pressure_kpa : (N, rows, cols) array_like, optional
        Normal pressure, kPa (:attr:`tactilevision.fem.ForceMap.pressure_kpa`),
        drawn over the same extent as the height map.
    titles : sequence of str, optional
        One label per frame (the slider's); default the frame numbers.
    max_px : int or None, default 160
        Longest side of the images on the page (:func:`downsample_map`); the
        3D surface gets half of it.
    active : int, default 0
        The frame shown when the page opens (and the slider's position).

    Returns
    -------
    fig : plotly.graph_objects.Figure
        Traces: 0 the frame (a ``go.Image``, only with `frames_bgr`), then the
        height map (``go.Heatmap``), the surface (``go.Surface``) and the
        pressure (``go.Heatmap``, only with `pressure_kpa`). One Plotly frame
        per input frame (named ``"0"``, ``"1"``...), one slider step each.
        The height colour scale (``layout.coloraxis``) spans the heights'
        minimum to maximum, mm; the pressure's (``layout.coloraxis2``) 0 to the
        maximum, kPa.

    Raises
    ------
    InputError
        For mismatched shapes or counts, or no finite height.
    """
    go = _plotly()
    heights, frames, pressure, finite, titles = _check_maps(frames_bgr, heights_mm,
                                                            pressure_kpa, titles, active)
    n = heights.shape[0]
    pan = _panels(heights, frames, pressure, mm_per_px, max_px)
    zmin, zmax = float(finite.min()), float(finite.max())
    if zmax <= zmin:
        zmax = zmin + 1e-6

    # panels of the top row, left to right: frame, height, pressure; the surface below
    cols = (["frame"] if frames is not None else []) + ["height"] + (
        ["pressure"] if pressure is not None else [])
    layout, domain = _axes_layout(cols, pan.unit)
    axis_of = {name: ("" if k == 0 else str(k + 1)) for k, name in enumerate(cols)}
    layout["coloraxis"] = dict(colorscale=HEIGHT_COLORSCALE, cmin=zmin, cmax=zmax,
                               colorbar=_colorbar(domain, "height", "height (mm)"))
    pmax = 0.0
    if pan.pressures is not None:
        pf = pressure[np.isfinite(pressure)]
        pmax = float(pf.max()) if pf.size and pf.max() > 0 else 1.0
        layout["coloraxis2"] = dict(colorscale=PRESSURE_COLORSCALE, cmin=0.0, cmax=pmax,
                                    colorbar=_colorbar(domain, "pressure", "pressure (kPa)"))
    zrange = zmax - zmin
    layout["scene"] = dict(
        domain=dict(x=[0.1, 0.9], y=[0.0, 0.48]),
        xaxis=dict(title=f"x ({pan.unit})"),
        yaxis=dict(title=f"y ({pan.unit})", autorange="reversed"),
        zaxis=dict(title="height (mm)", range=[zmin - 0.05 * zrange, zmax + 0.05 * zrange]),
        aspectmode="manual",
        aspectratio=dict(x=1.0, y=max(pan.ext_y, 1e-9) / max(pan.ext_x, 1e-9), z=0.35))

    def traces(i: int) -> list:
        return _traces(go, pan, axis_of, i)

    frame_objs = [go.Frame(name=str(i), data=traces(i),
                           traces=list(range(len(traces(0)))),
                           layout=dict(title=dict(text=titles[i])))
                  for i in range(n)]
    steps = [dict(method="animate", label=titles[i],
                  args=[[str(i)], dict(mode="immediate", frame=dict(duration=0, redraw=True),
                                       transition=dict(duration=0))])
             for i in range(n)]
    layout.update(
        title=dict(text=titles[active]), height=FIGURE_HEIGHT_PX,
        margin=dict(l=60, r=60, t=70, b=110), annotations=_annotations(domain),
        sliders=[dict(active=active, steps=steps, x=0.05, len=0.9, y=0.0, yanchor="top",
                      pad=dict(t=40), currentvalue=dict(prefix="frame: "))],
    )
    return go.Figure(data=traces(active), frames=frame_objs, layout=layout)


def _check_maps(frames_bgr: np.ndarray | Sequence[np.ndarray] | None, heights_mm: np.ndarray,
                pressure_kpa: np.ndarray | None, titles: Sequence[str] | None, active: int
                ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray,
                           list[str]]:
    """Check :func:`viewer_figure`'s inputs; return the heights, frames and pressures as
    (N, ...) arrays, the finite heights and the titles."""
    heights = np.asarray(heights_mm, dtype=np.float32)
    if heights.ndim == 2:
        heights = heights[None]
    if heights.ndim != 3 or heights.shape[0] == 0:
        raise InputError(f"height maps must be (N, H, W), got shape {heights.shape}")
    n, H, W = heights.shape
    if frames_bgr is not None:
        frames = np.asarray(frames_bgr)
        if frames.ndim == 3:
            frames = frames[None]
        if frames.shape[:3] != (n, H, W) or frames.shape[3:] != (3,):
            raise InputError(f"frames of shape {frames.shape} do not match the height maps "
                             f"{heights.shape}")
    else:
        frames = None
    pressure = None
    if pressure_kpa is not None:
        pressure = np.asarray(pressure_kpa, dtype=np.float32)
        if pressure.ndim == 2:
            pressure = pressure[None]
        if pressure.ndim != 3 or pressure.shape[0] != n:
            raise InputError(f"pressure maps of shape {pressure.shape} do not match the "
                             f"{n} height map(s)")
    finite = heights[np.isfinite(heights)]
    if finite.size == 0:
        raise InputError("no finite height in the height maps")
    titles = [str(i) for i in range(n)] if titles is None else [str(t) for t in titles]
    if len(titles) != n:
        raise InputError(f"{len(titles)} titles for {n} frames")
    if not 0 <= active < n:
        raise InputError(f"active frame {active} is not in 0..{n - 1}")
    return heights, frames, pressure, finite, titles


@dataclass(frozen=True)
class _Panels:
    """The maps as the page shows them (downsampled), with their axes in mm (or px)."""

    unit: str
    ext_x: float
    ext_y: float
    heights: list[np.ndarray]
    xs: np.ndarray
    ys: np.ndarray
    surfaces: list[np.ndarray]
    sx: np.ndarray
    sy: np.ndarray
    frames: list[str] | None          # PNG data URIs
    pressures: list[np.ndarray] | None


def _panels(heights: np.ndarray, frames: np.ndarray | None, pressure: np.ndarray | None,
            mm_per_px: float | None, max_px: int | None) -> _Panels:
    """Downsample the maps for the page (the surface to half of `max_px`)."""
    _, H, W = heights.shape
    unit = "mm" if mm_per_px is not None else "px"
    scale = float(mm_per_px) if mm_per_px is not None else 1.0
    ext_x, ext_y = (W - 1) * scale, (H - 1) * scale
    h_small = [downsample_map(z, max_px) for z in heights]
    hh, hw = h_small[0].shape
    surf_px = None if max_px is None else max(2, max_px // 2)
    s_small = [downsample_map(z, surf_px) for z in heights]
    return _Panels(
        unit=unit, ext_x=ext_x, ext_y=ext_y, heights=h_small,
        xs=_axis_mm(hw, ext_x), ys=_axis_mm(hh, ext_y), surfaces=s_small,
        sx=_axis_mm(s_small[0].shape[1], ext_x), sy=_axis_mm(s_small[0].shape[0], ext_y),
        frames=(None if frames is None
                else [_png_uri(downsample_map(f, max_px)) for f in frames]),
        pressures=None if pressure is None else [downsample_map(p, max_px) for p in pressure])


#: vertical extent of the top row of panels (figure fraction)
_TOP = (0.55, 1.0)


def _axes_layout(cols: list[str], unit: str) -> tuple[dict, dict[str, tuple[float, float]]]:
    """The x and y axes of the top row's panels; returns the layout and each panel's x
    domain."""
    width = 1.0 / len(cols)
    layout: dict = {}
    domain = {}
    for k, name in enumerate(cols):
        x0, x1 = k * width, (k + 1) * width - (0.09 if name != "frame" else 0.03)
        domain[name] = (x0, x1)
        ax = "" if k == 0 else str(k + 1)
        layout[f"xaxis{ax}"] = dict(domain=[x0, x1], anchor=f"y{ax}", title=f"x ({unit})",
                                    constrain="domain")
        layout[f"yaxis{ax}"] = dict(domain=list(_TOP), anchor=f"x{ax}", title=f"y ({unit})",
                                    autorange="reversed", scaleanchor=f"x{ax}",
                                    constrain="domain")
    return layout, domain


def _colorbar(domain: dict[str, tuple[float, float]], name: str, title: str) -> dict:
    """A colour bar right of the panel `name`, as tall as the top row."""
    return dict(title=dict(text=title, side="right"), x=domain[name][1] + 0.01,
                xanchor="left", y=_TOP[0], yanchor="bottom", len=_TOP[1] - _TOP[0],
                lenmode="fraction", thickness=18)


def _traces(go, pan: _Panels, axis_of: dict[str, str], i: int) -> list:
    """The traces of frame `i`: the frame, the height map, the surface, the pressure."""
    ext_x, ext_y, unit = pan.ext_x, pan.ext_y, pan.unit
    hh, hw = pan.heights[0].shape
    out = []
    if pan.frames is not None:
        fdx = ext_x / max(hw - 1, 1)
        out.append(go.Image(source=pan.frames[i], x0=0.0, y0=0.0, dx=fdx,
                            dy=ext_y / max(hh - 1, 1), xaxis=f"x{axis_of['frame']}",
                            yaxis=f"y{axis_of['frame']}", name="frame",
                            hoverinfo="skip"))
    out.append(go.Heatmap(z=pan.heights[i], x=pan.xs, y=pan.ys, coloraxis="coloraxis",
                          xaxis=f"x{axis_of['height']}", yaxis=f"y{axis_of['height']}",
                          name="height (mm)",
                          hovertemplate=f"x %{{x:.2f}} {unit}<br>y %{{y:.2f}} {unit}"
                          "<br>height %{z:.4f} mm<extra></extra>"))
    out.append(go.Surface(z=pan.surfaces[i], x=pan.sx, y=pan.sy, coloraxis="coloraxis",
                          name="surface", scene="scene"))
    if pan.pressures is not None:
        p = pan.pressures[i]
        out.append(go.Heatmap(z=p, x=_axis_mm(p.shape[1], ext_x),
                              y=_axis_mm(p.shape[0], ext_y), coloraxis="coloraxis2",
                              xaxis=f"x{axis_of['pressure']}",
                              yaxis=f"y{axis_of['pressure']}", name="pressure (kPa)",
                              hovertemplate="pressure %{z:.2f} kPa<extra></extra>"))
    return out


def _annotations(domain: dict[str, tuple[float, float]]) -> list[dict]:
    """The panels' titles (the surface's below the top row)."""
    annotations = []
    for name, label in (("frame", "tactile frame"), ("height", "height map (mm)"),
                        ("pressure", "pressure (kPa)")):
        if name in domain:
            annotations.append(dict(text=label, x=sum(domain[name]) / 2, y=1.0, xref="paper",
                                    yref="paper", xanchor="center", yanchor="bottom",
                                    showarrow=False, font=dict(size=14)))
    annotations.append(dict(text="3D surface (drag to rotate)", x=0.5, y=0.48, xref="paper",
                            yref="paper", xanchor="center", yanchor="bottom", showarrow=False,
                            font=dict(size=14)))
    return annotations


def write_viewer(path: str | Path, frames_bgr: np.ndarray | Sequence[np.ndarray] | None,
                 heights_mm: np.ndarray, *, mm_per_px: float | None,
                 pressure_kpa: np.ndarray | None = None, titles: Sequence[str] | None = None,
                 max_px: int | None = 160, active: int = 0) -> Path:
    """Write the viewer (:func:`viewer_figure`) as one self-contained HTML page.

    Parameters
    ----------
    path : str or Path
        The ``.html`` file (its folder is created).
    frames_bgr, heights_mm, mm_per_px, pressure_kpa, titles, max_px, active
        As :func:`viewer_figure`.

    Returns
    -------
    path : Path
        The page: Plotly's JavaScript inline (no CDN, no network), no animation
        on load, written through a temporary name.
    """
    fig = viewer_figure(frames_bgr, heights_mm, mm_per_px=mm_per_px,
                        pressure_kpa=pressure_kpa, titles=titles, max_px=max_px,
                        active=active)
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create the folder of {path}: {exc.strerror}") from None
    tmp = path.with_name(f".{path.name}.tmp")
    fig.write_html(str(tmp), include_plotlyjs=True, full_html=True, auto_play=False,
                   div_id="tactilevision-view", config={"responsive": True})
    tmp.replace(path)
    return path
