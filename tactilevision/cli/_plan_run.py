"""What ``tactilevision plan`` does once its options are parsed
(:mod:`tactilevision.cli._plan`): what a calibration session's design will measure, before
it runs.

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from .. import InputError
from ..contact import RESOLVED_PX
from ..io import DEPTH_TOLERANCE_MM, write_output_file
from ..mechanics import EFFECT_SIZE_PARAMS
from ..pipeline import depth_half95
from ..planning import (
    PlanPrediction,
    Recommendation,
    design_from_calibration,
    design_toml,
    plan_session,
    read_design,
    readable_overshoot_um,
    recommend,
)
from ._fit_run import _write_json

__all__ = ["run"]


def _certified_line(pred) -> str:
    """Whether calibrate will count the design's depths as certified: their 95 %
    half-width (:func:`~tactilevision.pipeline.depth_half95`, as calibrate states it)
    against ``[gauge_block] depth_tolerance_mm``'s default."""
    half = float(depth_half95(np.array([pred.depth_std_um]),
                              np.array([pred.depth_shared_um or 0.0]))[0])
    tol = 1e3 * DEPTH_TOLERANCE_MM
    if half <= tol:
        return (f"depths certified: 95 % within +-{half:.1f} um, inside calibrate's "
                f"+-{tol:.0f} um ([gauge_block] depth_tolerance_mm)")
    if pred.design.bevel_angle_deg > 0:
        how = (f"a stage stopping at least {readable_overshoot_um(pred.design):.0f} um past w0 "
               f"(a band of {RESOLVED_PX:g} px), or a shallower bevel, pins them; more frames "
               "or a slower approach do not")
    else:
        how = "more frames per second or a slower approach pins them"
    return (f"depths only bounded: 95 % within +-{half:.1f} um, past calibrate's +-{tol:.0f} "
            "um ([gauge_block] depth_tolerance_mm): it fits them with that weight but "
            f"certifies none; {how}")


def summary(pred) -> str:
    """The prediction in a few lines of text."""
    d = pred.design
    lines = [
        f"design: h {d.thickness_mm:g} mm, a {d.radius_mm:g} mm (a/h {d.a_over_h:.2f}), "
        f"{len(d.depths_mm)} depths x {d.repeats} repeats = {pred.n_presses} presses"
        + (" in the order and places of [plan] schedule" if d.schedule is not None else "")
        + f", E {d.E_mpa:.4g} MPa, nu {d.nu:.4g}",
        f"depth per press: sd {pred.depth_std_um:.2f} um random"
        + (f", up to {pred.depth_shared_um:.1f} um shared" if pred.depth_shared_um else "")
        + f" ({pred.depth_source}); force per press: sd {1e3 * pred.force_std_n:.2f} mN",
        _certified_line(pred),
        f"E: sd {pred.E_sigma_mpa:.4f} MPa ({pred.E_sigma_pct:.1f} %); nu: sd "
        f"{pred.nu_sigma:.4f}; their correlation {pred.E_nu_corr:+.2f}",
    ]
    for name, (e, n) in pred.bias.items():
        what = {"model": "the fit itself on the design's noise-free FEM forces",
                "noise": "the noise, through the fit's curvature (mean over sessions)",
                "depth_shared": f"a depth error of +{pred.depth_shared_um:.1f} um in every press",
                "depth_shared_minus": f"a depth error of -{pred.depth_shared_um:.1f} um in "
                                      "every press",
                "force_zero": f"a force offset of +{d.force_zero_n:.3g} N in every press",
                "force_zero_minus": f"a force offset of -{d.force_zero_n:.3g} N in every press",
                }[name]
        if math.isfinite(e) and math.isfinite(n):
            lines.append(f"bias from {what}: E {e:+.1f} %, nu {n:+.4f}")
        elif name == "depth_shared_minus" and pred.depth_shared_um >= 1e3 * min(d.depths_mm):
            lines.append(f"bias from {what}: no E or nu (the shallowest depth, "
                         f"{1e3 * min(d.depths_mm):.0f} um, would be gone)")
        else:
            lines.append(f"bias from {what}: no E or nu (beta beyond the beta table)")
    lines.append(_verdict(pred))
    for name, why in pred.untestable.items():
        lines.append(f"diagnose cannot test {name}: {why}")
    found = [s for s in pred.effect_sizes.values() if math.isfinite(s.size)
             or math.isinf(s.size)]
    if found:
        lines.append("smallest effects diagnose names in 95 % of sessions (catalogue "
                     "parameter; snr: over the replicate noise):")
        if any(s.why.startswith("from the crossing forces") for s in found):
            lost = (f", {100 * d.unseen_share:.3g} % of presses unseen"
                    if d.unseen_share > 0 else "")
            lines.append(f"  (sessions drawn: the crossing forces bracketed by "
                         f"{d.bracket_periods:.3g} frame periods of travel on average{lost}; "
                         "[plan] bracket_periods, unseen_share)")
        for s in found:
            snr = f"; snr {s.snr:.2g}" if math.isfinite(s.snr) else "; the crossing forces"
            lines.append(f"  {s.effect:24s} " + (
                f"{s.size:.3g}{' ' + s.unit if s.unit else ''} ({s.parameter} "
                f"{s.size_param:.3g}{snr})"
                if math.isfinite(s.size) else "not at any size its parameter allows"))
            if s.dip:
                lines.append(f"    ({s.dip})")
            if s.at_places:
                lines.append(f"    ({s.places_sentence()})")
    for name, p in pred.detect_power.items():
        size = dict(d.detect)[name]
        unit = EFFECT_SIZE_PARAMS[name][1]
        lines.append(f"{name} of {size:g}{' ' + unit if unit else ''}: named in "
                     f"{100 * p:.0f} % of sessions")
    if pred.relaxation is not None:
        lines.append(f"relaxation: {pred.relaxation.why}")
    lines += [f"note: {n}" for n in pred.notes]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Run ``plan``; returns 0 (2 through InputError on a bad design)."""
    if (args.design is None) == (args.from_calibration is None):
        raise InputError("give a design file or --from-calibration DIR (one of them)")
    if args.session is not None and args.from_calibration is None:
        raise InputError("--session goes with --from-calibration")
    design = (read_design(args.design) if args.design is not None
              else design_from_calibration(args.from_calibration, args.session))
    if args.write_design is not None:
        write_output_file(args.write_design, design_toml(design), overwrite=True)
    targets = args.target_E_pct is not None or args.target_nu is not None
    if args.write_recommended is not None and not targets:
        raise InputError("--write-recommended needs a target: --target-E-pct or --target-nu")
    for key, v in (("target_E_pct", args.target_E_pct), ("target_nu", args.target_nu)):
        # refused before the plan's work, as recommend() refuses it
        if v is not None and not (math.isfinite(v) and v > 0):
            raise InputError(f"{key} must be a positive number, got {v!r}")
    pred = plan_session(design)
    rec = (recommend(design, target_E_pct=args.target_E_pct, target_nu=args.target_nu)
           if args.recommend or targets else None)
    doc = pred.as_dict()
    if rec is not None:
        doc["recommendation"] = rec.as_dict()
    if rec is not None and args.write_recommended is not None:
        if rec.cheapest is None:
            raise InputError(f"no design file written to {args.write_recommended}: {rec.why}")
        write_output_file(args.write_recommended, design_toml(rec.cheapest.design),
                          overwrite=True)
    if args.json == "-":
        _write_json(doc, "-")
        return 0
    print(summary(pred))
    if rec is not None:
        print(recommendation_summary(rec))
    if args.json:
        _write_json(doc, args.json)
    return 0


def _verdict(pred: PlanPrediction) -> str:
    """The one identification verdict of a run: the scatter's and the shared errors'."""
    if not pred.nu_identified:
        return "nu NOT identified"
    if not pred.systematic_breaks:
        return "nu identified (with the shared errors at their bounds too)"
    what = {"depth_shared": f"a depth error of +{pred.depth_shared_um:.1f} um in every press",
            "depth_shared_minus": f"a depth error of -{pred.depth_shared_um:.1f} um in every "
                                  "press",
            "force_zero": "a force offset at its bound", "force_zero_minus":
            "a force offset at its bound"}
    causes = sorted({what.get(k, k) for k in pred.systematic_breaks})
    return (f"nu NOT identified: the presses' scatter alone would pin it (sd "
            f"{pred.nu_sigma:.4f}), but {' or '.join(causes)}, within the shared errors' "
            "bounds, takes beta beyond the beta table")


def _total(e: float, n: float) -> str:
    return ("nu not identified" if not math.isfinite(n) else
            f"E {e:.1f} %, nu {n:.4f}")


def recommendation_summary(rec: Recommendation) -> str:
    """The ranked changes and the cheapest design, in lines of text."""
    lines = [f"total error now (random and systematic): {_total(rec.E_total_pct, rec.nu_total)}"]
    if rec.changes:
        lines.append("changes, by predicted gain (the binding error's fall):")
    for c in rec.changes:
        if c.gains:
            gain = "nu identified" if math.isinf(c.gain) else f"{100 * c.gain:+4.0f} %"
            lines.append(f"  {gain}  {c.what}: {_total(c.E_total_pct, c.nu_total)}"
                         f", {c.n_presses} presses")
        else:
            lines.append(f"  lets diagnose test {', '.join(c.opens)}: {c.what}")
    if not rec.changes:
        lines.append("no single change lowers the error by 2 % or more")
    if rec.target_E_pct is not None or rec.target_nu is not None:
        want = ", ".join(x for x in (
            f"E within {rec.target_E_pct:g} %" if rec.target_E_pct is not None else "",
            f"nu within {rec.target_nu:g}" if rec.target_nu is not None else "") if x)
        if rec.cheapest is None:
            lines.append(f"targets ({want}): {rec.why}")
        else:
            c = rec.cheapest
            lines.append(f"cheapest design meeting the targets ({want}): {c.what or 'as it is'}"
                         f" -> {c.n_presses} presses, {_total(c.E_total_pct, c.nu_total)}")
    return "\n".join(lines)
