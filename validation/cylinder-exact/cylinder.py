#!/usr/bin/python3
"""A rigid body slid along a plate in exact contact: an independent reference.

    /usr/bin/python3 cylinder.py MESH.msh [--obstacle polygon|circle] [--press 0.15]
                                 [--slide 0.5] [--steps 200] [--penalty 1e4] [--points 20]
                                 [--rim rim] [--mu 0]

FEniCSx (Debian's python3-dolfinx 0.5.2) solves the group "plate" of a mesh tmc made alone
(`tmc mesh geo/cylinder-plate.geo --set h=0.1 -o MESH.msh`, or a run's mesh.msh): the
Neo-Hooke energy of eq. 12 (K = 20, G = 10, plane strain with 3D invariants), P1, its bottom
(y = 0) held, its top face at y = 0.5. There is no third medium. The other body is rigid, as
tmc's is where its whole boundary is prescribed: the convex polygon of the nodes of the group
RIM (the README's cylinder, or the pad of `pad-box-rigid.geo`), or for a cylinder the circle
its rim's nodes were drawn on. It is pressed PRESS down in twenty steps, then slid SLIDE along
x in STEPS steps, held in y.

Contact is a penalty on the plate's top face, at POINTS Gauss points per edge: where a point
stands inside the body, the traction (PENALTY G/h) times its depth pushes it out along the
normal of the nearest side (the polygon) or along the radius (the circle); with MU, Coulomb
friction in full slip over the slide, MU times that pressure along the face, the way the body
slides. Each state is the equilibrium of its loads.

Prints per step: the slide, F_t, F_n and F_t/F_n, the force the plate puts on the body (the
contact tractions integrated over the plate's top; F_n > 0 pressing).
"""
import argparse
import sys
from pathlib import Path

import gmsh
import numpy as np
import ufl
from dolfinx import fem, mesh
from dolfinx.fem import petsc
from mpi4py import MPI
from petsc4py import PETSc

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from plane_strain import first_piola, pad  # noqa: E402

args = argparse.ArgumentParser()
args.add_argument("msh")
args.add_argument("--obstacle", choices=["polygon", "circle"], default="polygon")
args.add_argument("--press", type=float, default=0.15)
args.add_argument("--slide", type=float, default=0.5)
args.add_argument("--steps", type=int, default=200)
args.add_argument("--penalty", type=float, default=1e4)
args.add_argument("--points", type=int, default=20)
args.add_argument("--rim", default="rim", help="the group of the rigid body's boundary")
args.add_argument("--mu", type=float, default=0.0, help="Coulomb friction in full slip")
args.add_argument("--pass", dest="passes", choices=["sides", "corners", "both"], default="sides",
                  help="what is pushed across what: the plate's points across the body's "
                  "sides, the body's corners across the plate's face, or both")
a = args.parse_args()

K, G = 20.0, 10.0


def group(name, dim):
    """The nodes (by gmsh tag) of the elements of the physical group `name`, per element."""
    tag = next(t for d, t in gmsh.model.getPhysicalGroups(dim)
               if gmsh.model.getPhysicalName(d, t) == name)
    cells = []
    for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
        _, _, nodes = gmsh.model.mesh.getElements(dim, entity)
        cells.append(np.array(nodes[0], dtype=np.int64).reshape(-1, dim + 1))
    return np.vstack(cells)


gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.open(a.msh)
tags, coords, _ = gmsh.model.mesh.getNodes()
place = {int(t): coords[3 * i:3 * i + 2] for i, t in enumerate(tags)}
plate = group("plate", 2)
rim = group(a.rim, 1)
gmsh.finalize()

# the plate's own nodes, numbered from 0
used = np.unique(plate)
index = {int(t): i for i, t in enumerate(used)}
x0 = np.array([place[int(t)] for t in used])
cells = np.vectorize(lambda t: index[int(t)])(plate).astype(np.int64)
domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.triangle, 1))
msh = mesh.create_mesh(MPI.COMM_WORLD, cells, x0, domain)

# the rim's polygon, its corners in order round the cylinder (anticlockwise)
after = {int(p): int(q) for p, q in rim}
if len(after) != len(rim):
    after = {int(q): int(p) for p, q in rim}
corners, at = [], int(rim[0][0])
for _ in range(len(rim)):
    corners.append(place[at])
    at = after[at]
corners = np.array(corners)
# the body's centre, and the radius of the circle its rim's nodes stand on (a cylinder's)
CENTRE = corners.mean(axis=0)
RADIUS = float(np.mean(np.linalg.norm(corners - CENTRE, axis=1)))
if np.cross(corners[1] - corners[0], CENTRE - corners[0]) < 0:
    corners = corners[::-1]
print(f"# {len(used)} plate nodes, {len(cells)} cells; the rim a polygon of {len(corners)} sides")

V = fem.VectorFunctionSpace(msh, ("Lagrange", 1))
u = fem.Function(V)
v = ufl.TestFunction(V)
P = first_piola(u, K, G)

fdim = 1
top = mesh.locate_entities_boundary(msh, fdim, lambda X: np.isclose(X[1], 0.5))
bottom = mesh.locate_entities_boundary(msh, fdim, lambda X: np.isclose(X[1], 0.0))
tags = mesh.meshtags(msh, fdim, top, np.full(len(top), 1, dtype=np.int32))
ds = ufl.Measure("ds", domain=msh, subdomain_data=tags,
                 metadata={"quadrature_degree": 2 * a.points - 1})

shift = fem.Constant(msh, np.zeros(2))  # the cylinder's displacement
x = ufl.SpatialCoordinate(msh) + u - shift
if a.obstacle == "circle":
    d = x - ufl.as_vector(CENTRE)
    dist = ufl.sqrt(ufl.dot(d, d) + 1e-30)
    depth, n = RADIUS - dist, d / dist
else:
    # a point inside the polygon is nearest the side whose sector about the centre it stands
    # in (the sectors' bounds bisect the corners of a regular polygon): a flat sum of sides,
    # each weighted 1 in its sector and 0 elsewhere
    r = x - ufl.as_vector(CENTRE)
    depth, n = 0, ufl.as_vector([0.0, 0.0])
    for k in range(len(corners)):
        p, q = corners[k], corners[(k + 1) % len(corners)]
        if min(p[1], q[1]) > CENTRE[1]:
            continue  # the upper half never meets the plate
        outward = np.array([q[1] - p[1], p[0] - q[0]]) / np.linalg.norm(q - p)
        a_, b_ = p - CENTRE, q - CENTRE
        inside = ufl.conditional(ufl.ge(a_[0] * r[1] - a_[1] * r[0], 0.0), 1.0, 0.0) * \
            ufl.conditional(ufl.gt(r[0] * b_[1] - r[1] * b_[0], 0.0), 1.0, 0.0)
        depth = depth + inside * ufl.dot(ufl.as_vector(p) - x, ufl.as_vector(outward))
        n = n + inside * ufl.as_vector(outward)
h = float(np.median(np.linalg.norm(np.diff(corners, axis=0), axis=1)))
p_n = a.penalty * G / h * ufl.max_value(depth, 0.0)
# what the body puts on the plate: the pressure, and where it slides (x growing) friction in
# full slip, μ p_n along the face in the direction of the slide
sliding = fem.Constant(msh, 0.0)
traction = p_n * n + a.mu * sliding * p_n * ufl.as_vector([-n[1], n[0]])
R = (ufl.inner(P, pad(ufl.grad(v))) * ufl.dx(metadata={"quadrature_degree": 1})
     - ufl.dot(traction, v) * ds(1))

zero = fem.Constant(msh, np.zeros(2))
bcs = [fem.dirichletbc(zero, fem.locate_dofs_topological(V, fdim, bottom), V)]
residual = fem.form(R)
jacobian = fem.form(ufl.derivative(R, u, ufl.TrialFunction(V)))
R_elastic = ufl.inner(P, pad(ufl.grad(v))) * ufl.dx(metadata={"quadrature_degree": 1})
elastic = fem.form(R_elastic)
elastic_jacobian = fem.form(ufl.derivative(R_elastic, u, ufl.TrialFunction(V)))
forces = [fem.form(traction[i] * ds(1)) for i in range(2)]


# the plate's face as a line of nodes (block dofs, left to right), for the body's corners
face = fem.locate_dofs_topological(V, fdim, top)
face = face[np.argsort(V.tabulate_dof_coordinates()[face, 0])]
face_X = V.tabulate_dof_coordinates()[face, :2]
low = corners[corners[:, 1] <= CENTRE[1]]
kappa = a.penalty * G  # per corner: the Gauss points' penalty times the length they stand for


def corner_forces(values):
    """The body's corners pushed across the plate's face (node to segment, no friction): per
    corner below its face, the face's two nodes, their weights, the face's normal and the
    force the corner puts on the face (κ × depth along the normal, into the plate)."""
    if a.passes == "sides":
        return []
    at = face_X + values.reshape(-1, 2)[face]
    found = []
    for c in low + np.array(shift.value):
        k = np.searchsorted(at[:, 0], c[0]) - 1
        if not 0 <= k < len(at) - 1:
            continue
        t = at[k + 1] - at[k]
        length = np.linalg.norm(t)
        t /= length
        n = np.array([-t[1], t[0]])
        xi = np.dot(c - at[k], t) / length
        depth = -np.dot(c - at[k], n)
        if depth > 0:
            found.append((k, np.array([1 - xi, xi]), n, -kappa * depth * n))
    return found


def assemble_R(snes, x, b):
    x.copy(u.vector)
    u.vector.ghostUpdate(PETSc.InsertMode.INSERT_VALUES, PETSc.ScatterMode.FORWARD)
    with b.localForm() as local:
        local.set(0.0)
    if a.passes != "corners":
        petsc.assemble_vector(b, residual)
    else:
        petsc.assemble_vector(b, elastic)
    petsc.apply_lifting(b, [jacobian], [bcs], [x], -1.0)
    b.ghostUpdate(PETSc.InsertMode.ADD_VALUES, PETSc.ScatterMode.REVERSE)
    array = b.getArray()
    for k, w, _, f in corner_forces(u.x.array):
        for node, weight in zip(face[k:k + 2], w):
            array[2 * node:2 * node + 2] -= weight * f
    petsc.set_bc(b, bcs, x, -1.0)


def assemble_J(snes, x, A, P_):
    A.zeroEntries()
    petsc.assemble_matrix(A, jacobian if a.passes != "corners" else elastic_jacobian, bcs)
    A.assemble()
    # each corner's depth along the face's normal, the normal held (Newton's line search
    # makes up for its turn)
    for k, w, n, _ in corner_forces(u.x.array):
        nodes = face[k:k + 2]
        for i, wi in zip(nodes, w):
            for j, wj in zip(nodes, w):
                block = kappa * wi * wj * np.outer(n, n)
                A.setValues([2 * i, 2 * i + 1], [2 * j, 2 * j + 1], block.ravel(),
                            addv=PETSc.InsertMode.ADD_VALUES)
    A.assemble()


# Newton with a backtracking line search: the penalty's active points and the polygon's
# sides switch between iterations, and a full Newton step then cycles
snes = PETSc.SNES().create(MPI.COMM_WORLD)
b_vec, A_mat = petsc.create_vector(residual), petsc.create_matrix(jacobian)
snes.setFunction(assemble_R, b_vec)
snes.setJacobian(assemble_J, A_mat)
snes.setTolerances(rtol=1e-10, atol=1e-10, max_it=100)
options = PETSc.Options()
options["snes_linesearch_type"] = "bt"
snes.setFromOptions()
snes.getKSP().setType("preonly")
snes.getKSP().getPC().setType("lu")
snes.getKSP().getPC().setFactorSolverType("mumps")


def advance(to, parts=1):
    """The cylinder moved from where it is to `to` in `parts` steps, each halved again where
    Newton fails; the force the plate puts on the cylinder at the end."""
    start = np.array(shift.value)
    for k in range(1, parts + 1):
        shift.value = start + (to - start) * k / parts
        kept = u.x.array.copy()
        x_vec = u.vector.copy()
        snes.solve(None, x_vec)
        if snes.getConvergedReason() <= 0:
            u.x.array[:] = kept
            shift.value = start + (to - start) * (k - 1) / parts
            if parts > 64:
                raise SystemExit(f"no convergence at {shift.value}")
            return advance(to, parts * 2)
        x_vec.copy(u.vector)
        u.x.scatter_forward()
    on_plate = np.zeros(2)
    if a.passes != "corners":
        on_plate += [fem.assemble_scalar(f) for f in forces]
    for _, _, _, f in corner_forces(u.x.array):
        on_plate += f
    return -on_plate[0], -on_plate[1]


for k in range(1, 21):
    fx, fy = advance(np.array([0.0, -a.press * k / 20]))
print(f"# pressed {a.press}: F_n {fy:.6f}")
print("# slide F_t F_n F_t/F_n")
sliding.value = 1.0
for k in range(1, a.steps + 1):
    at = a.slide * k / a.steps
    fx, fy = advance(np.array([at, -a.press]))
    print(f"{at:.5f} {fx:.6f} {fy:.6f} {fx / fy:.5f}", flush=True)
