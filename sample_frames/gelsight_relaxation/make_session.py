"""Regenerate the simulated session of a relaxing gel (needs the test extra: taxim).

    python sample_frames/gelsight_relaxation/make_session.py

The gel of this session relaxes while held: a standard linear solid, G(t) /
G(0) = 1 - g (1 - exp(-t / tau)) with g = 0.25 and tau = 1 s, E_0 = 0.20 MPa.
Each press is held 0.5 to 3 s (uniform) and the force window (50 samples at
250 Hz) ends where the hold ends (``window_at = "end"``), so the windows fall
at different times of their holds and the table's ``hold_s`` shows the
relaxation as well as the hold curves do. Deterministic: the same seed gives
the same frames, forces and truth.json on the same library versions (JPEG
encoding by OpenCV).
"""

from pathlib import Path

from tactilevision.sim import SessionSpec, make_session

HERE = Path(__file__).resolve().parent
KEEP = {"make_session.py", "README.md", "LICENSE"}

if __name__ == "__main__":
    for p in sorted(HERE.rglob("*"), reverse=True):
        if p.is_file() and p.name not in KEEP:
            p.unlink()
        elif p.is_dir() and not any(p.iterdir()):
            p.rmdir()
    tmp = HERE / "_new"
    spec = SessionSpec(E_mpa=0.20, nu=0.48, repeats=4, hold_s=(0.5, 3.0), window_at="end",
                       relaxation_g=0.25, relaxation_tau_s=1.0, rate_hz=250.0,
                       window_samples=50, jpeg_quality=90, overshoot_mm=(0.0, 0.05), seed=1)
    make_session(tmp, spec, progress=False)
    for p in tmp.iterdir():
        p.rename(HERE / p.name)
    tmp.rmdir()
