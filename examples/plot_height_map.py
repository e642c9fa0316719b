"""
# A height map from a real GelSight frame

A ball of radius 2.0 mm pressed into a GelSight gel (real frames from the
`taxim` package, MIT licence). The shipped calibration turns the frame into a
height map in mm, positive into the gel, levelled on the gel around the
contact (`level="far_field"`).
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from tactilevision.io import read_frame, read_reference
from tactilevision.optics import DepthReconstructor, PhotometricCalibration

HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
SAMPLE = next(p for p in (HERE.parent / "sample_frames", Path("sample_frames"))
              if p.is_dir()) / "gelsight_ball"

cal = PhotometricCalibration.load("gelsight")
ref = read_reference(SAMPLE / "reference.png")
recon = DepthReconstructor(cal, reference=ref, level="far_field")
frame = read_frame(SAMPLE / "frames" / "press_25.png")
height_mm = recon(frame)                    # (H, W) float32, mm

mm_per_px = 0.0295
cx, cy, r = 308, 186, 61                    # the annotated contact circle (circles.csv), px
cap = 2.0 - np.sqrt(2.0**2 - (r * mm_per_px) ** 2)   # the depth that circle implies
print(f"frame {frame.shape}: depth at the contact centre {height_mm[cy, cx]:.3f} mm; "
      f"a 2 mm ball whose contact has this circle is {cap:.3f} mm deep")

# %%
# The frame and its height map, side by side.
fig, ax = plt.subplots(1, 2, figsize=(9, 3.4))
ax[0].imshow(frame[..., ::-1])
ax[0].set_title("GelSight frame")
extent = (0, frame.shape[1] * mm_per_px, frame.shape[0] * mm_per_px, 0)
im = ax[1].imshow(height_mm, cmap="viridis", extent=extent)
ax[1].set_title("height map")
ax[1].set_xlabel("x (mm)")
ax[1].set_ylabel("y (mm)")
fig.colorbar(im, ax=ax[1], label="depth (mm)")
ax[0].axis("off")
fig.tight_layout()
plt.show()

# %%
# A profile through the contact centre against the ball whose contact is the
# annotated circle. The height map reads the centre deeper than the ball
# goes: photometric stereo integrates slopes, and the steep rim's error adds
# up (the documentation's "Absolute depth" page measures it).
row = height_mm[cy]
x_mm = (np.arange(row.size) - cx) * mm_per_px
inside = np.abs(x_mm) < r * mm_per_px
ball = cap - (2.0 - np.sqrt(np.clip(2.0**2 - x_mm**2, 0, None)))
fig, ax = plt.subplots(figsize=(6, 3))
ax.plot(x_mm, row, label="height map")
ax.plot(x_mm[inside], ball[inside], "--", label="ball of radius 2 mm")
ax.set_xlabel("x from the contact centre (mm)")
ax.set_ylabel("depth (mm)")
ax.invert_yaxis()
ax.legend()
fig.tight_layout()
plt.show()
