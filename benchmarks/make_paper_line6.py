"""Write ``sample_frames/paper_line6``: 50 synthetic presses on the paper's line (6).

The paper ("In-situ Mechanical Calibration for Vision-based Tactile Sensors")
reports only its fitted line, eq. (6): ``P/w = 5.2662 w/h + 3.4943`` N/mm with
h = 3.0 mm, a = 2.5 mm. This script puts ten presses at each gauge depth
(0.15, 0.30, 0.40, 0.50, 0.60 mm) on that line and adds small seeded noise:
0.4% of P (press-to-press scatter over the gel) plus 0.005 N (mean of the F/T
window). Then it fits the table and prints E and nu next to the paper's.

Run from the repository root::

    python benchmarks/make_paper_line6.py           # (re)write the folder, print the fit
    python benchmarks/make_paper_line6.py --check   # exit 1 if the files differ
"""

from __future__ import annotations

import argparse
import io
import sys
from pathlib import Path

import numpy as np

SEED = 20230601
SLOPE_N_PER_MM, INTERCEPT_N_PER_MM = 5.2662, 3.4943  # eq. (6)
H_MM, A_MM = 3.0, 2.5
DEPTHS_MM = (0.15, 0.30, 0.40, 0.50, 0.60)
PRESSES_PER_DEPTH = 10
REL_SD, ABS_SD_N = 0.004, 0.005
OUT = Path(__file__).resolve().parent.parent / "sample_frames" / "paper_line6"

COLUMNS = ("press", "indenter", "depth_mm", "force_n", "force_std_n", "fx_n", "fy_n",
           "time_s", "hold_s", "wait_s", "x_mm", "y_mm")

SESSION_TOML = """\
# Synthetic session of the demo table measurements.csv (see README.md).
[sensor]
name = "gelslim3"
gel_thickness_mm = 3.0      # h
gel_radius_mm = 15.0

[indenter]
radius_mm = 2.5             # a

[gauge_block]
depths_mm = [0.15, 0.30, 0.40, 0.50, 0.60]

[force_sensor]
rate_hz = 1000
window_samples = 200
"""


def measurements_csv(seed: int = SEED) -> str:
    """The demo table as CSV text (formats.md section 2), deterministic in `seed`.

    Presses go round the five indenters ten times (press 0 is the 0.15 mm one
    of round 0), each at a random point within 6 mm of the gel centre, 25 s
    apart. The first press has no ``wait_s`` (an empty cell).
    """
    rng = np.random.default_rng(seed)
    buf = io.StringIO()
    buf.write(",".join(COLUMNS) + "\n")
    press = 0
    for _ in range(PRESSES_PER_DEPTH):
        for k, w in enumerate(DEPTHS_MM):
            p_true = w * (SLOPE_N_PER_MM * w / H_MM + INTERCEPT_N_PER_MM)  # eq. (6), N
            p = p_true * (1 + REL_SD * rng.standard_normal()) + ABS_SD_N * rng.standard_normal()
            r, th = 6.0 * np.sqrt(rng.uniform()), rng.uniform(0, 2 * np.pi)
            fx, fy = 0.01 * rng.standard_normal(2)
            std = 0.012 + 0.002 * abs(rng.standard_normal())
            wait = "" if press == 0 else "24.0"
            buf.write(f"{press},{k + 1},{w:.2f},{p:.4f},{std:.4f},{fx:.4f},{fy:.4f},"
                      f"{25.0 * press:.1f},0.6,{wait},{r * np.cos(th):.2f},"
                      f"{r * np.sin(th):.2f}\n")
            press += 1
    return buf.getvalue()


def readme() -> str:
    """The folder's README.md text."""
    return (
        "Synthetic demo table, not a measurement: 50 presses (10 per depth 0.15, 0.30, "
        "0.40, 0.50, 0.60 mm) on the paper's fitted line (6), P/w = 5.2662 w/h + 3.4943 "
        f"N/mm with h = {H_MM} mm, a = {A_MM} mm, plus seeded noise ({REL_SD:.1%} of P and "
        f"{ABS_SD_N} N, numpy default_rng({SEED})); made by "
        "`python benchmarks/make_paper_line6.py`, checked by tests/test_cli_fit.py.\n"
    )


def main(argv: list[str] | None = None) -> int:
    """Write (or with ``--check`` compare) the folder, then print the fit."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--check", action="store_true", help="compare instead of writing")
    args = ap.parse_args(argv)
    files = {"measurements.csv": measurements_csv(), "session.toml": SESSION_TOML,
             "README.md": readme()}
    if args.check:
        stale = [n for n, t in files.items()
                 if not (args.out / n).is_file() or (args.out / n).read_text() != t]
        print("stale: " + ", ".join(stale) if stale else "up to date")
        return 1 if stale else 0
    args.out.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (args.out / name).write_text(text)
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # run from a checkout
    from tactilevision.io import read_measurements
    from tactilevision.mechanics import fit_indentation

    t = read_measurements(args.out / "measurements.csv")
    for ah, label in ((0.8, "a/h = 0.8 (paper)"), (None, "exact a/h")):
        f = fit_indentation(t.depth_mm, t.force_n, thickness_mm=t.thickness_mm,
                            radius_mm=t.radius_mm, a_over_h=ah, beta_table="paper")
        print(f"{label}: c = {f.c_n_per_mm:.4f} N/mm, beta = {f.beta:.4f}, "
              f"nu = {f.nu:.4f} {np.round(f.nu_ci95, 4)}, "
              f"E = {f.E_mpa:.4f} MPa {np.round(f.E_ci95_mpa, 4)}  "
              "(paper: nu = 0.4797, E = 0.1981 MPa at a/h = 0.8)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
