"""Regenerate ``sample_frames/history_aging/``: four calibrations of one aging gel.

    python benchmarks/make_history_sample.py            # a few minutes
    python benchmarks/make_history_sample.py 0 14       # only these days (truth.json whole)

A simulated GelSight gel (``tactilevision.sim``, the renderer of the other
samples; needs the test extra: taxim) whose Young's modulus falls linearly
over calendar time, E(day) = E0 (1 - k day) with E0 = 0.20 MPa and k = 0.08 /
14 per day (8 % of E0 every two weeks), nu = 0.45 throughout (inside the FEM
beta table with room on both sides: at nu = 0.48, next to the table's top at
0.485, a session's beta often falls above the table and E is then null). It is
calibrated on days 0, 14, 28 and 42 (dates 2026-11-02 + day, written as
``[session] date`` into each session.toml): each session is rendered into a
temporary folder, calibrated by the real ``tactilevision calibrate
--no-report``, and only what ``tactilevision history`` reads is kept under
``day_XX/``: ``fit.json``, ``measurements.csv``, ``rejected.csv`` and the
session's ``session.toml`` (which is also the sidecar of measurements.csv).
Frames, forces and figures are dropped. ``fit.json``'s ``session`` key (the
temporary folder) is replaced by the sample's own folder name.

Deterministic: seeds 100 + i for day i (the frames, forces and truth.json are
the same on the same library versions; ``fit.json``'s ``seconds`` is the
calibration's run time and differs between runs). ``truth.json`` lists each
day's true E and nu.
"""

from __future__ import annotations

import datetime
import json
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "sample_frames" / "history_aging"
E0_MPA = 0.20
NU = 0.45
RATE_PER_DAY = 0.08 / 14.0          # fraction of E0 lost per day
DAYS = (0, 14, 28, 42)
DAY0 = datetime.date(2026, 11, 2)
SENSOR = "gelsight"
KEEP = ("fit.json", "measurements.csv", "rejected.csv", "session.toml")


def true_E(day: float) -> float:
    """The gel's true Young's modulus on `day`, MPa."""
    return E0_MPA * (1.0 - RATE_PER_DAY * day)


def main(days: tuple[int, ...] = DAYS) -> int:
    from tactilevision.cli import main as cli
    from tactilevision.sim import SessionSpec, make_session

    OUT.mkdir(parents=True, exist_ok=True)
    truth = {"sensor": SENSOR, "E0_mpa": E0_MPA, "nu": NU,
             "E_rate_per_day": -RATE_PER_DAY,
             "model": "E(day) = E0_mpa (1 + E_rate_per_day day), nu constant",
             "day0": DAY0.isoformat(), "calibrations": []}
    for i, day in enumerate(DAYS):
        date = DAY0 + datetime.timedelta(days=day)
        truth["calibrations"].append({"folder": f"day_{day:02d}", "day": day,
                                      "date": date.isoformat(),
                                      "E_mpa": round(true_E(day), 6), "nu": NU, "seed": 100 + i})
        if day not in days:
            continue
        name = f"day_{day:02d}"
        spec = SessionSpec(E_mpa=round(true_E(day), 6), nu=NU, repeats=5, rate_hz=250.0,
                           window_samples=50, overshoot_mm=(0.0, 0.05), sensor_name=SENSOR,
                           seed=100 + i)
        with tempfile.TemporaryDirectory() as tmp:
            session = Path(tmp) / name
            make_session(session, spec, progress=False)
            with (session / "session.toml").open("a") as fh:
                fh.write(f"\n[session]\ndate = {date.isoformat()}\n")
            cal = Path(tmp) / "calibration"
            status = cli(["calibrate", str(session), "--out", str(cal), "--no-report",
                          "--no-progress"])
            if status != 0:
                print(f"{name}: calibrate exited with {status}", file=sys.stderr)
                return status
            dest = OUT / name
            if dest.exists():
                shutil.rmtree(dest)
            dest.mkdir()
            for f in KEEP[:3]:
                shutil.copy(cal / f, dest / f)
            shutil.copy(session / "session.toml", dest / "session.toml")
            fit = json.loads((dest / "fit.json").read_text())
            fit["session"] = f"sample_frames/history_aging/{name} (simulated, frames not kept)"
            (dest / "fit.json").write_text(json.dumps(fit, indent=2) + "\n")
        print(f"{name}: {date}  true E {spec.E_mpa:.4f} MPa, fitted {fit['E_mpa']:.4f} MPa "
              f"[{fit['E_ci95_mpa'][0]:.4f}, {fit['E_ci95_mpa'][1]:.4f}]", flush=True)
    (OUT / "truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(tuple(int(d) for d in sys.argv[1:]) or DAYS))
