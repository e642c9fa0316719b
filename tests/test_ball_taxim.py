"""A ball's depths and E from frames drawn by Taxim's own renderer (no shading of ours):
dead weights on a thick gel, Sneddon's closed form for each mass's contact radius, depth and
surface (``tests/_data.taxim_dead_weights``); ``benchmarks/bench_ball_taxim.py`` runs the
same over 20 seeds (E's interval held the truth in 20 of 20, E 4 to 16 % high)."""

from __future__ import annotations

import numpy as np
import pytest

from tactilevision.pipeline import calibrate_dead_weights

E = 1.0


@pytest.fixture(scope="module")
def taxim_weights(tmp_path_factory):
    pytest.importorskip("taxim", reason="Taxim's renderer is in the test extra")
    pytest.importorskip("jax", reason="Taxim's jax backend is in the test extra")
    from _data import flat_gel_taxim, taxim_dead_weights

    folder = tmp_path_factory.mktemp("taxim_weights") / "w"
    with flat_gel_taxim() as sim:
        w, a = taxim_dead_weights(sim, folder, E_mpa=E, seed=0)
    return folder, w, a


@pytest.mark.slow
def test_depths_from_taxims_frames_and_E_inside_its_interval(taxim_weights):
    """Every frame read; at most one depth (the detector's worst case, a 20 px circle) off
    by more than its stated bounds; E's interval holds the truth, E within 15 %."""
    folder, w, _ = taxim_weights
    cal = calibrate_dead_weights(folder, nu=0.5, law="linear")
    assert len(cal.used) == w.size
    d = cal.depths
    err = d.depth_mm - w[cal.used]
    outside = np.abs(err) > d.depth_shared_mm + 2 * d.depth_std_mm
    assert outside.sum() <= 1, err
    fit = cal.fit
    assert fit.E_ci95_mpa[0] <= E <= fit.E_ci95_mpa[1], fit.E_ci95_mpa
    assert abs(fit.E_mpa / E - 1) < 0.15, fit.E_mpa
