"""Shared fixtures.

mechanics (tests/test_mechanics_*.py): ``hand_kappa``, kappa of the Hayes 1972
table interpolated by the documented rule written out by hand (no scipy).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import cv2
import pytest
from threadpoolctl import threadpool_limits

#: The suite's own disk cache (FEM sweeps, MLP tables, Taxim renders), apart from the
#: user's (``$TACTILEVISION_CACHE`` or ``~/.cache/tactilevision``), which the suite never
#: writes; ``$TACTILEVISION_SUITE_CACHE`` moves it. Set before any test runs: the workers
#: and every command the tests start inherit it.
SUITE_CACHE = Path(os.environ.get("TACTILEVISION_SUITE_CACHE",
                                  Path.home() / ".cache" / "tactilevision-suite"))
os.environ["TACTILEVISION_CACHE"] = str(SUITE_CACHE)

_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
#: the worker's thread limit (threadpoolctl's handle), kept for the session
_LIMITS = pytest.StashKey[object]()


def pytest_configure(config):
    """One compute thread per xdist worker: the workers already fill the cores, and
    BLAS, OpenMP and OpenCV threads on top of them contend (two workers of two OpenBLAS
    threads each ran numpy's solves 2.3x slower than of one). Subprocesses inherit it."""
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        return
    for var in _THREAD_VARS:
        os.environ[var] = "1"
    config.stash[_LIMITS] = threadpool_limits(1)
    cv2.setNumThreads(1)


# Hayes et al. 1972 kappa as listed in method.md, typed independently of the
# package: rows a/h, columns nu.
HAYES_AH = (0.2, 0.4, 0.6, 0.8, 1.0, 1.5, 2.0)
HAYES_NU = (0.30, 0.35, 0.40, 0.45, 0.50)
HAYES_ROWS = (
    (1.207, 1.218, 1.232, 1.252, 1.281),
    (1.472, 1.502, 1.542, 1.599, 1.683),
    (1.784, 1.839, 1.917, 2.031, 2.211),
    (2.124, 2.211, 2.337, 2.532, 2.855),
    (2.480, 2.603, 2.789, 3.085, 3.609),
    (3.400, 3.629, 3.994, 4.645, 6.033),
    (4.336, 4.679, 5.249, 6.332, 8.980),
)


def _pchip(xs, ys, x):
    """Piecewise cubic Hermite with Fritsch-Butland slopes (Moler's pchip).

    Interior slope: weighted harmonic mean of the adjacent secants,
    ``(w1 + w2) / (w1 / m_left + w2 / m_right)`` with ``w1 = 2 h_right + h_left``,
    ``w2 = h_right + 2 h_left`` (0 when the secants differ in sign or one is 0).
    End slope: one-sided three-point ``((2 h0 + h1) m0 - h0 m1) / (h0 + h1)``,
    set to 0 if its sign differs from m0, to 3 m0 if m0, m1 differ in sign and
    it exceeds 3 |m0|.
    """
    n = len(xs)
    h = [xs[k + 1] - xs[k] for k in range(n - 1)]
    m = [(ys[k + 1] - ys[k]) / h[k] for k in range(n - 1)]
    d = [0.0] * n
    for k in range(1, n - 1):
        if m[k - 1] * m[k] > 0:
            w1, w2 = 2 * h[k] + h[k - 1], h[k] + 2 * h[k - 1]
            d[k] = (w1 + w2) / (w1 / m[k - 1] + w2 / m[k])

    def end(h0, h1, m0, m1):
        e = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
        if math.copysign(1, e) != math.copysign(1, m0):
            return 0.0
        if math.copysign(1, m0) != math.copysign(1, m1) and abs(e) > 3 * abs(m0):
            return 3 * m0
        return e

    d[0] = end(h[0], h[1], m[0], m[1])
    d[-1] = end(h[-1], h[-2], m[-1], m[-2])
    k = min(max(next(i for i in range(n - 1) if x <= xs[i + 1]), 0), n - 2)
    t = (x - xs[k]) / h[k]
    h00, h10 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t
    h01, h11 = -2 * t**3 + 3 * t**2, t**3 - t**2
    return h00 * ys[k] + h10 * h[k] * d[k] + h01 * ys[k + 1] + h11 * h[k] * d[k + 1]


def _hand_kappa(nu: float, a_over_h: float) -> float:
    """The documented rule: PCHIP along nu within each a/h row, then along a/h."""
    col = [_pchip(HAYES_NU, row, nu) for row in HAYES_ROWS]
    return _pchip(HAYES_AH, col, a_over_h)


@pytest.fixture
def hand_kappa():
    """kappa(nu, a_over_h) from the Hayes table by the rule written out by hand."""
    return _hand_kappa


@pytest.fixture
def hayes_table():
    """(a_over_h, nu, rows) of the Hayes 1972 table, typed from method.md."""
    return HAYES_AH, HAYES_NU, HAYES_ROWS


# optics fixtures
@pytest.fixture(scope="session")
def torch_one_thread():
    """Train networks on one torch thread: small nets on a loaded 2-core machine
    run ~50x slower with two contending OpenMP threads."""
    torch = pytest.importorskip("torch")
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.fixture(scope="session")
def taxim_presses():
    """The taxim GelSight ball presses (48 frames, hand-annotated circles), read once."""
    from tactilevision.io import read_ball_presses, taxim_datapack

    return read_ball_presses(taxim_datapack())


@pytest.fixture(scope="session")
def taxim_lut(taxim_presses):
    """LUT calibration on the even taxim presses with their annotated circles."""
    from tactilevision.optics import PhotometricCalibration

    ps = taxim_presses
    return PhotometricCalibration.from_ball_presses(
        ps.reference, ps.frames[0::2], ps.centers_px[0::2], ps.radii_px[0::2],
        ball_radius_mm=2.0, mm_per_px=0.0295, model="lut", source="taxim dataPack.npz")


#: Test files by their measured time from an empty suite cache, longest first (``pytest
#: --durations=0``, summed per file: 646 s in all on this project's 2-core machine;
#: test_calibrate.py 52 s, test_validate.py 39, test_fem_sphere.py 36,
#: test_fem_sphere_dome.py 29; test_config_strict.py's 30 s since cut to 9). pytest-xdist
#: hands out whole files (``--dist loadfile``) in collection order
#: (``--no-loadscope-reorder`` in pyproject.toml): the long files first and the many short
#: ones after fill the two workers evenly, where the default order (files with the most
#: tests first) left the longest files to the end, one worker busy alone. test_ball_caps.py
#: is left to the end: its thick gel's FEM sweep is test_ball_depths.py's, read from the
#: cache by then.
LONGEST_FIRST = (
    "test_calibrate.py", "test_validate.py", "test_fem_sphere.py", "test_fem_sphere_dome.py",
    "test_plan.py", "test_ball_depths.py", "test_vernier_taxim.py", "test_forces_gelslim.py",
    "test_relaxation.py", "test_docs.py", "test_ball_texture.py", "test_fem_pad.py",
    "test_lut_mlp.py", "test_diagnose.py", "test_interrupts.py", "test_gs_sdk_net.py",
    "test_batch.py", "test_live.py", "test_gradient_window.py", "test_config_strict.py",
    "test_fem_linear.py", "test_cli_forces.py", "test_ball_fit.py", "test_structure.py",
    "test_diagnose_separation.py", "test_fem_forces.py", "test_cli_optics.py",
    "test_fem_beta_table.py", "test_forces_binning.py", "test_fem_finite.py",
    "test_fem_forces_proof.py", "test_optics_load_by_name.py", "test_crossing_statement.py",
    "test_history.py", "test_ramp.py", "test_fem_forces_grid.py", "test_noise_budget.py",
    "test_forces_box.py", "test_io_source.py",
)
#: Files run after every other (:data:`LONGEST_FIRST`'s note).
LAST = ("test_ball_caps.py",)


def pytest_collection_modifyitems(config, items):
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    rank.update({name: len(rank) + 1 + i for i, name in enumerate(LAST)})
    items.sort(key=lambda item: rank.get(item.path.name, len(LONGEST_FIRST)))  # stable
