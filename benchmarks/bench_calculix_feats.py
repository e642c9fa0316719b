"""CalculiX beside our FEM on the FEATS authors' own GelSight Mini model (issue 84, item 1).

The FEATS authors (E. Helmut et al., arXiv:2411.03315; github.com/feats-ai/feats, MIT)
published the CalculiX input files of their gel identification (their repository,
commit f15e158, folder ``src/calculix/src/hyperelasticity_identification/``: ``sim.inp``,
``materials.inp``, ``templates/all.msh`` with second-order tetrahedra, the ``.nam``/``.sur``
sets; put them in one folder, given as ``--model-dir``) and the four measured presses
(``sample_frames/feats/force_depth.csv``). This benchmark runs their model with ``ccx``
and our axisymmetric Neo-Hookean sphere FEM on the same problem, side by side.

Install CalculiX once (the library never installs it; CI does not need it)::

    apt-get install -y calculix-ccx        # Debian's CalculiX 2.20, the command `ccx`

Usage::

    python benchmarks/bench_calculix_feats.py --model-dir FEATS_DIR --cache out/calculix_feats
    python benchmarks/bench_calculix_feats.py --model-dir FEATS_DIR --cache out/calculix_feats \
        --quick
    python benchmarks/bench_calculix_feats.py --model-dir FEATS_DIR --cache DIR \
        --depths 0.5,1.0,1.5,2.0 \
        --ccx-cases published,frictionless,frictionless-soft,axisym-1,axisym-2

Each CalculiX case is one NLGEOM run to the deepest depth in a scratch folder under
``--cache`` (their files copied into ``template/`` so that their include paths resolve;
nothing in ``--model-dir`` is touched). The driver ``sim.inp`` is their text with only
these changes: the indenter's displacement set to the deepest depth (their own script
edits that line per depth), a ``*TIME POINTS`` list at the other depths over it, and
``TIME POINTS=`` on their two ``*NODE PRINT`` requests, so that one run reports the
force at every depth (their script ran one job per depth; the load path is the same
ramp). The cases:

- ``published``: their files as they are;
- ``frictionless``: their contact block replaced by ``PRESSURE-OVERCLOSURE=LINEAR`` with
  K = 100 MPa/mm and no friction (the law our frictionless FEM solves);
- ``frictionless-soft``: the same with the slope ccx gave theirs (50 C10 = 3.625 MPa/mm);
- ``axisym-1``, ``axisym-2``: our problem in CalculiX, not their mesh: the round pad of
  equal area, axisymmetric (CAX8), the ``frictionless`` law, on two meshes (the second
  halves every cell), written by :func:`axisym_text`. Both stop converging past
  1.7 mm (ccx cuts the increment again and again, the largest residuals on nodes near the
  axis under the ball), so they give the first three depths: a run whose last six
  attempts failed is ended there (the cached ones were ended by hand at that point);
- ``axisym-tri-1``: the first grid with each cell cut into two CAX6 triangles (ccx's
  wedges of C3D15, full integration, where CAX8 becomes the reduced-integration C3D20R):
  it passes 1.7 mm and reaches 1.9 mm, where its stiffness matrix turns singular on the
  way to 2.0 mm (spooles: "matrix found to be singular"; the gel under the apex
  compressed by about half); ``--depths 0.5,1.0,1.5,1.9`` reads it to its last depth.

A 3D run takes 8 to 22 minutes by ccx's own clock on the project's 2-core machine
(43,299 equations; longer on the wall under load), an axisymmetric one 10 to 15 minutes
of wall time to its stop; progress is printed every 30 s; forces, log and timing are
cached in ``--cache`` and reused by a rerun whose input and ``ccx`` version are
unchanged.

Prints:

1. What ccx said while reading their input: every WARNING and INFO block verbatim
   (the material's compressibility, the contact law, the friction), then what that
   means for the model it actually solves.
2. Per CalculiX case: the total force on the gel's fixed base (``NGELSIGHT_MINIFIXED``)
   and their own reading (``NGELSIGHT_MINIVOLUME``, all gel nodes) at each depth, its
   increments and time.
3. Our FEM (``tactilevision.fem.sphere_indentation``, Neo-Hookean, finite strain):
   their geometry as our axisymmetric pad allows (the equal-area radius of their
   20.75 x 25.25 mm pad, h = 4.0 mm, R = 7.5 mm, their dome's mean radius of curvature
   fitted to their mesh), at the material CalculiX runs (mu = 2 C10, bulk modulus
   2 / D1 as ccx replaced it; the files' stated nu = 0.5 beside it), tied and
   frictionless (the penalty slope that of the ``frictionless`` case, 100 MPa/mm), on
   two surface cells (``--quick``: the coarser only). Not the slope of 3.625 MPa/mm
   (our penalty contact's Newton fails past w/h = 0.48 with it, on both cells) nor the
   stick slope (our FEM has no elastic tangential spring): CalculiX's own cases part
   those two.
4. Side by side at each depth: measured, CalculiX, ours, and the ratios that name the
   causes (mesh, pad shape, contact slope, friction).
5. Each of our rows fitted to the measured points: one modulus, its rmse and the
   measured over fitted force at each depth (the drift).
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tactilevision.fem import sphere_indentation

ROOT = Path(__file__).resolve().parents[1]
#: The folder of their input files (``--model-dir``; set by :func:`main`).
FEATS = Path()
MEASURED = ROOT / "sample_frames" / "feats" / "force_depth.csv"
TEMPLATE_FILES = ("all.msh", "gelsight_miniVolume.nam", "gelsight_miniFixed.nam",
                  "gelsight_miniSurface.sur", "indenterVolume.nam", "indenterFixed.nam",
                  "indenterSurface.sur")
C10 = 0.0725                  # MPa, their materials.inp
MU = 2.0 * C10                # shear modulus, MPa
H_MM, R_MM = 4.0, 7.5         # gel thickness at the apex, ball radius
PAD_MM = (20.75, 25.25)       # their gel's sides
CONTACT_BLOCK = "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=TIED\n*FRICTION\n1.0\n"
FRICTIONLESS_K = 100.0        # MPa/mm, the 'frictionless' case's pressure-overclosure slope
CCX_CASES = ("published", "frictionless", "frictionless-soft", "axisym-1", "axisym-2",
             "axisym-tri-1")
CELLS = (0.04, 0.02)          # our surface cells, units of h (coarse: the default here)
INSTALL = "apt-get install -y calculix-ccx"
STALLED = 6                   # failed attempts in a row that end a ccx run


@dataclass
class CcxResult:
    """One CalculiX run: forces (N, into the gel) at each depth, and what ccx printed."""

    case: str
    depths_mm: list[float]
    force_fixed: list[float]
    force_volume: list[float]
    notes: list[str]
    equations: int
    increments: int
    seconds: float
    version: str
    from_cache: bool = False
    complete: bool = True


def equal_area_radius_mm() -> float:
    """The radius of the disc of their pad's area."""
    return float(np.sqrt(PAD_MM[0] * PAD_MM[1] / np.pi))


def read_measured() -> dict[float, float]:
    """Depth (mm) -> measured force (N) of the four FEATS presses."""
    with open(MEASURED, newline="") as f:
        return {float(r["depth_mm"]): float(r["force_n"]) for r in csv.DictReader(f)}


def read_mesh_nodes() -> np.ndarray:
    """(N, 3) node coordinates of their all.msh (mm), in node-number order."""
    rows = []
    with open(FEATS / "all.msh") as f:
        next(f)
        for line in f:
            if line.startswith("*"):
                break
            rows.append([float(v) for v in line.split(",")[1:4]])
    return np.array(rows)


def read_node_set(name: str) -> np.ndarray:
    """Node numbers of the first *NSET in one of their .nam files."""
    ids: list[int] = []
    with open(FEATS / name) as f:
        for line in f:
            if line.startswith("**"):
                continue
            if line.startswith("*"):
                if ids:
                    break
                continue
            ids += [int(v) for v in line.split(",") if v.strip()]
    return np.array(ids)


def dome_fit() -> tuple[float, float, float]:
    """Their gel top's radii of curvature (mm) along x and y near the apex, and the mean.

    The top-surface nodes within 6 mm of the axis (the contact radius at 2 mm is about
    5 mm) fitted by z = -(x^2 / 2 Rx + y^2 / 2 Ry); the mean is 2 / (1/Rx + 1/Ry), the
    axisymmetric cap with the same mean curvature.
    """
    xyz = read_mesh_nodes()[read_node_set("gelsight_miniVolume.nam") - 1]
    top = xyz[(np.hypot(xyz[:, 0], xyz[:, 1]) < 6.0) & (xyz[:, 2] > -0.3)]
    top = top[top[:, 2] > -0.5 * (top[:, 0] ** 2 + top[:, 1] ** 2) / 50.0]   # the top only
    a = np.c_[top[:, 0] ** 2, top[:, 1] ** 2]
    cx, cy = np.linalg.lstsq(a, -top[:, 2], rcond=None)[0]
    rx, ry = 0.5 / cx, 0.5 / cy
    return float(rx), float(ry), float(2.0 / (1.0 / rx + 1.0 / ry))


# ---------------------------------------------------------------------------- CalculiX

def ccx_version(ccx: str) -> str:
    """The version line ccx prints (run without input it prints its banner and stops)."""
    out = subprocess.run([ccx, "-v"], capture_output=True, text=True, timeout=60)
    m = re.search(r"Version\s+([\d.]+)", out.stdout + out.stderr)
    return m.group(1) if m else "unknown"


def driver_text(case: str, depths_mm: list[float]) -> str:
    """Their sim.inp with the deepest depth, time points at the others and (frictionless)
    the contact block replaced; everything else as published."""
    src = (FEATS / "sim.inp").read_text()
    d_max = max(depths_mm)
    points = ", ".join(str(round(d / d_max, 6)) for d in depths_mm)
    edits = [] if d_max == 2.0 else [("NindenterFixed,3,,-2.", f"NindenterFixed,3,,-{d_max:g}")]
    edits += [("** Normal Simulation Step",
              f"*TIME POINTS, NAME=TP\n{points}\n** Normal Simulation Step"),
             ("*NODE PRINT,NSET=Ngelsight_miniVolume, TOTALS=YES",
              "*NODE PRINT,NSET=Ngelsight_miniVolume, TOTALS=YES, TIME POINTS=TP"),
             ("*NODE PRINT,NSET=Ngelsight_miniFixed, TOTALS=YES",
              "*NODE PRINT,NSET=Ngelsight_miniFixed, TOTALS=YES, TIME POINTS=TP")]
    if case == "frictionless":
        edits.append((CONTACT_BLOCK,
                      f"*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{FRICTIONLESS_K:.0f}.\n"))
    elif case == "frictionless-soft":             # the slope ccx gave theirs, no friction
        edits.append((CONTACT_BLOCK,
                      f"*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{50 * C10!r}\n"))
    for old, new in edits:
        if src.count(old) != 1:
            raise SystemExit(f"their sim.inp no longer holds {old!r} once: the driver "
                             "cannot be built; read the file and update this benchmark")
        src = src.replace(old, new)
    return src


def read_totals(dat: Path, node_set: str, axis: int = 2, scale: float = 1.0
                ) -> dict[float, float]:
    """time -> scale * F[axis] of the 'total force' blocks of one node set in a .dat file
    (the base's reaction on the gel, upward: the force the ball presses with)."""
    text = dat.read_text()
    pat = re.compile(r"total force \(fx,fy,fz\) for set " + node_set
                     + r" and time\s+(\S+)\s*\n\s*\n\s*(\S+)\s+(\S+)\s+(\S+)")
    return {float(m.group(1)): scale * float(m.group(2 + axis)) for m in pat.finditer(text)}


def log_notes(log: str) -> list[str]:
    """Every WARNING / INFO block ccx printed (a block runs to the next blank line or the
    next block)."""
    notes: list[str] = []
    block: list[str] = []
    for line in log.splitlines():
        starts = line.strip().startswith(("*WARNING", "*INFO", "*ERROR"))
        if starts or (block and not line.strip()):
            if block:
                notes.append("\n".join(block))
            block = [line.rstrip()] if starts else []
        elif block:
            block.append(line.rstrip())
    if block:
        notes.append("\n".join(block))
    return notes


def case_folder(case: str, depths_mm: list[float], cache: Path, version: str
                ) -> tuple[Path, str]:
    """The case's scratch folder (named by a digest of its driver, their files and the
    ccx version) and its driver text."""
    text = (axisym_text(int(case[-1]), depths_mm, dome_fit()[2], triangles="tri" in case)
            if case.startswith("axisym") else driver_text(case, depths_mm))
    key = hashlib.sha256((text + (FEATS / "materials.inp").read_text() + version
                          + "".join(f"{n}:{(FEATS / n).stat().st_size}" for n in TEMPLATE_FILES)
                          ).encode()).hexdigest()[:16]
    return cache / "ccx" / f"{case}_{key}", text


def job_name(case: str) -> str:
    """ccx's job (input file stem) of a case."""
    return "axi" if case.startswith("axisym") else "sim"


def collect(folder: Path, case: str, depths_mm: list[float], version: str,
            returncode: int = 0) -> CcxResult:
    """Read a finished run's forces, notes and size from its folder (and cache them)."""
    log_text = (folder / "ccx.log").read_text()
    if case.startswith("axisym"):           # y is the axis; forces per 2 degrees
        fixed = volume = read_totals(folder / "axi.dat", "BASE", axis=1, scale=180.0)
    else:
        fixed = read_totals(folder / "sim.dat", "NGELSIGHT_MINIFIXED")
        volume = read_totals(folder / "sim.dat", "NGELSIGHT_MINIVOLUME")
    times = [d / max(depths_mm) for d in depths_mm]

    def at(table: dict[float, float]) -> list[float]:
        return [next((f for t, f in table.items() if abs(t - tt) < 1e-5), float("nan"))
                for tt in times]

    eq = re.search(r"number of equations\s*\n\s*(\d+)", log_text)
    sec = re.search(r"Total CalculiX Time:\s*(\S+)", log_text)
    sta_rows = (folder / f"{job_name(case)}.sta").read_text().splitlines()[2:]
    res = CcxResult(case=case, depths_mm=list(depths_mm), force_fixed=at(fixed),
                    force_volume=at(volume), notes=log_notes(log_text),
                    equations=int(eq.group(1)) if eq else 0, increments=len(sta_rows),
                    seconds=float(sec.group(1)) if sec else float("nan"), version=version)
    if returncode != 0 or any(np.isnan(res.force_fixed)):
        res.complete = False
        print(f"   ccx ({case}) ended with code {returncode} before every depth (forces "
              f"{res.force_fixed}): read {folder / 'ccx.log'}", flush=True)
        if all(np.isnan(res.force_fixed)):
            raise SystemExit(f"ccx ({case}) gave no force at all")
    (folder / "result.json").write_text(json.dumps(res.__dict__, indent=1))
    return res


def run_ccx(ccx: str, case: str, depths_mm: list[float], cache: Path,
            version: str) -> CcxResult:
    """Run (or read from the cache) one CalculiX case; print progress every 30 s.

    A folder whose ccx.log already ends with ccx's total time (a finished run whose
    result was not yet collected) is read, not run again.
    """
    folder, text = case_folder(case, depths_mm, cache, version)
    done = folder / "result.json"
    if done.exists():
        res = CcxResult(**json.loads(done.read_text()))
        res.from_cache = True
        return res
    log, job = folder / "ccx.log", job_name(case)
    if log.exists() and "Total CalculiX Time" in log.read_text() \
            and (folder / f"{job}.inp").read_text() == text:
        return collect(folder, case, depths_mm, version)
    folder.mkdir(parents=True, exist_ok=True)
    if job == "sim":
        (folder / "template").mkdir(exist_ok=True)
        for name in TEMPLATE_FILES:
            shutil.copyfile(FEATS / name, folder / "template" / name)
        shutil.copyfile(FEATS / "materials.inp", folder / "materials.inp")
    (folder / f"{job}.inp").write_text(text)
    env = dict(os.environ, GFORTRAN_UNBUFFERED_ALL="y",
               OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "1"))
    t0 = time.perf_counter()
    print(f"   running ccx ({case}) in {folder} ...", flush=True)
    with open(log, "w") as out:
        proc = subprocess.Popen([ccx, job], cwd=folder, stdout=out, stderr=subprocess.STDOUT,
                                env=env)
        while proc.poll() is None:
            time.sleep(30)
            sta = folder / f"{job}.sta"
            rows = sta.read_text().splitlines()[2:] if sta.exists() else []
            last = rows[-1].split() if rows else []
            step_time = float(last[4]) if len(last) >= 5 else 0.0
            print(f"   ... {time.perf_counter() - t0:6.0f} s: {len(rows)} increments, "
                  f"depth {step_time * max(depths_mm):.3f} of {max(depths_mm):g} mm",
                  flush=True)
            failed = 0
            for row in reversed(rows):                 # trailing unconverged attempts
                if len(row.split()) < 3 or not row.split()[2].endswith("U"):
                    break
                failed += 1
            if failed >= STALLED:
                print(f"   ccx ({case}): {failed} attempts in a row did not converge; ended",
                      flush=True)
                proc.terminate()
                proc.wait()
    return collect(folder, case, depths_mm, version, proc.returncode)


def _graded(x0: float, x1: float, h0: float, growth: float) -> np.ndarray:
    xs, step = [x0], h0
    while xs[-1] + step < x1 - 0.5 * step:
        xs.append(xs[-1] + step)
        step *= growth
    xs.append(x1)
    return np.array(xs)


def axisym_text(level: int, depths_mm: list[float], dome_mm: float,
                triangles: bool = False) -> str:
    """A CalculiX model of our problem: the round pad of equal area, axisymmetric.

    CAX8 quadrilaterals (ccx expands them to a 2 degree wedge of C3D20R, reduced
    integration), or with `triangles` each cut along its diagonal into two CAX6 (wedges of
    C3D15, full integration; the same nodes plus each cell's centre): the gel
    (radius the equal-area one, 4 mm thick at the apex, its top the cap of radius
    `dome_mm`, the base fixed) on a grid of 0.25 / level mm out to 7 mm, graded beyond,
    layers from 0.25 / level mm at the top growing 15 % downwards; the ball a steel ring
    (radius 7.5 to 7.0 mm, 0 to 60 degrees from the apex) driven down by its inner arc.
    Their material as ccx runs it (C10, D1 = 0.1 / mu), frictionless surface-to-surface
    contact, K = 100 MPa/mm: the 'frictionless' case on our pad. Forces are per 2 degrees.
    """
    h, radius, pad, d_max = H_MM, R_MM, equal_area_radius_mm(), max(depths_mm)
    dr = 0.25 / level
    r = np.unique(np.round(np.concatenate([np.arange(0.0, 7.0, dr),
                                           _graded(7.0, pad, dr, 1.2)]), 9))
    zf = np.sort(1.0 - _graded(0.0, 1.0, 0.0625 / level, 1.15))
    rr = np.empty(2 * r.size - 1)
    rr[0::2], rr[1::2] = r, 0.5 * (r[:-1] + r[1:])
    zz = np.empty(2 * zf.size - 1)
    zz[0::2], zz[1::2] = zf, 0.5 * (zf[:-1] + zf[1:])
    sag = dome_mm - np.sqrt(dome_mm**2 - rr**2)
    nid = -np.ones((rr.size, zz.size), dtype=int)
    coords: dict[int, tuple[float, float]] = {}

    def node(i: int, j: int) -> int:
        if nid[i, j] < 0:
            nid[i, j] = len(coords) + 1
            coords[int(nid[i, j])] = (float(rr[i]), float(-h + zz[j] * (h - sag[i])))
        return int(nid[i, j])

    els: list[list[int]] = []
    top: list[int] = []
    ne_r, ne_z = (rr.size - 1) // 2, (zz.size - 1) // 2
    for i in range(ne_r):
        for j in range(ne_z):
            a, b = 2 * i, 2 * j
            if triangles:       # corners counter-clockwise, then the sides' middles
                els.append([node(a, b), node(a + 2, b), node(a + 2, b + 2),
                            node(a + 1, b), node(a + 2, b + 1), node(a + 1, b + 1)])
                els.append([node(a, b), node(a + 2, b + 2), node(a, b + 2),
                            node(a + 1, b + 1), node(a + 1, b + 2), node(a, b + 1)])
            else:
                els.append([node(a, b), node(a + 2, b), node(a + 2, b + 2), node(a, b + 2),
                            node(a + 1, b), node(a + 2, b + 1), node(a + 1, b + 2),
                            node(a, b + 1)])
            if j == ne_z - 1 and rr[a] < radius:
                top.append(len(els))
    n_gel = len(els)
    base = [int(nid[i, 0]) for i in range(rr.size) if nid[i, 0] > 0]
    axis = [int(nid[0, j]) for j in range(zz.size) if nid[0, j] > 0]
    n_phi = int(np.ceil(np.radians(60.0) * radius / dr))
    phi = np.linspace(0.0, np.radians(60.0), 2 * n_phi + 1)
    ring = (radius, radius - 0.25, radius - 0.5)
    pid: dict[tuple[int, int], int] = {}
    for i, p in enumerate(phi):
        for j, q in enumerate(ring):
            pid[i, j] = len(coords) + 1
            coords[pid[i, j]] = (float(q * np.sin(p)), float(radius - q * np.cos(p)))
    master: list[int] = []
    for i in range(n_phi):
        a = 2 * i
        els.append([pid[a, 0], pid[a + 2, 0], pid[a + 2, 2], pid[a, 2], pid[a + 1, 0],
                    pid[a + 2, 1], pid[a + 1, 2], pid[a, 1]])
        master.append(len(els))
    inner = [pid[i, 2] for i in range(phi.size)]
    used = {n for e in els for n in e}
    lines = ["*NODE, NSET=NALL"]
    lines += [f"{n}, {x:.12g}, {y:.12g}, 0" for n, (x, y) in coords.items() if n in used]
    lines.append(f"*ELEMENT, TYPE={'CAX6' if triangles else 'CAX8'}, ELSET=GEL")
    lines += [f"{k}, " + ", ".join(map(str, e)) for k, e in enumerate(els[:n_gel], 1)]
    lines.append("*ELEMENT, TYPE=CAX8, ELSET=BALL")
    lines += [f"{k}, " + ", ".join(map(str, e)) for k, e in enumerate(els[n_gel:], n_gel + 1)]
    for name, ids in (("BASE", base), ("AXIS", axis), ("DRIVE", inner)):
        lines.append(f"*NSET, NSET={name}")
        lines += [", ".join(map(str, ids[s:s + 8])) + "," for s in range(0, len(ids), 8)]
    lines.append("*SURFACE, NAME=SGEL")
    lines += [f"{e}, {'S2' if triangles else 'S3'}" for e in top]    # the top side
    lines.append("*SURFACE, NAME=SBALL")
    lines += [f"{e}, S1" for e in master]
    points = ", ".join(str(round(d / d_max, 6)) for d in depths_mm)
    lines += ["*MATERIAL, NAME=SILICONE", "*HYPERELASTIC, NEO HOOKE", f"{C10!r}, {0.1 / MU!r}",
              "*MATERIAL, NAME=STEEL", "*ELASTIC", "210000.0, 0.3",
              "*SOLID SECTION, ELSET=GEL, MATERIAL=SILICONE",
              "*SOLID SECTION, ELSET=BALL, MATERIAL=STEEL",
              "*SURFACE INTERACTION, NAME=PRESS",
              "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", f"{FRICTIONLESS_K!r}",
              "*CONTACT PAIR, INTERACTION=PRESS, TYPE=SURFACE TO SURFACE", "SGEL, SBALL",
              "*BOUNDARY", "BASE, 1, 2", "AXIS, 1, 1", "DRIVE, 1, 1",
              "*TIME POINTS, NAME=TP", points,
              "*STEP, NLGEOM, INC=1000", "*STATIC", "0.05, 1.0, 1e-6, 0.1",
              "*BOUNDARY", f"DRIVE, 2, 2, -{d_max!r}",
              "*NODE PRINT, NSET=BASE, TOTALS=ONLY, TIME POINTS=TP", "RF", "*END STEP"]
    return "\n".join(lines) + "\n"


def material_as_run(notes: list[str]) -> tuple[float, float]:
    """(D1 in 1/MPa, contact slope K in MPa/mm) that ccx printed it uses (nan if not said)."""
    d1 = k = float("nan")
    for n in notes:
        m = re.search(r"D1 =\s*(\S+)", n)
        if "HYPERELASTIC" in n and m:
            d1 = float(m.group(1))
        m = re.search(r"default will be used:\s*(\S+)", n)
        if "SURFACE BEHAVIOR: K must" in n and m:
            k = float(m.group(1))
    return d1, k


def nu_from_bulk(bulk: float) -> float:
    """Small-strain Poisson's ratio of shear modulus MU and bulk modulus `bulk`."""
    return float((3 * bulk - 2 * MU) / (2 * (3 * bulk + MU)))


# ---------------------------------------------------------------------------- ours

@dataclass
class OurRow:
    label: str
    nu: float
    contact: str
    dome_mm: float | None
    k_mm: float | None = None        # frictionless: pressure per penetration, MPa/mm
    fine: bool = True                # also on the finer surface cell


def ours(row: OurRow, depths_mm: list[float], cell: float, cache: Path
         ) -> tuple[np.ndarray, float, bool]:
    """Forces (N) of one of our sweeps at the depths; its seconds; from the cache."""
    e = 2.0 * MU * (1.0 + row.nu)
    # RigidPunch's penalty is a pressure per penetration of penalty / l (l the surface cell,
    # units E / h): a slope K (MPa/mm) is penalty = K h / E * l.
    penalty = 1e3 if row.k_mm is None else row.k_mm * H_MM / e * cell
    pad = equal_area_radius_mm() / H_MM
    t0 = time.perf_counter()
    res = sphere_indentation(R_MM / H_MM, row.nu, np.asarray(depths_mm) / H_MM,
                             model="neo_hookean", contact=row.contact, pad_radius_over_h=pad,
                             surface_cell=cell, penalty=penalty,
                             dome_radius_over_h=None if row.dome_mm is None
                             else row.dome_mm / H_MM, cache_dir=cache / "ours")
    if res is None or not res.complete:
        return np.full(len(depths_mm), np.nan), time.perf_counter() - t0, False
    return res.force * e * H_MM**2, time.perf_counter() - t0, res.from_cache


# ---------------------------------------------------------------------------- round pad

#: Depths (mm) of the round-pad comparison per CalculiX case: the CAX8 runs to 1.5 mm
#: (they stall past 1.7 mm), the CAX6 run to 1.9 mm (singular between 1.9 and 2.0 mm).
ROUND_PAD_DEPTHS = {"axisym-1": [0.5, 1.0, 1.5], "axisym-2": [0.5, 1.0, 1.5],
                    "axisym-tri-1": [0.5, 1.0, 1.5, 1.9]}


def use_model_dir(model_dir: Path) -> None:
    """Set :data:`FEATS` to `model_dir` after checking it holds their files.

    Raises
    ------
    FileNotFoundError
        Naming the folder and each missing file.
    """
    global FEATS
    missing = [n for n in ("sim.inp", "materials.inp", *TEMPLATE_FILES)
               if not (Path(model_dir) / n).is_file()]
    if missing:
        raise FileNotFoundError(f"{model_dir}: missing {', '.join(missing)} (the FEATS "
                                "authors' CalculiX files, see bench_calculix_feats.py)")
    FEATS = Path(model_dir)


def round_pad(model_dir: Path, cache: Path, *, quick: bool = False) -> dict:
    """CalculiX and our FEM on the same problem: the FEATS ball on the round pad of equal
    area, axisymmetric, their material as ccx 2.20 runs it (D1 = 0 replaced by 0.1 / mu),
    frictionless with K = 100 MPa/mm, their dome's mean curvature.

    CalculiX on :data:`ROUND_PAD_DEPTHS` (`quick`: the CAX6 run only); ours at the CAX6
    run's depths on the surface cells :data:`CELLS` (`quick`: the coarser). Returns
    ``{"version", "nu", "dome_mm", "pad_mm", "depths_mm", "ccx": {case: CcxResult},
    "ours": {cell: forces (N)}, "ours_s": {cell: seconds}}``.

    Raises
    ------
    FileNotFoundError
        Without `ccx` on the path (how to install it is named) or their files.
    """
    use_model_dir(model_dir)
    ccx = shutil.which("ccx")
    if ccx is None:
        raise FileNotFoundError(f"ccx (CalculiX) is not installed: `{INSTALL}`")
    version = ccx_version(ccx)
    cases = ["axisym-tri-1"] if quick else list(ROUND_PAD_DEPTHS)
    runs = {c: run_ccx(ccx, c, ROUND_PAD_DEPTHS[c], cache, version) for c in cases}
    nu = nu_from_bulk(2.0 / (0.1 / MU))
    dome = dome_fit()[2]
    depths = ROUND_PAD_DEPTHS["axisym-tri-1"]
    row = OurRow("frictionless", nu, "frictionless", dome, FRICTIONLESS_K)
    ours_f, ours_s = {}, {}
    for cell in CELLS[:1] if quick else CELLS:
        ours_f[cell], ours_s[cell], _ = ours(row, depths, cell, cache)
    return {"version": version, "nu": nu, "dome_mm": dome, "pad_mm": equal_area_radius_mm(),
            "depths_mm": depths, "ccx": runs, "ours": ours_f, "ours_s": ours_s}


# ---------------------------------------------------------------------------- report

def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model-dir", type=Path, required=True,
                    help="folder holding their input files (sim.inp, materials.inp, all.msh, "
                         "the .nam and .sur sets)")
    ap.add_argument("--cache", type=Path, required=True,
                    help="folder for the CalculiX runs and our sweeps (reused by reruns)")
    ap.add_argument("--depths", default="0.5,1.0,1.5,2.0",
                    help="indentation depths in mm, comma-separated (default the four "
                         "measured)")
    ap.add_argument("--quick", action="store_true",
                    help="our FEM on the coarser surface cell only; CalculiX read from the "
                         "cache only (no run)")
    ap.add_argument("--ccx-cases", default=",".join(CCX_CASES),
                    help=f"CalculiX cases to run, from {', '.join(CCX_CASES)}")
    args = ap.parse_args()
    try:
        use_model_dir(args.model_dir)
    except FileNotFoundError as err:
        ap.error(f"--model-dir {err}")
    depths = sorted(float(v) for v in args.depths.split(","))
    cases = [c for c in args.ccx_cases.split(",") if c]
    if any(c not in CCX_CASES for c in cases):
        ap.error(f"--ccx-cases: choose from {', '.join(CCX_CASES)}")
    args.cache.mkdir(parents=True, exist_ok=True)
    measured = read_measured()
    print(f"FEATS GelSight Mini: CalculiX on their model beside our FEM "
          f"({platform.node()}, {os.cpu_count()} cores, Python {platform.python_version()})")

    ccx = shutil.which("ccx")
    if ccx is None:
        print(f"ccx (CalculiX) is not installed: `{INSTALL}` (Debian's CalculiX 2.20), "
              "then run this again. The library does not need it.", file=sys.stderr)
        return 2
    version = ccx_version(ccx)
    runs: dict[str, CcxResult] = {}
    print(f"\n1-2. CalculiX {version} on their input files ({FEATS})")
    for case in cases:
        if args.quick:
            folder = args.cache / "ccx"
            hits = sorted(folder.glob(f"{case}_*/result.json")) if folder.exists() else []
            key_ok = [h for h in hits
                      if json.loads(h.read_text())["depths_mm"] == depths]
            if not key_ok:
                print(f"   {case}: not in the cache (--quick runs no ccx); run without --quick")
                continue
            runs[case] = CcxResult(**json.loads(key_ok[-1].read_text()))
            runs[case].from_cache = True
        else:
            runs[case] = run_ccx(ccx, case, depths, args.cache, version)
        r = runs[case]
        took = (f"ccx's total time {r.seconds / 60:.1f} min" if np.isfinite(r.seconds)
                else "ended early")
        print(f"\n   case '{case}': {r.equations} equations, {r.increments} increments, {took}"
              f"{' (cached run)' if r.from_cache else ''}"
              f"{'' if r.complete else '; STOPPED before the last depth'}")
        if case == cases[0] or case == "published":
            print("   what ccx printed while reading the input (every WARNING / INFO block):")
            for n in r.notes:
                print("     | " + n.strip().replace("\n", "\n     | "))
        for d, ff, fv in zip(r.depths_mm, r.force_fixed, r.force_volume, strict=True):
            print(f"   w = {d:.2f} mm: force on the fixed base {ff:8.4f} N, on all gel nodes "
                  f"(their reading) {fv:8.4f} N")

    # ccx's rules (hyperelastics.f, surfacebehaviors.f, frictions.f of 2.20): D1 = 0 becomes
    # 0.1 / mu, a missing K 50 C10; the printed values (4 digits) are checked against them.
    d1, k_ccx = 0.1 / MU, 50.0 * C10
    if "published" in runs:
        d1_p, k_p = material_as_run(runs["published"].notes)
        if not (abs(d1_p / d1 - 1) < 1e-3 and abs(k_p / k_ccx - 1) < 1e-3):
            d1, k_ccx = d1_p, k_p
            print(f"   ccx printed D1 = {d1_p}, K = {k_p}: not 2.20's rules; using them")
    bulk = 2.0 / d1
    nu_ccx = nu_from_bulk(bulk)
    rx, ry, rd = dome_fit()
    pad = equal_area_radius_mm()
    print(f"\n   The model ccx solves (from the lines above and its 2.20 source): "
          f"Neo-Hookean C10 = {C10} MPa with D1 = 0 replaced by {d1:.4g} /MPa (bulk "
          f"{bulk:.3g} MPa, nu = {nu_ccx:.4f} at small strain, E = "
          f"{2 * MU * (1 + nu_ccx):.4f} MPa); the TIED contact without its data line "
          f"read as LINEAR (compression only) with K = {k_ccx:.4g} MPa/mm; friction 1.0 "
          f"with the default stick slope {C10 / 2:.4g} MPa/mm.")
    print(f"   Their gel top near the apex: radii of curvature {rx:.0f} mm (x, the "
          f"{PAD_MM[0]} mm side) and {ry:.0f} mm (y); mean {rd:.0f} mm. Pad: equal-area "
          f"radius {pad:.3f} mm.")

    rows = [OurRow(f"frictionless K {FRICTIONLESS_K:g}, nu {nu_ccx:.4f}, dome", nu_ccx,
                   "frictionless", rd, FRICTIONLESS_K),
            OurRow(f"tied, nu {nu_ccx:.4f}, dome", nu_ccx, "tied", rd),
            OurRow(f"frictionless K {FRICTIONLESS_K:g}, nu {nu_ccx:.4f}, flat", nu_ccx,
                   "frictionless", None, FRICTIONLESS_K, fine=False),
            OurRow("tied, nu 0.5, flat (the files' stated model)", 0.5, "tied", None,
                   fine=False)]
    cells = CELLS[:1] if args.quick else CELLS
    print(f"\n3. Our FEM: Neo-Hookean sphere on the bonded pad (R/h = {R_MM / H_MM:g}, pad "
          f"{pad / H_MM:.4f} h), surface cells {', '.join(f'h/{1 / c:g}' for c in cells)}")
    table: dict[str, list[np.ndarray]] = {}
    for row in rows:
        table[row.label] = []
        for cell in cells if row.fine else cells[:1]:
            f, sec, hit = ours(row, depths, cell, args.cache)
            table[row.label].append(f)
            print(f"   {row.label:52s} h/{1 / cell:g}: "
                  + " ".join(f"{v:8.4f}" for v in f)
                  + f" N  ({'cache' if hit else f'{sec:.0f} s'})", flush=True)
        if len(table[row.label]) == 2:
            c, fn = table[row.label]
            print(f"   {'':52s} fine/coarse - 1: "
                  + " ".join(f"{100 * (b / a - 1):+7.2f}%" for a, b in zip(c, fn, strict=True)))

    print("\n4. Side by side (N; ours on the finest cell run)")
    head = "   " + f"{'':52s}" + "".join(f"{d:>10.2f}" for d in depths) + "  mm"
    print(head)
    meas = [measured.get(d, float("nan")) for d in depths]
    print("   " + f"{'measured (FEATS)':52s}" + "".join(f"{v:10.4f}" for v in meas))
    for case, r in runs.items():
        print("   " + f"{'CalculiX ' + case:52s}" + "".join(f"{v:10.4f}" for v in r.force_fixed))
    for label, fs in table.items():
        print("   " + f"{'ours ' + label:52s}" + "".join(f"{v:10.4f}" for v in fs[-1]))
    k100 = f"frictionless K {FRICTIONLESS_K:g}, nu {nu_ccx:.4f}, dome"
    pairs = [(f"ours frictionless K 100 dome / ccx {c}", table[k100][-1], runs[c].force_fixed)
             for c in ("frictionless", "axisym-1", "axisym-2", "axisym-tri-1") if c in runs]
    for num, den, what in (("axisym-2", "axisym-1", "mesh: fine / coarse"),
                           ("axisym-tri-1", "axisym-1", "CAX6 / CAX8, one grid"),
                           ("frictionless", "axisym-2", "their pad + mesh / round"),
                           ("frictionless-soft", "frictionless", "K 3.625 / K 100"),
                           ("published", "frictionless-soft", "stick slope"),
                           ("published", "frictionless", "their contact / K 100")):
        if num in runs and den in runs:
            pairs.append((f"ccx {num} / {den} ({what})", runs[num].force_fixed,
                          runs[den].force_fixed))
    print("   ratios:")
    for label, a, b in pairs:
        print("   " + f"{label:60s}" + "".join(f"{x / y:10.4f}" for x, y in
                                              zip(a, b, strict=True)))
    for case, r in runs.items():
        print("   " + f"{'ccx ' + case + ' / measured':60s}"
              + "".join(f"{a / b:10.4f}" for a, b in zip(r.force_fixed, meas, strict=True)))
    if "published" in runs and not np.isnan(meas).any():
        # ccx's defaults make every modulus of their model C10 times a constant (the bulk
        # modulus 2 / D1 = 20 C10, K = 50 C10, the stick slope C10 / 2; the steel ball is
        # rigid beside them), so its forces scale with C10: the least-squares C10 of the
        # four points (their script's loss) is C10 * sum(Fm Fc) / sum(Fc^2).
        fc, fm = np.array(runs["published"].force_fixed), np.array(meas)
        c10 = C10 * float(fm @ fc / (fc @ fc))
        print(f"   their model as ccx {version} runs it, fitted to the measured points: "
              f"C10 = {c10:.4f} MPa (theirs {C10}), E = {4 * c10 * (1 + nu_ccx):.3f} MPa at "
              f"nu {nu_ccx:.4f}; measured / fitted at each depth: "
              + ", ".join(f"{v:.3f}" for v in fm / (fc * c10 / C10)))
    if not np.isnan(meas).any():
        # a Neo-Hookean solid's forces scale with its modulus at a fixed nu and contact (the
        # penalty slope scaled with it; at K 100 MPa/mm its share of the depth is < 0.5 %)
        print("\n5. Our rows fitted to the measured points (one modulus each, least squares):")
        fm = np.array(meas)
        for row in rows:
            fo = table[row.label][-1]
            if np.isnan(fo).any():
                continue
            s = float(fm @ fo / (fo @ fo))
            rmse = float(np.sqrt(np.mean((fm - s * fo) ** 2)))
            print(f"   {row.label:52s} E = {s * 2 * MU * (1 + row.nu):.3f} MPa, rmse "
                  f"{1e3 * rmse:4.0f} mN, measured / fitted "
                  + ", ".join(f"{v:.3f}" for v in fm / (s * fo)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
