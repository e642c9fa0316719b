"""
# E and nu from presses on the paper's line

`sample_frames/paper_line6/measurements.csv` holds 50 presses on the line (6)
of the in-situ calibration paper, with seeded noise. With the paper's own
sources (Hayes' kappa, relation (7) for beta) the fit gives back the paper's
E = 0.1981 MPa and nu = 0.4797.
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from tactilevision.io import read_measurements
from tactilevision.mechanics import fit_indentation

HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
TABLE = next(p for p in (HERE.parent / "sample_frames", Path("sample_frames"))
             if p.is_dir()) / "paper_line6" / "measurements.csv"

m = read_measurements(TABLE)
w, P = m.depth_mm, m.force_n
fit = fit_indentation(w, P, thickness_mm=3.0, radius_mm=2.5, beta_table="paper", a_over_h=0.8)
print(f"E  = {fit.E_mpa:.4f} MPa  95% CI [{fit.E_ci95_mpa[0]:.4f}, {fit.E_ci95_mpa[1]:.4f}]")
print(f"nu = {fit.nu:.4f}      95% CI [{fit.nu_ci95[0]:.4f}, {fit.nu_ci95[1]:.4f}]")

# %%
# Eq. (5): P/w is a straight line in w/h; its intercept is c, its slope c beta.
wh = np.linspace(0, w.max() / 3.0 * 1.05, 50)
fig, ax = plt.subplots(figsize=(6, 3.4))
ax.plot(w / 3.0, P / w, ".", label="presses")
ax.plot(wh, fit.c_n_per_mm * (1 + fit.beta * wh), label=f"fit: c = {fit.c_n_per_mm:.3f} N/mm, "
        f"beta = {fit.beta:.3f}")
ax.set_xlabel("w / h")
ax.set_ylabel("P / w (N/mm)")
ax.legend()
fig.tight_layout()
plt.show()
