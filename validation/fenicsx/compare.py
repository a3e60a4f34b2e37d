#!/usr/bin/python3
"""Compare tmc's final state with FEniCSx's on the same mesh, node by node.

    /usr/bin/python3 compare.py TMC_OUT_DIR FENICSX.npz   → prints one JSON line

Nodes are matched by their reference coordinates. Differences are relative to the solution's
max-norm (u: over all components; θ: over θ − θ0-free values, i.e. the max |θ|).
"""
import glob
import json
import sys

import meshio
import numpy as np


def match(x_tmc, x_fx):
    """Index into x_fx of each tmc node (exact up to round-off, else an error)."""
    scale = np.abs(x_tmc).max() + 1.0
    key = lambda x: tuple(np.round(x / scale * 1e9).astype(np.int64))
    index = {key(p): i for i, p in enumerate(x_fx)}
    out = np.array([index.get(key(p), -1) for p in x_tmc])
    if (out < 0).any():
        raise SystemExit(f"{(out < 0).sum()} tmc nodes have no FEniCSx twin")
    return out


def rel(a, b):
    d = a - b
    return (float(np.abs(d).max() / np.abs(b).max()),
            float(np.sqrt((d**2).sum() / (b**2).sum())))


def main(tmc_out, npz):
    last = sorted(glob.glob(f"{tmc_out}/step_*.vtu"))[-1]
    m = meshio.read(last)
    summary = json.load(open(f"{tmc_out}/summary.json"))
    f = np.load(npz)
    gdim = f["u"].shape[1]
    x = m.points[:, :gdim]
    iu = match(x, f["x_u"][:, :gdim])
    it = match(x, f["x_t"][:, :gdim])
    u_max, u_l2 = rel(m.point_data["u"][:, :gdim], f["u"][iu])
    t_max, t_l2 = rel(m.point_data["theta"], f["theta"][it])
    print(json.dumps({
        "nodes": len(x), "u_max": u_max, "u_l2": u_l2, "theta_max": t_max, "theta_l2": t_l2,
        "tmc_iterations": summary["newton_iterations"], "fenicsx_iterations": int(f["iterations"]),
        "tmc_seconds": summary["wall_seconds"], "fenicsx_seconds": float(f["wall"]),
        "steps": int(f["steps"]),
    }))


if __name__ == "__main__":
    main(*sys.argv[1:3])
