#!/usr/bin/python3
"""The one-cell block's drag without a third medium: an independent reference.

    /usr/bin/python3 corner.py NX NY DELTA MU R [--base-end E] [--drag D] [--steps S]
                               [--width W] [--height H] [--sides]

FEniCSx (Debian's python3-dolfinx 0.5.2) solves tmc's block alone: 2 wide, 1 high, the
Neo-Hooke energy of eq. 12 (K = 20, G = 10, plane strain with 3D invariants), P1 on NX x NY
right-diagonal triangles. Its bottom meets a rigid base, the region x <= E (2 by default, the
block's own width), y <= 0, whose corner is rounded by R, through a penalty on the
penetration (100 G/h; the normal and the tangent of the base at the nearest point). Its top
is pressed down by DELTA (ten steps), then dragged by D (0.5) along x in S (40) steps,
held in y.

Friction is Coulomb's in full slip: every point in contact takes the traction mu p_N along
the base's tangent against the drag, switched on over the first 0.1 of the drag (the block
shears before it slides) and at full value from there. It has no history, so each state is
the equilibrium of its loads; that the slide is everywhere forward is checked after each step
(the `back` column: the share of the normal force where the last step's slip went backward,
which must be 0 once the friction is whole). A drag that sticks anywhere is not this model's.

`--width`, `--height`: another block (2 × 1 by default; 1 × 0.5 is the pad of
`cases/pad-box-slide.toml`). `--sides`: its sides meet the base too (a face that rolls onto it).

Prints per step: drag, F_t (against the drag), F_n, F_t/F_n and `back`, the forces the base
puts on the block (the contact tractions integrated over its bottom).
"""
import argparse
import sys
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem, mesh
from dolfinx.fem.petsc import NonlinearProblem
from dolfinx.nls.petsc import NewtonSolver
from mpi4py import MPI

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from plane_strain import first_piola, pad  # noqa: E402

args = argparse.ArgumentParser()
for name in ["nx", "ny"]:
    args.add_argument(name, type=int)
for name in ["delta", "mu", "r"]:
    args.add_argument(name, type=float)
args.add_argument("--base-end", type=float, default=2.0)
args.add_argument("--drag", type=float, default=0.5)
args.add_argument("--steps", type=int, default=40)
args.add_argument("--width", type=float, default=2.0)
args.add_argument("--height", type=float, default=1.0)
args.add_argument("--sides", action="store_true")
a = args.parse_args()

K, G = 20.0, 10.0
msh = mesh.create_rectangle(MPI.COMM_WORLD, [np.array([0.0, 0.0]), np.array([a.width, a.height])],
                            [a.nx, a.ny], mesh.CellType.triangle,
                            diagonal=mesh.DiagonalType.right)
V = fem.VectorFunctionSpace(msh, ("Lagrange", 1))
u = fem.Function(V)  # the displacement being solved for
un = fem.Function(V)  # at the last accepted step
uprev = fem.Function(V)  # at the one before
v = ufl.TestFunction(V)
P = first_piola(u, K, G)

fdim = 1


def touching(X):
    """The facets that may meet the base: the bottom, and with --sides both sides."""
    sides = np.isclose(X[0], 0.0) | np.isclose(X[0], a.width)
    return np.isclose(X[1], 0.0) | (a.sides & sides)


bottom = mesh.locate_entities_boundary(msh, fdim, touching)
top = mesh.locate_entities_boundary(msh, fdim, lambda X: np.isclose(X[1], a.height))
tags = mesh.meshtags(msh, fdim, bottom, np.full(len(bottom), 1, dtype=np.int32))
ds = ufl.Measure("ds", domain=msh, subdomain_data=tags, metadata={"quadrature_degree": 4})

# the base: its top face up to the rounding, then the arc about c, its side below that
x = ufl.SpatialCoordinate(msh) + u
c = ufl.as_vector([a.base_end - a.r, -a.r])
d = x - c
dist = ufl.sqrt(ufl.dot(d, d) + 1e-30)
on_top = ufl.le(x[0], a.base_end - a.r)
gap = ufl.conditional(on_top, x[1], dist - a.r)
n = ufl.conditional(on_top, ufl.as_vector([0.0, 1.0]), d / dist)
t = ufl.as_vector([n[1], -n[0]])
h = a.width / a.nx
p_n = 100 * G / h * ufl.max_value(-gap, 0.0)
sliding = fem.Constant(msh, 0.0)
traction = p_n * n - a.mu * sliding * p_n * t
R = (ufl.inner(P, pad(ufl.grad(v))) * ufl.dx(metadata={"quadrature_degree": 2})
     - ufl.dot(traction, v) * ds(1))

ux, uy = fem.Constant(msh, 0.0), fem.Constant(msh, 0.0)
bcs = [fem.dirichletbc(ux, fem.locate_dofs_topological(V.sub(0), fdim, top), V.sub(0)),
       fem.dirichletbc(uy, fem.locate_dofs_topological(V.sub(1), fdim, top), V.sub(1))]
problem = NonlinearProblem(R, u, bcs)


def newton():
    """A Newton solver of its own (one that has failed once may then take a changed load
    as converged in 0 iterations)."""
    solver = NewtonSolver(MPI.COMM_WORLD, problem)
    solver.rtol, solver.atol, solver.max_it = 1e-10, 1e-10, 200
    solver.convergence_criterion = "residual"
    ksp = solver.krylov_solver
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    return solver


solver = newton()
forces = [fem.form(traction[i] * ds(1)) for i in range(2)]
backward = fem.form(ufl.conditional(ufl.lt(ufl.dot(un - uprev, t), 0.0), p_n, 0.0) * ds(1))


def advance(to_x, to_y, parts=1):
    """The loads moved from where they are to (to_x, to_y) in `parts` steps, each halved
    again where Newton fails; the forces on the block at the end."""
    x0, y0 = float(ux.value), float(uy.value)
    for k in range(1, parts + 1):
        ux.value, uy.value = x0 + (to_x - x0) * k / parts, y0 + (to_y - y0) * k / parts
        kept = u.x.array.copy()
        global solver
        try:
            iterations, converged = solver.solve(u)
        except RuntimeError:
            iterations, converged = 0, False
        if not converged or iterations == 0:  # every step moves the top
            solver = newton()
            u.x.array[:] = kept
            ux.value = x0 + (to_x - x0) * (k - 1) / parts
            uy.value = y0 + (to_y - y0) * (k - 1) / parts
            if parts > 64:
                raise SystemExit(f"no convergence at a drag of {float(ux.value)}")
            return advance(to_x, to_y, parts * 2)
        fx, fy = (fem.assemble_scalar(f) for f in forces)
        uprev.x.array[:] = un.x.array
        un.x.array[:] = u.x.array
    return fx, fy


for k in range(1, 11):
    fx, fy = advance(0.0, -a.delta * k / 10)
print(f"# pressed {a.delta}: F_n {fy:.6f}")
print("# drag F_t F_n F_t/F_n back")
for k in range(1, a.steps + 1):
    at = a.drag * k / a.steps
    sliding.value = min(1.0, at / 0.1)
    fx, fy = advance(at, -a.delta)
    back = fem.assemble_scalar(backward) / fy
    print(f"{at:.4f} {-fx:.6f} {fy:.6f} {-fx / fy:.5f} {back:.4f}", flush=True)
