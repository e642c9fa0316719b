"""Regenerate the simulated session with a hidden effect (needs the test extra: taxim).

    python sample_frames/gelsight_recovery/make_session.py

The gel of this session does not recover fully between presses: each press
is stiffer by 1 + r (1 + t_wait / tau)^-1.5 (r = 0.08, tau = 2 s; a power law,
not the catalogue's exponential), and the waits run from 0.3 s to 10 s.
Deterministic: the same seed gives the same frames, forces and truth.json on
the same library versions (JPEG encoding by OpenCV).
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
    spec = SessionSpec(E_mpa=0.20, nu=0.48, repeats=8, wait_s=(0.3, 10.0), recovery_r=0.08,
                       recovery_tau_s=2.0, rate_hz=250.0, window_samples=50, jpeg_quality=90,
                       overshoot_mm=(0.0, 0.05), seed=1)
    make_session(tmp, spec, progress=True)
    for p in tmp.iterdir():
        p.rename(HERE / p.name)
    tmp.rmdir()
