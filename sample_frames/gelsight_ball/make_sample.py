"""Copy a few GelSight ball presses from the taxim package into this folder.

Run from the repository root: ``python sample_frames/gelsight_ball/make_sample.py``.
The presses are odd-numbered ones, held out from the default calibration
``calibration/gelsight.npz`` (fitted on the even-numbered presses).
"""

from pathlib import Path

import cv2
import numpy as np

from tactilevision.io import read_ball_presses, taxim_datapack

PRESSES = (1, 9, 25, 41)
HERE = Path(__file__).resolve().parent

ps = read_ball_presses(taxim_datapack("gelsight"))
cv2.imwrite(str(HERE / "reference.png"), ps.reference)
rows = ["frame,x_px,y_px,radius_px"]
for i in PRESSES:
    name = f"press_{i:02d}.png"
    cv2.imwrite(str(HERE / "frames" / name), ps.frames[i])
    x, y = ps.centers_px[i]
    rows.append(f"{name},{x:g},{y:g},{ps.radii_px[i]:g}")
(HERE / "frames" / "circles.csv").write_text("\n".join(rows) + "\n")
print(f"wrote {len(PRESSES)} frames, reference.png and frames/circles.csv to {HERE}")
assert np.array_equal(cv2.imread(str(HERE / "reference.png")), ps.reference)
