"""Calibration of the effect models' standard errors (issue 5, part 1).

    python benchmarks/bench_effect_fits.py [SEEDS]

For every catalogue effect: synthetic tables from the effect's own form
(tests/test_mechanics_model.py's covariates and parameters), 2 mN noise, fit
the base + effect; prints how often a parameter lies beyond 2 and 4 standard
errors of the truth (a Gaussian would give about 5% and 0.006%).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_mechanics_model import BETA, TRUTH, C, _table

from tactilevision.mechanics import IndentationModel


def main() -> None:
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    for name in sorted(TRUTH):
        z = []
        for seed in range(seeds):
            d, rng = _table(seed=seed + 100)
            model = IndentationModel().with_effect(name)
            params = {"c_n_per_mm": C, "large_deformation.beta": BETA}
            params.update({f"{name}.{k}": v for k, v in TRUTH[name].items()})
            d["force_n"] = model.predict(params, d, 3.0) + rng.normal(0, 0.002, d["depth_mm"].size)
            f = model.fit(d, thickness_mm=3.0)
            z += [abs(f.params[k] - v) / f.stderr[k] for k, v in params.items()]
        z = np.array(z)
        print(f"{name:32s} {z.size:4d} parameters: beyond 2 se {100 * np.mean(z > 2):5.1f}%, "
              f"beyond 4 se {100 * np.mean(z > 4):4.1f}%, max {z.max():.2f} se")


if __name__ == "__main__":
    main()
