"""The crossing forces' brackets read as intervals: the likelihood of a within-indenter change
against closed forms worked by hand, and the null's brackets against their definition."""

from __future__ import annotations

import math

import numpy as np

from tactilevision.diagnosis._brackets import (
    BRACKET_DELTAS,
    BRACKET_SOFTNESS,
    bracket_draws,
    bracket_gains,
)


def test_two_brackets_gain_the_log_of_their_best_overlap():
    """One indenter, brackets [0.9, 1.1] and [1.0, 1.2], the second press changed by delta:
    in log force it is [0, log 1.2] - log(1 + delta), which lies inside the first's [log
    0.9, log 1.1] for 1 + delta in [1.2 / 1.1, 1 / 0.9]: an overlap of log 1.2, against
    log 1.1 with no change; so the best gain is log(log 1.2 / log 1.1) = 0.649, at delta =
    1/11 (the first of the plateau). The softened edges change it by under 1e-6 (overlaps
    25 softness widths). An indenter whose presses all change alike gains nothing."""
    lo, hi = np.array([[0.9, 1.0]]), np.array([[1.1, 1.2]])
    fine = np.r_[0.0, np.linspace(-0.3, 0.3, 60001)]
    gain, delta = bracket_gains(lo, hi, np.array([0, 0]), np.array([[0.0, 1.0]]), fine)
    assert abs(gain[0, 0] - math.log(math.log(1.2) / math.log(1.1))) < 1e-6
    assert abs(delta[0, 0] - (1.2 / 1.1 - 1)) < 2e-5
    # the same change as a trend shape (any shape, not only a step's zeros and ones)
    gain_t, _ = bracket_gains(lo, hi, np.array([0, 0]), np.array([[0.0, 0.999999]]), fine)
    assert abs(gain_t[0, 0] - gain[0, 0]) < 1e-4
    same, _ = bracket_gains(lo, hi, np.array([0, 0]), np.array([[1.0, 1.0]]), fine)
    assert abs(same[0, 0]) < 1e-12


def test_disjoint_indenters_are_joined_by_the_change_that_made_them():
    """Two indenters, each with one press before and one after a 20 % fall: the brackets
    after lie 0.8 times those before, so no force lies in both (no overlap: the softened
    edges' likelihood only), and delta = -0.2 overlaps them fully again: the gain is at
    least log(0.08 / softness's scale) per indenter and the best delta is -0.2."""
    before = np.array([0.95, 1.95])
    lo = np.r_[before, 0.8 * before][None]
    hi = np.r_[before + 0.1, 0.8 * (before + 0.1)][None]
    groups = np.array([0, 1, 0, 1])
    shape = np.array([[0.0, 0.0, 1.0, 1.0]])
    gain, delta = bracket_gains(lo, hi, groups, shape, np.linspace(-0.3, 0.3, 601))
    assert abs(delta[0, 0] - (-0.2)) < 1e-9
    assert gain[0, 0] > 2 * math.log(0.08 / (BRACKET_SOFTNESS * 0.1))
    # the default grid (sizes 20 % apart, 0 among them) lands within a step of it
    _, coarse = bracket_gains(lo, hi, groups, shape)
    assert np.any(BRACKET_DELTAS == 0.0) and abs(coarse[0, 0] / -0.2 - 1) < 0.1


def test_the_nulls_brackets_hold_the_force_at_a_uniform_place():
    """bracket_draws: widths as given, the force 1 inside all but the jittered few (the
    jitter's sd is 2 % of the width, so E|jitter| / width = 0.02 sqrt(2 / pi) = 1.6 % of
    brackets just miss it: 1.59 % of these), and its place in the bracket uniform (a
    quarter in each quarter)."""
    w = np.array([0.1, 0.2, 0.3])
    lo, hi = bracket_draws(w, 40000, np.random.default_rng(0))
    assert np.allclose(hi - lo, w)
    inside = (lo <= 1.0) & (1.0 <= hi)
    assert 0.979 < inside.mean() < 0.989
    place = (1.0 - lo) / w
    counts = np.histogram(place[inside], bins=4, range=(0, 1))[0] / inside.sum()
    assert np.all(np.abs(counts - 0.25) < 0.02), counts


def _grid_by_hand(lo, hi, groups, z, deltas):
    """The log-likelihood of one set of brackets at every delta, written from the module's
    definition (no code of it): per indenter the softened length of the intersection of
    its brackets in log force, each shifted by -log(1 + delta z), and their sum."""
    llo, lhi = np.log(lo), np.log(hi)
    out = np.zeros(deltas.size)
    for g in np.unique(groups):
        m = groups == g
        soft = BRACKET_SOFTNESS * float(np.mean(lhi[m] - llo[m]))
        for i, d in enumerate(deltas):
            shift = np.log1p(d * z[m])
            length = np.min(lhi[m] - shift) - np.max(llo[m] - shift)
            out[i] += np.log(soft * np.logaddexp(0.0, length / soft))
    return out


def test_a_steps_best_size_is_the_grids():
    """A step (a shape of zeros and ones) is searched by bisection, not on every size: on
    random brackets of 4 indenters with and without a change, its gain is the hand-written
    grid's largest (within 1e-9), the size it names reaches that largest, and where no
    change reaches more than none (a plateau holding 0) the size is 0."""
    rng = np.random.default_rng(3)
    groups = np.repeat(np.arange(4), 4)[rng.permutation(16)]
    zeros_named = plateaus = 0
    for trial in range(60):
        z = (np.arange(16) >= rng.integers(3, 13)).astype(float)
        lo = rng.uniform(0.8, 1.0, 16) * (1.0 + rng.choice([0.0, 0.1, -0.15]) * z)
        hi = lo * (1.0 + rng.uniform(0.02, 0.3, 16))
        ll = _grid_by_hand(lo, hi, groups, z, BRACKET_DELTAS)
        gain, delta = bracket_gains(lo[None], hi[None], groups, z[None])
        zero = int(np.flatnonzero(BRACKET_DELTAS == 0.0)[0])
        assert abs(gain[0, 0] - (ll.max() - ll[zero])) < 1e-9, trial
        at = int(np.flatnonzero(BRACKET_DELTAS == delta[0, 0])[0])
        assert ll[at] > ll.max() - 1e-9, trial
        if ll[zero] > ll.max() - 1e-12:
            zeros_named += delta[0, 0] == 0.0
            plateaus += 1
    assert plateaus >= 3 and zeros_named == plateaus, (plateaus, zeros_named)
