"""``tactilevision view``: the self-contained HTML viewer (Plotly), its data, a real browser."""

from __future__ import annotations

import base64
import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("plotly")

from tactilevision.cli import main
from tactilevision.viz import downsample_map, write_viewer

ROOT = Path(__file__).resolve().parents[1]
FRAMES = ROOT / "sample_frames" / "gelsight_ball" / "frames"
DIV = "tactilevision-view"


def _decode(v):
    """A Plotly JSON array (a list, or a base64 typed array) as an ndarray."""
    if isinstance(v, dict) and "bdata" in v:
        a = np.frombuffer(base64.b64decode(v["bdata"]), dtype=np.dtype(v["dtype"]))
        if "shape" in v:
            a = a.reshape([int(s) for s in str(v["shape"]).split(",")])
        return a
    return np.asarray(v)


def _page(html: str) -> tuple[list, dict, list]:
    """(data, layout, frames) of the figure in a page written by write_viewer."""
    dec = json.JSONDecoder()
    i = html.index("Plotly.newPlot(")
    i = html.index("[", html.index(f'"{DIV}"', i))
    data, j = dec.raw_decode(html, i)
    layout, _ = dec.raw_decode(html, html.index("{", j))
    k = html.index("[", html.index(f"Plotly.addFrames('{DIV}'"))
    frames, _ = dec.raw_decode(html, k)
    return data, layout, frames


@pytest.fixture(scope="module")
def sample_page(tmp_path_factory):
    out = tmp_path_factory.mktemp("view") / "view.html"
    assert main(["view", str(FRAMES), "--sensor", "gelsight", "--out", str(out)]) == 0
    return out


def test_sample_page_is_self_contained_with_one_step_per_frame(sample_page):
    html = sample_page.read_text()
    assert not re.search(r"<script[^>]+src=[\"']?https?://", html)
    assert "plotly.js" in html.lower() and len(html) > 3_000_000     # Plotly's JS inline
    data, layout, frames = _page(html)
    n = len(list((FRAMES).glob("press_*.png")))
    assert len(frames) == n == 4
    assert len(layout["sliders"][0]["steps"]) == n
    assert [t["type"] for t in data] == ["image", "heatmap", "surface"]
    assert layout["coloraxis"]["colorbar"]["title"]["text"] == "height (mm)"


def test_sample_heights_equal_the_reconstructor(sample_page):
    from tactilevision import default_calibration_path
    from tactilevision.io import find_reference, list_frames, read_frame, read_reference
    from tactilevision.optics import DepthReconstructor, PhotometricCalibration

    cal = PhotometricCalibration.load(default_calibration_path("gelsight"))
    recon = DepthReconstructor(cal, reference=read_reference(find_reference(FRAMES), cal.shape))
    heights = [recon(read_frame(p, cal.shape)) for p in list_frames(FRAMES)]
    _, layout, frames = _page(sample_page.read_text())
    for h, fr in zip(heights, frames, strict=True):
        z = _decode(fr["data"][1]["z"])
        want = downsample_map(h, 160)
        assert z.shape == want.shape and max(z.shape) == 160
        np.testing.assert_allclose(z, want, rtol=1e-5, atol=1e-6)
    lo = min(float(h.min()) for h in heights)
    hi = max(float(h.max()) for h in heights)
    assert layout["coloraxis"]["cmin"] == pytest.approx(lo, rel=1e-5)
    assert layout["coloraxis"]["cmax"] == pytest.approx(hi, rel=1e-5)


def _zarr_group(path: Path, heights: np.ndarray, pressure: np.ndarray | None = None) -> Path:
    zarr = pytest.importorskip("zarr")
    g = zarr.open_group(str(path), mode="w")
    a = g.create_array("height_mm", shape=heights.shape, dtype="float32")
    a[...] = heights
    if pressure is not None:
        p = g.create_array("pressure_kpa", shape=pressure.shape, dtype="float32")
        p[...] = pressure
    return path


def test_zarr_colour_scale_spans_the_data(tmp_path, capsys):
    yy, xx = np.mgrid[0:30, 0:40]
    heights = np.stack([0.1 * k * np.exp(-((xx - 20) ** 2 + (yy - 15) ** 2) / 50.0)
                        for k in range(1, 6)]).astype(np.float32) - 0.05
    pressure = (heights * 100).clip(0)
    g = _zarr_group(tmp_path / "press.zarr", heights, pressure)
    out = tmp_path / "z.html"
    assert main(["view", str(g), "--out", str(out), "--max-frames", "3"]) == 0
    data, layout, frames = _page(out.read_text())
    assert [t["type"] for t in data] == ["heatmap", "surface", "heatmap"]     # no frame
    assert len(frames) == 3 == len(layout["sliders"][0]["steps"])
    picked = heights[[0, 2, 4]]
    assert layout["coloraxis"]["cmin"] == pytest.approx(float(picked.min()), rel=1e-6)
    assert layout["coloraxis"]["cmax"] == pytest.approx(float(picked.max()), rel=1e-6)
    assert layout["coloraxis2"]["cmax"] == pytest.approx(float(pressure[[0, 2, 4]].max()),
                                                         rel=1e-6)
    np.testing.assert_allclose(_decode(frames[2]["data"][0]["z"]), heights[4], rtol=1e-6)


@pytest.mark.parametrize("kind", ["missing", "text", "zarr_without_height"])
def test_bad_inputs_exit_2_naming_the_path(tmp_path, capsys, kind):
    if kind == "missing":
        src = tmp_path / "nowhere"
    elif kind == "text":
        src = tmp_path / "notes.txt"
        src.write_text("not frames\n")
    else:
        zarr = pytest.importorskip("zarr")
        src = tmp_path / "empty.zarr"
        zarr.open_group(str(src), mode="w").create_array("other", shape=(2,), dtype="f4")
    out = tmp_path / "v.html"
    assert main(["view", str(src), "--sensor", "gelsight", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(src) in err and "Traceback" not in err
    assert not out.exists()


# ----------------------------------------------------------------------------- real browser
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
WINDOW = (1200, 1000)


def _chromium(args: list[str], page: Path, budget_ms: int = 5000
              ) -> subprocess.CompletedProcess:
    if CHROMIUM is None:
        pytest.skip("no chromium binary on PATH (apt-get install chromium)")
    return subprocess.run([CHROMIUM, "--headless=new", "--no-sandbox", "--disable-gpu",
                           "--disable-dev-shm-usage", f"--window-size={WINDOW[0]},{WINDOW[1]}",
                           f"--virtual-time-budget={budget_ms}", "--enable-logging=stderr",
                           "--v=0",
                           *args, page.resolve().as_uri()],
                          capture_output=True, text=True, timeout=90)


def _panel_px(domain_x, domain_y, layout) -> tuple[slice, slice]:
    """Inner 60 % of a panel's paper domain in screenshot pixels (8 px body margin)."""
    m = layout["margin"]
    w = WINDOW[0] - 16 - 15 - m["l"] - m["r"]        # body margins, scroll bar
    h = layout["height"] - m["t"] - m["b"]
    x0, x1 = (8 + m["l"] + f * w for f in domain_x)
    y0, y1 = (8 + m["t"] + (1 - f) * h for f in reversed(domain_y))
    dx, dy = 0.2 * (x1 - x0), 0.2 * (y1 - y0)
    return slice(int(y0 + dy), int(y1 - dy)), slice(int(x0 + dx), int(x1 - dx))


#: Appended to a viewer page for the browser test: once Plotly has drawn the page, a click
#: (a mouse press and release, as DOM events) at the right end of the frame slider's rail;
#: then, every 200 ms, the clicks made, the slider's active step and the column of the
#: drawn height map's peak (Plotly's calcdata) written into the page title, which the
#: DOM dump shows at the end of the time budget.
CLICK_LAST_STEP = """
<script>
(function () {
  var clicks = 0;
  function peak(gd) {
    var z = gd.calcdata.map(function (c) { return c[0]; })
      .filter(function (c) { return c.trace.type === 'heatmap'; })[0].z;
    var best = -1, col = -1;
    for (var i = 0; i < z.length; i++) for (var j = 0; j < z[i].length; j++)
      if (z[i][j] > best) { best = z[i][j]; col = j; }
    return col;
  }
  function tick() {
    var gd = document.querySelector('.js-plotly-plot');
    var rail = document.querySelector('.slider-rail-touch-rect');
    if (!gd || !rail || !gd.calcdata) { setTimeout(tick, 200); return; }
    var active = gd.layout.sliders[0].active;
    if (active !== 2 && clicks < 5) {
      var r = rail.getBoundingClientRect();
      var at = {bubbles: true, cancelable: true, view: window, buttons: 1,
                clientX: r.right - 3, clientY: r.top + r.height / 2};
      rail.dispatchEvent(new MouseEvent('mousedown', at));
      window.dispatchEvent(new MouseEvent('mouseup', at));
      clicks += 1;
    }
    document.title = 'clicks ' + clicks + ', active step ' + active +
      ', peak at column ' + peak(gd);
    setTimeout(tick, 200);
  }
  window.addEventListener('load', function () { setTimeout(tick, 500); });
})();
</script>
"""


def _clicked_title(page: Path) -> tuple[str, str]:
    """The page title after the scripted click (``--dump-dom`` with a 30 s time budget),
    and the DOM.

    Whether the redraw after the click lands within headless Chromium's virtual time
    budget is not certain: the slider's step is taken at once, but Plotly draws the new
    frame on an animation frame, which virtual time does not always reach (measured: 20
    of 20 runs on one machine; 8 of 9 on another, idle, where the ninth showed the step
    taken and the old frame still drawn; a clean-clone run on 2026-11-25 saw three such
    runs in a row). Such a run is repeated, up to six runs.
    """
    dom = None
    for _ in range(6):
        dom = _chromium(["--dump-dom"], page, budget_ms=30000)
        assert dom.returncode == 0, dom.stderr[-2000:]
        assert "Uncaught" not in dom.stderr, dom.stderr[-2000:]
        title = re.search(r"<title>(clicks .*?)</title>", dom.stdout)
        if title and not title[1].endswith("peak at column 15"):
            break
    return (title[1] if title else dom.stdout[:300]), dom.stdout


@pytest.mark.slow
def test_page_renders_in_chromium_and_the_slider_changes_the_frame(tmp_path):
    import cv2

    from tactilevision.viz import viewer_figure

    if CHROMIUM is None:
        pytest.skip("no chromium binary on PATH (apt-get install chromium)")
    yy, xx = np.mgrid[0:60, 0:80]
    heights = np.stack([np.exp(-((xx - cx) ** 2 + (yy - 30) ** 2) / 60.0)
                        for cx in (15, 40, 65)]).astype(np.float32)
    frames = np.repeat((heights[..., None] * 200).astype(np.uint8), 3, axis=3)
    first = write_viewer(tmp_path / "first.html", frames, heights, mm_per_px=0.05)
    last = write_viewer(tmp_path / "last.html", frames, heights, mm_per_px=0.05, active=2)

    # the page drawn (2D and WebGL), and a click on the slider: the last step, and its
    # frame's bump (x = 65) drawn
    clicked = tmp_path / "clicked.html"
    clicked.write_text(first.read_text().replace("</body>", CLICK_LAST_STEP + "</body>"))
    title, dom = _clicked_title(clicked)
    assert "main-svg" in dom and "<canvas" in dom
    assert title == "clicks 1, active step 2, peak at column 65"

    shots = []
    for page in (first, last):
        png = tmp_path / f"{page.stem}.png"
        r = _chromium([f"--screenshot={png}"], page)
        assert r.returncode == 0 and png.is_file(), r.stderr[-2000:]
        assert "Uncaught" not in r.stderr, r.stderr[-2000:]
        shots.append(cv2.imread(str(png))[..., ::-1].astype(int))      # RGB
    layout = viewer_figure(frames, heights, mm_per_px=0.05).layout.to_plotly_json()
    rows, cols = _panel_px(layout["xaxis2"]["domain"], layout["yaxis2"]["domain"], layout)
    a, b = shots[0][rows, cols], shots[1][rows, cols]
    assert np.abs(a - b).sum(axis=2).max() > 100        # the height map moved
    assert np.mean(np.abs(a - b).sum(axis=2) > 60) > 0.05

    # the colour bar: right of the height panel, yellow (Viridis' max) on top, purple below
    bar = layout["coloraxis"]["colorbar"]
    m = layout["margin"]
    w = WINDOW[0] - 16 - 15 - m["l"] - m["r"]
    bx = int(8 + m["l"] + bar["x"] * w)
    strip = shots[0][8 + m["t"]: 8 + m["t"] + int(0.5 * layout["height"]), bx - 10: bx + 40]
    top_c, bottom_c = np.array([253, 231, 37]), np.array([68, 1, 84])
    near_top = np.argwhere(np.abs(strip - top_c).sum(axis=2) < 40)
    near_bottom = np.argwhere(np.abs(strip - bottom_c).sum(axis=2) < 40)
    assert len(near_top) > 20 and len(near_bottom) > 20
    assert near_top[:, 0].mean() < near_bottom[:, 0].mean()     # max on top
