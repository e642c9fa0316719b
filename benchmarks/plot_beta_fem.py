"""The stored FEM beta table against the paper's relation (7): a figure and the numbers.

Writes ``docs/beta_fem.png`` (left: beta(nu) at a/h = 0.8 from our bonded
finite-strain FEM, secant and tangent, against relation (7); right: beta(nu)
at every tabulated a/h) and prints beta at a/h = 0.8 and 2.5/3, the paper's
relation at the same nu, and what the paper's beta = 1.5071 gives with our
tables.

Run: ``python benchmarks/plot_beta_fem.py [--out docs/beta_fem.png]`` (seconds).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from tactilevision.mechanics import PAPER_BETA_RELATION, beta, beta_relation
from tactilevision.mechanics._fem_tables import _load

PAPER_BETA = 5.2662 / 3.4943


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=Path("docs/beta_fem.png"))
    args = ap.parse_args()
    data = _load("beta_fem.npz")
    nu_grid, ah_grid = data["nu"], data["a_over_h"]
    print(f"table: {data['path']}, {data['meta']['command']!r}, {data['meta']['created']}, "
          f"incomplete sweeps {data['meta']['sweeps_incomplete']}")

    paper_nu = np.linspace(0.40, 0.499, 50)
    paper_beta = PAPER_BETA_RELATION.beta(paper_nu)
    print("\n a/h = 0.8, bonded punch: nu, beta secant, beta tangent, relation (7), "
          "secant / (7)")
    for nu in (0.30, 0.40, 0.42, 0.45, 0.47, 0.48, 0.49, 0.495, 0.499):
        bs = beta(nu, 0.8)
        bt = beta(nu, 0.8, definition="tangent")
        p7 = PAPER_BETA_RELATION.beta(nu)
        print(f"  {nu:6.3f}  {bs:7.4f}  {bt:7.4f}  {p7:7.4f}  {bs / p7:6.3f}")
    for ah in (0.8, 2.5 / 3.0):
        rel = beta_relation("fem", a_over_h=ah)
        print(f"\n a/h = {ah:.4f}: FEM {rel.range_text()}; the paper's beta {PAPER_BETA:.4f} "
              f"{'is inside' if rel.beta_min <= PAPER_BETA < rel.beta_max else 'is outside'}")
    big = ah_grid[np.argmax(data["beta_secant"][0, :, -1] >= PAPER_BETA)]
    print(f" smallest tabulated a/h whose beta(nu = {nu_grid[-1]}) reaches {PAPER_BETA:.4f}: "
          f"{big:g}")

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    nu_fine = np.linspace(nu_grid[0], nu_grid[-1], 200)
    ax0.plot(paper_nu, paper_beta, "k-", lw=2, label="paper, relation (7)")
    ax0.plot(nu_fine, beta(nu_fine, 0.8), "C0-", label="FEM bonded, secant (eq. 5)")
    ax0.plot(nu_fine, beta(nu_fine, 0.8, definition="tangent"), "C0--",
             label="FEM bonded, tangent")
    ax0.plot(nu_grid, [beta(n, 0.8) for n in nu_grid], "C0o", ms=4)
    ax0.axhline(PAPER_BETA, color="C3", lw=1, ls=":",
                label=f"paper's data, beta = {PAPER_BETA:.3f}")
    ax0.set(xlabel="Poisson's ratio nu", ylabel="beta", title="a/h = 0.8")
    ax0.legend(fontsize=8)
    ax0.grid(alpha=0.3)
    cmap = plt.get_cmap("viridis")
    for i, ah in enumerate(ah_grid):
        ax1.plot(nu_grid, data["beta_secant"][0, i], "-o", ms=2.5,
                 color=cmap(i / max(len(ah_grid) - 1, 1)), label=f"{ah:g}")
    ax1.axhline(PAPER_BETA, color="C3", lw=1, ls=":")
    ax1.set(xlabel="Poisson's ratio nu", ylabel="secant beta", title="FEM, bonded punch, by a/h")
    ax1.legend(title="a/h", fontsize=7, ncol=2)
    ax1.grid(alpha=0.3)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
