#!/usr/bin/python3
"""A block dragged on a rigid flat base with Coulomb friction that sticks and slips: the
reference `corner.py` (full slip only) cannot be where no state of full slip exists.

    /usr/bin/python3 stick.py NX NY DELTA MU [--width W] [--height H] [--drag D] [--steps S]
                              [--tangential T]

FEniCSx (Debian's python3-dolfinx 0.5.2) solves the block alone, W × H (1 × 0.5 by default:
the pad of `cases/pad-box-slide.toml`), the Neo-Hooke energy of eq. 12 (K = 20, G = 10, plane
strain with 3D invariants), P1 on NX x NY right-diagonal triangles. Each node of its bottom and
of its sides meets the base y <= 0 through a penalty, k_n = 100 G/h times the node's share of
the face (h the cells' shorter side), and k_t = T k_n along it (T = 1 by default): a node below
the base is pushed up by k_n times its depth, and held along x at the place it stuck by k_t
times the distance, up to mu times its normal force, past which it slides and the place it
sticks moves with it (a return mapping, per node, committed at each converged step). Its top
is pressed down by DELTA (ten steps, friction on), then dragged by D (0.5) along x in S (100)
steps, held in y; a step that Newton cannot take is cut in two, down to 1/64.

Prints per step: drag, F_t (against the drag), F_n, F_t/F_n, and the share of the normal force
on nodes that stick.
"""
import argparse
import sys
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem, mesh
from dolfinx.fem.petsc import (apply_lifting, assemble_matrix, assemble_vector,
                               create_matrix, create_vector, set_bc)
from mpi4py import MPI
from petsc4py import PETSc

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from plane_strain import first_piola, pad  # noqa: E402

args = argparse.ArgumentParser()
for name in ["nx", "ny"]:
    args.add_argument(name, type=int)
for name in ["delta", "mu"]:
    args.add_argument(name, type=float)
args.add_argument("--width", type=float, default=1.0)
args.add_argument("--height", type=float, default=0.5)
args.add_argument("--drag", type=float, default=0.5)
args.add_argument("--steps", type=int, default=100)
args.add_argument("--tangential", type=float, default=1.0)
a = args.parse_args()

K, G = 20.0, 10.0
W, H = a.width, a.height
msh = mesh.create_rectangle(MPI.COMM_WORLD, [np.array([0.0, 0.0]), np.array([W, H])],
                            [a.nx, a.ny], mesh.CellType.triangle,
                            diagonal=mesh.DiagonalType.right)
V = fem.VectorFunctionSpace(msh, ("Lagrange", 1))
u = fem.Function(V)
v = ufl.TestFunction(V)
du = ufl.TrialFunction(V)
P = first_piola(u, K, G)
R = ufl.inner(P, pad(ufl.grad(v))) * ufl.dx(metadata={"quadrature_degree": 2})
residual = fem.form(R)
jacobian = fem.form(ufl.derivative(R, u, du))

fdim = 1
top = mesh.locate_entities_boundary(msh, fdim, lambda X: np.isclose(X[1], H))
ux, uy = fem.Constant(msh, 0.0), fem.Constant(msh, 0.0)
held = [fem.dirichletbc(ux, fem.locate_dofs_topological(V.sub(0), fdim, top), V.sub(0)),
        fem.dirichletbc(uy, fem.locate_dofs_topological(V.sub(1), fdim, top), V.sub(1))]

# the contact nodes: the bottom and the sides, less the top's corners (held)
X = V.tabulate_dof_coordinates()[:, :2]
on_face = (np.isclose(X[:, 1], 0.0) | np.isclose(X[:, 0], 0.0) | np.isclose(X[:, 0], W))
nodes = np.where(on_face & ~np.isclose(X[:, 1], H))[0]
# each node's share of the faces it lies on (half of each cell side of its face)
hx, hy = W / a.nx, H / a.ny
share = np.zeros(len(nodes))
for k, b in enumerate(nodes):
    x, y = X[b]
    if np.isclose(y, 0.0):
        share[k] += hx * (0.5 if np.isclose(x, 0.0) or np.isclose(x, W) else 1.0)
    if np.isclose(x, 0.0) or np.isclose(x, W):
        share[k] += hy * (0.5 if np.isclose(y, 0.0) else 1.0)
k_n = 100 * G / min(hx, hy) * share
k_t = a.tangential * k_n
anchor = X[nodes, 0].copy()  # where each node sticks along x (committed)


def contact(ua, anchor):
    """Each node's normal and tangential force on the block, whether it sticks, and the
    2 x 2 derivative of the forces with respect to its (u_x, u_y)."""
    x = X[nodes, 0] + ua[2 * nodes]
    y = X[nodes, 1] + ua[2 * nodes + 1]
    touching = y < 0.0
    f_n = np.where(touching, -k_n * y, 0.0)
    trial = -k_t * (x - anchor)
    limit = a.mu * f_n
    sticks = touching & (np.abs(trial) <= limit)
    f_t = np.where(sticks, trial, -np.sign(x - anchor) * limit)
    f_t = np.where(touching, f_t, 0.0)
    d = np.zeros((len(nodes), 2, 2))  # d[k, i, j]: d f_i / d u_j, i, j in (x, y)
    d[:, 1, 1] = np.where(touching, -k_n, 0.0)
    d[:, 0, 0] = np.where(sticks, -k_t, 0.0)
    slides = touching & ~sticks
    d[:, 0, 1] = np.where(slides, np.sign(x - anchor) * a.mu * k_n, 0.0)
    return f_t, f_n, sticks, d, x


A = create_matrix(jacobian)
b = create_vector(residual)
ksp = PETSc.KSP().create(MPI.COMM_WORLD)
ksp.setType("preonly")
ksp.getPC().setType("lu")
ksp.getPC().setFactorSolverType("mumps")


def solve(to_x, to_y):
    """Newton from the state as it is, the top moved to (to_x, to_y); whether it converged."""
    ua = u.x.array
    ux.value, uy.value = to_x, to_y
    for iteration in range(40):
        A.zeroEntries()
        assemble_matrix(A, jacobian, bcs=held)
        A.assemble()
        with b.localForm() as loc:
            loc.set(0.0)
        assemble_vector(b, residual)
        f_t, f_n, sticks, d, _ = contact(ua, anchor)
        # the residual is internal less external force: the contact's forces go in with a minus
        rows = np.concatenate([2 * nodes, 2 * nodes + 1]).astype(np.int32)
        b.setValues(rows, np.concatenate([-f_t, -f_n]), addv=PETSc.InsertMode.ADD)
        b.assemble()
        for k, node in enumerate(nodes):
            idx = np.array([2 * node, 2 * node + 1], dtype=np.int32)
            A.setValues(idx, idx, -d[k].ravel(), addv=PETSc.InsertMode.ADD)
        A.assemble()
        apply_lifting(b, [jacobian], bcs=[held], x0=[u.vector], scale=-1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        set_bc(b, held, u.vector, -1.0)
        norm = b.norm()
        if iteration == 0:
            first = max(norm, 1e-30)
        if norm < 1e-9 * max(first, 1.0) or norm < 1e-11:
            return True
        ksp.setOperators(A)
        dx = b.copy()
        try:
            ksp.solve(b, dx)
        except PETSc.Error:  # a factorisation that fails: the step is cut
            return False
        ua[:] -= dx.array
        if not np.all(np.isfinite(ua)):
            return False
    return False


def advance(to_x, to_y, parts=1):
    """The loads moved to (to_x, to_y) in `parts` steps, each halved again where Newton
    fails; the contact's forces at the end."""
    global anchor
    ua = u.x.array
    x0, y0 = float(ux.value), float(uy.value)
    for k in range(1, parts + 1):
        kept = ua.copy()
        if not solve(x0 + (to_x - x0) * k / parts, y0 + (to_y - y0) * k / parts):
            ua[:] = kept
            ux.value = x0 + (to_x - x0) * (k - 1) / parts
            uy.value = y0 + (to_y - y0) * (k - 1) / parts
            if parts >= 64:
                raise SystemExit(f"no convergence at a drag of {float(ux.value):.5f}")
            return advance(to_x, to_y, parts * 2)
        f_t, f_n, sticks, _, x = contact(ua, anchor)
        # committed: a node that slid sticks where it now stands, less its elastic stretch
        touching = f_n > 0.0
        anchor = np.where(touching, x + f_t / k_t, x)
    return f_t, f_n, sticks


for k in range(1, 11):
    f_t, f_n, sticks = advance(0.0, -a.delta * k / 10)
print(f"# pressed {a.delta}: F_n {f_n.sum():.6f}")
print("# drag F_t F_n F_t/F_n stuck")
for k in range(1, a.steps + 1):
    at = a.drag * k / a.steps
    f_t, f_n, sticks = advance(at, -a.delta)
    Ft, Fn = -f_t.sum(), f_n.sum()
    stuck = f_n[sticks].sum() / Fn
    print(f"{at:.4f} {Ft:.6f} {Fn:.6f} {Ft / Fn:.5f} {stuck:.4f}", flush=True)
