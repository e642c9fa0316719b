"""
# What the model misses: diagnose on a table with a hidden effect

A calibration table made by the project's generator
(`tactilevision.sim.make_measurement_table`): forces from the finite-strain
FEM, and a gel that does not recover fully between presses, in a form that is
not the catalogue's. `diagnose` names the missing effect and the error falls
to the noise floor once it is added.
"""

import matplotlib.pyplot as plt

from tactilevision.diagnosis import diagnose
from tactilevision.sim import make_measurement_table

t = make_measurement_table("incomplete_recovery", seed=3)
d = diagnose(t.columns, thickness_mm=t.thickness_mm, radius_mm=t.radius_mm)
print("verdict:", d.missing_effect)
for step in d.ladder:
    print(f"  {step.added or 'base':24s} CV RMSE {1e3 * step.cv_rmse_n:7.2f} mN")
print(f"  noise floor              {1e3 * d.noise_floor_n:7.2f} mN")

# %%
# The error ladder: each rung adds one effect.
names = [s.added or "base" for s in d.ladder]
fig, ax = plt.subplots(figsize=(6, 3))
ax.bar(names, [1e3 * s.cv_rmse_n for s in d.ladder])
ax.axhline(1e3 * d.noise_floor_n, color="k", ls="--", label="replicate noise floor")
ax.set_ylabel("cross-validated RMSE (mN)")
ax.legend()
fig.tight_layout()
plt.show()
