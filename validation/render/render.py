#!/usr/bin/python3
"""Render the last (or a chosen) state of a solved case to PNG: a field on the deformed
solids, the third medium hidden.

    /usr/bin/python3 validation/render/render.py results/NAME out.png [--step N | --at-lambda L] [--field theta]

2D meshes are drawn cell by cell; 3D meshes by the boundary faces of the solid cells, seen from
the (-0.5, -0.85, 0.9) direction (for the quarter models: onto the symmetry planes)."""
import argparse
import glob
import os

import matplotlib
import meshio
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

FACES = {  # local faces of 3D cells (VTK corner order), outward or not: orientation is unused
    "tetra": [(0, 1, 2), (0, 1, 3), (1, 2, 3), (0, 2, 3)],
    "tetra10": [(0, 1, 2), (0, 1, 3), (1, 2, 3), (0, 2, 3)],
    "hexahedron": [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
}
FACES["hexahedron27"] = FACES["hexahedron20"] = FACES["hexahedron"]
CORNERS2D = {"triangle": 3, "triangle6": 3, "quad": 4, "quad8": 4, "quad9": 4}


def state_file(results, step):
    files = sorted(glob.glob(os.path.join(results, "step_*.vtu")))
    if not files:
        raise SystemExit(f"{results}: no step_*.vtu (solve the case first)")
    if step is None:
        return files[-1]
    want = os.path.join(results, f"step_{step:04d}.vtu")
    if want not in files:
        raise SystemExit(f"{want} does not exist")
    return want


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("results")
    ap.add_argument("png")
    ap.add_argument("--step", type=int)
    ap.add_argument("--at-lambda", type=float, help="the step that reached this λ (history.csv)")
    ap.add_argument("--field", default="theta")
    ap.add_argument("--title", default=None)
    ap.add_argument("--window", help="x0,x1,y0,y1 (2D)")
    a = ap.parse_args()
    if a.at_lambda is not None:
        import csv
        with open(os.path.join(a.results, "history.csv")) as f:
            hits = [int(float(r["step"])) for r in csv.DictReader(f)
                    if abs(float(r["lambda"]) - a.at_lambda) < 1e-12]
        if not hits:
            raise SystemExit(f"{a.results}: no step reached λ = {a.at_lambda}")
        a.step = hits[0]
    path = state_file(a.results, a.step)
    m = meshio.read(path)
    X = m.points + m.point_data["u"]
    f = m.point_data.get(a.field)
    if f is None:
        raise SystemExit(f"{path}: no point field '{a.field}' (have {list(m.point_data)})")
    f = f if f.ndim == 1 else np.linalg.norm(f, axis=1)
    three_d = any(c.type in FACES for c in m.cells)
    fig = plt.figure(figsize=(9, 6.5) if three_d else (10, 6))
    lo, hi = float(f.min()), float(f.max())
    cmap = plt.get_cmap("inferno")
    norm = matplotlib.colors.Normalize(lo, hi if hi > lo else lo + 1)
    if not three_d:
        ax = fig.add_subplot(111)
        for blk, kind in zip(m.cells, m.cell_data["region_kind"]):
            if blk.type not in CORNERS2D:
                continue
            cells = blk.data[kind == 0][:, : CORNERS2D[blk.type]]
            pc = PolyCollection(X[cells][:, :, :2], array=f[cells].mean(axis=1), cmap=cmap,
                                norm=norm, edgecolors="face", linewidths=0.2)
            ax.add_collection(pc)
        ax.autoscale()
        ax.set_aspect("equal")
        if a.window:
            x0, x1, y0, y1 = map(float, a.window.split(","))
            ax.set_xlim(x0, x1)
            ax.set_ylim(y0, y1)
    else:
        ax = fig.add_subplot(111, projection="3d")
        count = {}
        for blk, kind in zip(m.cells, m.cell_data["region_kind"]):
            if blk.type not in FACES:
                continue
            for c in blk.data[kind == 0]:
                for lf in FACES[blk.type]:
                    face = tuple(c[list(lf)])
                    key = tuple(sorted(face))
                    count[key] = None if key in count else face
        faces = np.array([v for v in count.values() if v is not None and len(v) == 3]
                         or [v for v in count.values() if v is not None])
        view = np.array([-0.53, -0.85, 0.9])
        depth = (X[faces].mean(axis=1) @ view)
        order = np.argsort(depth)
        faces = faces[order]
        col = cmap(norm(f[faces].mean(axis=1)))
        pc = Poly3DCollection(X[faces], facecolors=col, edgecolors=col, linewidths=0.1)
        ax.add_collection3d(pc)
        lo3, hi3 = X.min(axis=0), X.max(axis=0)
        ax.set_xlim(lo3[0], hi3[0]); ax.set_ylim(lo3[1], hi3[1]); ax.set_zlim(lo3[2], hi3[2])
        ax.set_box_aspect(hi3 - lo3)
        ax.view_init(elev=25, azim=-122)
        ax.set_axis_off()
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=ax, shrink=0.8, label=a.field)
    ax.set_title(a.title or f"{os.path.basename(os.path.normpath(a.results))}: {a.field}, "
                 f"{os.path.basename(path)}")
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
