"""Each indenter's depths off by one shared error: the diagnosis with the depths taken as
independent against generalized least squares under the stated shared part.

    python benchmarks/bench_shared_indenter.py [--seeds 6]

Tables: the generator's (``tactilevision.sim.make_measurement_table``) with the presses at
one depth made one indenter's, each indenter's depths moved by one error (sd 15 um, as a
mark's P(w0) crossing moves them) and the shared part stated as ``calibrate`` states it
(``depth_indenter_std_mm``; ``tests/test_diagnose.py``'s ``_shared_by_indenter``). For
each hidden effect and seed: the verdict of ``diagnose_core`` on the table without the
column's use (the depths independent) and of ``diagnose`` (GLS under it), and how many
seeds name the hidden effect (its catalogue name or the step/trend along its column).
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_diagnose import _shared_by_indenter

from tactilevision.diagnosis import diagnose
from tactilevision.diagnosis._diagnose import diagnose_core

#: hidden effect -> what counts as naming it
RIGHT = {None: (None,), "stiffness_step": ("stiffness_step:press",),
         "force_drift": ("force_drift",), "spatial_nonuniformity": ("spatial_nonuniformity",)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=6)
    args = ap.parse_args()
    print(f"machine: {platform.machine()}, python {platform.python_version()}")
    t0 = time.perf_counter()
    for hidden, right in RIGHT.items():
        hits = [0, 0]
        for seed in range(args.seeds):
            t, c = _shared_by_indenter(hidden, seed)
            kw = dict(thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                verdicts = [diagnose_core(c, **kw), diagnose(c, **kw, rules_out=False)]
            row = []
            for i, d in enumerate(verdicts):
                v = d.missing_effect or (f"unexplained {d.unexplained_covariate}"
                                         if d.unexplained_covariate else None)
                ok = d.missing_effect in right and (hidden is not None
                                                    or d.unexplained_covariate is None)
                hits[i] += ok
                row.append(v)
            print(f"{hidden or 'null'} seed {seed}: independent {row[0]}; GLS {row[1]}")
        print(f"{hidden or 'null'}: right in {hits[0]} of {args.seeds} with the depths "
              f"independent, {hits[1]} of {args.seeds} under GLS")
    print(f"{time.perf_counter() - t0:.0f} s in all")


if __name__ == "__main__":
    main()
