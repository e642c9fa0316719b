"""Regenerate the simulated gauge-block session in this folder (needs the test extra: taxim).

    python sample_frames/gelsight_session/make_session.py

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
    spec = SessionSpec(E_mpa=0.20, nu=0.48, clock_offset_s=0.137, misaligned=(3,),
                       edge_presses=(7,), overshoot_mm=(0.0, 0.05), seed=0)
    make_session(tmp, spec, progress=True)
    for p in tmp.iterdir():
        p.rename(HERE / p.name)
    tmp.rmdir()
