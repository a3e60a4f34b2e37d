#!/usr/bin/python3
"""Solve a tmc validation case with FEniCSx (Debian's python3-dolfinx 0.5.2) on tmc's own mesh.

    /usr/bin/python3 solve_fenicsx.py CASE.toml TMC_OUT_DIR OUT.npz

Same discrete problem as tmc: the mesh tmc wrote (TMC_OUT_DIR/mesh.msh, read with
gmshio.model_to_mesh after gmsh.merge), displacement and temperature of the mesh's order (P1
or isoparametric P2), the Neo-Hooke +
thermal-expansion energy of eq. 12 (or Mooney-Rivlin's, with `law = "mooney-rivlin"`) and the pulled-back Fourier law (plane strain with 3D
invariants in 2D), radiation ε σ (θ⁴ − θ∞⁴) per current area on the groups that radiate (linear
meshes), the case's boundary conditions, tmc's load steps (from its history.csv) and
tmc's quadrature rules (1 point on simplices, 2^d Gauss points on quads and hexes).
"""
import csv
import sys
import time
import tomllib

import gmsh
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem.petsc import NonlinearProblem
from dolfinx.io import gmshio
from dolfinx.nls.petsc import NewtonSolver
from mpi4py import MPI


def main(case_path, tmc_out, out_path):
    case = tomllib.load(open(case_path, "rb"))
    (region,) = case["region"]  # one solid region
    K = region["K"]
    alpha, theta0, k = region.get("alpha", 0.0), region.get("theta0", 0.0), region["k"]
    lambdas = [float(r["lambda"]) for r in csv.DictReader(open(f"{tmc_out}/history.csv"))][1:]

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.merge(f"{tmc_out}/mesh.msh")
    gdim = gmsh.model.getDimension()
    names = {}
    for dim, tag in gmsh.model.getPhysicalGroups(gdim - 1):
        names[gmsh.model.getPhysicalName(dim, tag)] = tag
    mesh, _, facet_tags = gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=gdim)
    gmsh.finalize()

    cell = mesh.ufl_cell()
    name = cell.cellname()
    order = mesh.ufl_domain().ufl_coordinate_element().degree()
    # tmc's rules (basix degrees): linear: centroid on T1/tet4 (1), 2x2(x2) Gauss on Q1/H1 (3);
    # quadratic: 3 points on tri6 (2), 14 on tet10 (4), 3x3(x3) Gauss on quad9/hex27 (4)
    degree = {
        (1, "triangle"): 1, (1, "tetrahedron"): 1, (1, "quadrilateral"): 3, (1, "hexahedron"): 3,
        (2, "triangle"): 2, (2, "tetrahedron"): 4, (2, "quadrilateral"): 4, (2, "hexahedron"): 4,
    }[(order, name)]
    dx = ufl.dx(metadata={"quadrature_degree": degree})
    el_u = ufl.VectorElement("Lagrange", cell, order)
    el_t = ufl.FiniteElement("Lagrange", cell, order)
    W = fem.FunctionSpace(mesh, ufl.MixedElement([el_u, el_t]))
    w = fem.Function(W)
    u, th = ufl.split(w)
    v, q = ufl.TestFunctions(W)

    def pad(g):  # 2D gradient → 3x3 (plane strain)
        if gdim == 3:
            return g
        return ufl.as_matrix([[g[0, 0], g[0, 1], 0], [g[1, 0], g[1, 1], 0], [0, 0, 0]])

    def pad_vec(g):
        return g if gdim == 3 else ufl.as_vector([g[0], g[1], 0])

    F = ufl.variable(ufl.Identity(3) + pad(ufl.grad(u)))
    J = ufl.det(F)
    C = F.T * F
    lnJ = ufl.ln(J)
    thermal = 3 * alpha * (th - theta0) * K * lnJ
    if region.get("law", "neo-hooke") == "mooney-rivlin":
        c10, c01 = region["C10"], region["C01"]
        I1 = ufl.tr(C)
        I2 = (I1**2 - ufl.tr(C * C)) / 2
        psi = (c10 * (J ** (-2.0 / 3.0) * I1 - 3) + c01 * (J ** (-4.0 / 3.0) * I2 - 3)
               + K / 2 * (J - 1) ** 2 - thermal)
    else:
        mu = region["mu"]
        psi = K / 2 * lnJ**2 + mu / 2 * (J ** (-2.0 / 3.0) * ufl.tr(C) - 3) - thermal
    P = ufl.diff(psi, F)
    R = (ufl.inner(P, pad(ufl.grad(v))) * dx
         + J * k * ufl.inner(ufl.inv(C) * pad_vec(ufl.grad(th)), pad_vec(ufl.grad(q))) * dx)
    # radiation through the current area da = J |F⁻ᵀ N| dA, on tmc's facet rules (2-point
    # Gauss on lines and quad faces' 2x2, the centroid on triangle faces)
    facet_degree = {"triangle": 3, "quadrilateral": 3, "tetrahedron": 1, "hexahedron": 3}[name]
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags,
                     metadata={"quadrature_degree": facet_degree})
    N = pad_vec(ufl.FacetNormal(mesh))
    da = J * ufl.sqrt(ufl.dot(ufl.inv(C) * N, N))
    for bc in case["bc"]:
        rad = bc.get("radiation")
        if rad is None:
            continue
        assert order == 1, "radiation is compared on linear meshes"
        es, inf = rad["emissivity"] * rad["sigma"], rad["theta_inf"]
        R += es * (th**4 - inf**4) * da * q * ds(names[bc["group"]])

    # Dirichlet conditions, each value a Constant set per load step
    fdim = gdim - 1
    ramped = []
    bcs = []
    for bc in case["bc"]:
        facets = facet_tags.find(names[bc["group"]])
        for comp, key in enumerate(["ux", "uy", "uz"][:gdim] + ["theta"]):
            if key not in bc:
                continue
            sub = W.sub(1) if key == "theta" else W.sub(0).sub(comp)
            dofs = fem.locate_dofs_topological(sub, fdim, facets)
            start = theta0 if key == "theta" else 0.0
            value = fem.Constant(mesh, start)
            bcs.append(fem.dirichletbc(value, dofs, sub))
            ramped.append((value, start, bc[key], bc.get("ramp", True)))

    # initial state: zero displacement, θ = θ0
    Vt, t_map = W.sub(1).collapse()
    w.x.array[t_map] = theta0

    problem = NonlinearProblem(R, w, bcs)
    solver = NewtonSolver(MPI.COMM_WORLD, problem)
    solver.rtol = 1e-13
    solver.atol = 1e-11
    solver.max_it = 50
    solver.convergence_criterion = "residual"
    t0 = time.perf_counter()
    iterations = 0
    for lam in lambdas:
        for value, start, full, ramp in ramped:
            value.value = start + lam * (full - start) if ramp else full
        n, converged = solver.solve(w)
        assert converged, f"FEniCSx did not converge at λ = {lam}"
        iterations += n
    wall = time.perf_counter() - t0

    Vu, u_map = W.sub(0).collapse()
    xu = Vu.tabulate_dof_coordinates()
    uvals = w.x.array[u_map].reshape(-1, gdim)
    xt = Vt.tabulate_dof_coordinates()
    tvals = w.x.array[t_map]
    np.savez(out_path, x_u=xu, u=uvals, x_t=xt, theta=tvals,
             iterations=iterations, wall=wall, steps=len(lambdas))


if __name__ == "__main__":
    main(*sys.argv[1:4])
