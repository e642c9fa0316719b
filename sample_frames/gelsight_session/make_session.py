"""Regenerate the simulated gauge-block session in this folder (needs the test extra: taxim).

    python sample_frames/gelsight_session/make_session.py [--optics-only]

Deterministic: the same seed gives the same frames, forces and truth.json on
the same library versions (JPEG encoding by OpenCV).

The session's own photometric calibration, ``optics.npz`` (named in
``session.toml``'s ``[optics]`` table), is made as a rig makes one: from ball
presses of the session's sensor, here 256 presses of a 2 mm ball up to 1.4 mm
deep, their contacts reaching the image's edges, rendered through the same
shading table as the session's frames, then a colour table per cell of an
8 x 6 grid over the image. ``--optics-only`` remakes only that file.
"""

import sys
from pathlib import Path

from tactilevision.optics import PhotometricCalibration
from tactilevision.sim import SessionSpec, make_session, render_ball_presses, taxim_shading

HERE = Path(__file__).resolve().parent
KEEP = {"make_session.py", "README.md", "LICENSE"}
OPTICS_TOML = '\n[optics]\ncalibration = "optics.npz"\n'


def make_optics(folder: Path) -> Path:
    """Write ``folder/optics.npz``: position-cell LUT from rendered ball presses."""
    table, reference = taxim_shading()
    balls = render_ball_presses(table, reference, n=256, radius_mm=2.0, depth_mm=(0.2, 1.4),
                                partial=True, seed=5)
    cal = PhotometricCalibration.from_ball_presses(
        balls.reference, balls.frames, balls.centers_px, balls.radii_px, ball_radius_mm=2.0,
        mm_per_px=0.0295, model="lut", lut_cells=(8, 6))
    cal.provenance["source"] = ("256 presses of a 2 mm ball, 0.2 to 1.4 mm deep, rendered "
                                "through Taxim's GelSight shading table on the session's "
                                "reference (sample_frames/gelsight_session/make_session.py)")
    return cal.save(folder / "optics.npz")


if __name__ == "__main__":
    if "--optics-only" in sys.argv[1:]:
        print(make_optics(HERE))
        sys.exit(0)
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
    make_optics(HERE)
    with (HERE / "session.toml").open("a") as fh:
        fh.write(OPTICS_TOML)
