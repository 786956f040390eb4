"""Kirsch and Lame by finite elements (scikit-fem): one run, its times and its errors.

The plates, materials and loads are read from problems/kirsch.toml and
problems/lame.toml, so both programs solve the same problem:

- Lame: the quarter ring a <= r <= b, symmetry on both axes, the exact traction on the
  bore, a free outer edge; plane strain.
- Kirsch: the quarter plate [0, L]^2 minus the disc of radius a, symmetry on both axes,
  the exact traction on x = L and y = L, a free hole; plane stress.

Mesh (`--mesh polar`, the default): a graded polar map. `n` elements over the quarter turn; along each ray the
element edges grow geometrically (element size proportional to the distance from the
centre, aspect ratio about 1), which is the scale on which both solutions vary. Each
quadrilateral is split into two triangles. P2 and P3 elements use quadratic geometry
(MeshTri2: every node, edge midpoints included, placed by the exact map, so the bore
and the hole are curved); P1 uses straight triangles. `--mesh unstructured`: a
Delaunay mesh by gmsh with the same grading (size (pi/2) a / n at the inner arc, in
proportion to the distance from the centre), the mesh a user gets for a general plate;
its edge midpoints on the arcs moved onto them for P2 and P3.

Errors as `mlsm` defines them (src/quality/post/mod.rs): e_inf over nodes and
components relative to the largest exact component. The nodes are all nodes of the
Lagrange element (vertices, edge and interior nodes). The stress at a node is the
average over the elements that share it (what a post-processor shows); the error of
the raw element values at the nodes is printed too (`e_inf_sigma_raw`).

Timed (in-program): mesh, basis, assembly, solve and the nodal stresses; not timed:
the exact solution and the errors. Prints one JSON line.

    python3 benches/fem_plates.py lame --order 3 --solver direct --n 24
"""
import argparse
import json
import math
import os
import time
import tomllib

import numpy as np
import pyamg
import skfem
from skfem.helpers import dot
from skfem.models.elasticity import linear_elasticity

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
# AMG: CG preconditioned by smoothed aggregation with the rigid-body modes, to a
# relative residual far below the smallest target error (1e-7).
SOLVER_TOLERANCE, MAX_ITERATIONS = 1e-10, 2000
ELEMENTS = {1: skfem.ElementTriP1, 2: skfem.ElementTriP2, 3: skfem.ElementTriP3}


class Plate:
    """Geometry, material and exact solution of a shipped scene."""

    def __init__(self, scene):
        spec = tomllib.load(open(os.path.join(ROOT, "problems", f"{scene}.toml"), "rb"))
        self.scene = scene
        m = spec["material"]
        e, nu = float(m["E"]), float(m["nu"])
        self.mu = e / (2 * (1 + nu))
        lam = e * nu / ((1 + nu) * (1 - 2 * nu))
        self.plane = m["plane"]
        # plane stress: the in-plane lambda* = 2 lambda mu / (lambda + 2 mu)
        self.lam = lam if self.plane == "strain" else 2 * lam * self.mu / (lam + 2 * self.mu)
        self.kappa = 3 - 4 * nu if self.plane == "strain" else (3 - nu) / (1 + nu)
        self.nu, self.young = nu, e
        x = spec["exact"]
        if scene == "lame":
            self.a, self.b, self.p = float(x["inner"]), float(x["outer"]), float(x["pressure"])
        elif scene == "kirsch":
            self.a, self.t = float(x["radius"]), float(x["tension"])
            rect = next(r for r in spec["domain"]["region"] if r["shape"] == "rectangle")
            self.side = float(rect["max"][0])
        else:
            raise SystemExit(f"fem_plates.py: scene {scene!r} is not one of lame, kirsch")

    def ray_length(self, theta):
        """Distance from the centre to the outer edge along the ray at angle theta."""
        if self.scene == "lame":
            return np.full_like(theta, self.b)
        return self.side / np.maximum(np.cos(theta), np.sin(theta))

    def map(self, rho, theta):
        """The polar map: rho in [0, 1] from the inner to the outer edge, geometric."""
        d = self.a * (self.ray_length(theta) / self.a) ** rho
        return np.array([d * np.cos(theta), d * np.sin(theta)])

    def displacement(self, x, y):
        r, t = np.hypot(x, y), np.arctan2(y, x)
        if self.scene == "lame":
            k = self.p * self.a**2 / (self.b**2 - self.a**2)
            c1 = k * (1 + self.nu) * (1 - 2 * self.nu) / self.young if self.plane == "strain" else k * (1 - self.nu) / self.young
            ur = c1 * r + k * (1 + self.nu) * self.b**2 / self.young / r
            return np.array([ur * np.cos(t), ur * np.sin(t)])
        a, k, c = self.a, self.kappa, self.t * self.a / (8 * self.mu)
        q1, q3 = a / r, (a / r) ** 3
        u = (r / a) * (k + 1) * np.cos(t) + 2 * q1 * ((1 + k) * np.cos(t) + np.cos(3 * t)) - 2 * q3 * np.cos(3 * t)
        v = (r / a) * (k - 3) * np.sin(t) + 2 * q1 * ((1 - k) * np.sin(t) + np.sin(3 * t)) - 2 * q3 * np.sin(3 * t)
        return np.array([c * u, c * v])

    def stress(self, x, y):
        """[sigma_xx, sigma_yy, sigma_xy]."""
        r, t = np.hypot(x, y), np.arctan2(y, x)
        if self.scene == "lame":
            k = self.p * self.a**2 / (self.b**2 - self.a**2)
            srr, stt = k * (1 - (self.b / r) ** 2), k * (1 + (self.b / r) ** 2)
            c, s = np.cos(t), np.sin(t)
            return np.array([srr * c * c + stt * s * s, srr * s * s + stt * c * c, (srr - stt) * s * c])
        q2, q4 = (self.a / r) ** 2, (self.a / r) ** 4
        c2, s2, c4, s4 = np.cos(2 * t), np.sin(2 * t), np.cos(4 * t), np.sin(4 * t)
        return self.t * np.array(
            [1 - q2 * (1.5 * c2 + c4) + 1.5 * q4 * c4, -q2 * (0.5 * c2 - c4) - 1.5 * q4 * c4, -q2 * (0.5 * s2 + s4) + 1.5 * q4 * s4]
        )

    def mesh(self, n, order):
        """The graded polar mesh with n elements over the quarter turn (n even)."""
        n += n % 2  # a grid line on the diagonal, where Kirsch's outer edge turns
        mean = math.log(float(np.mean(self.ray_length(np.linspace(0, math.pi / 2, 9)))) / self.a)
        m = max(1, round(mean / (math.pi / 2 / n)))
        rho, theta = np.meshgrid(np.linspace(0, 1, m + 1), np.linspace(0, math.pi / 2, n + 1), indexing="ij")
        index = np.arange((m + 1) * (n + 1)).reshape(m + 1, n + 1)
        a, b, c, d = index[:-1, :-1].ravel(), index[1:, :-1].ravel(), index[1:, 1:].ravel(), index[:-1, 1:].ravel()
        t = np.hstack([np.array([a, b, c]), np.array([a, c, d])])
        flat = skfem.MeshTri1(np.array([rho.ravel(), theta.ravel()]), t)
        if order == 1:
            return skfem.MeshTri1(self.map(*flat.p), t)
        quadratic = skfem.MeshTri2.from_mesh(flat)
        return skfem.MeshTri2(self.map(*quadratic.doflocs), quadratic.t)

    def unstructured(self, n, order):
        """A Delaunay (gmsh) mesh graded like the polar one: size (pi/2) a / n at the inner
        arc, growing in proportion to the distance from the centre. P2/P3: the edge
        midpoints on the arc are moved onto it (quadratic geometry)."""
        import gmsh

        h0 = math.pi / 2 * self.a / n
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        geo = gmsh.model.geo
        outer = [(self.b, 0), (0, self.b)] if self.scene == "lame" else [(self.side, 0), (self.side, self.side), (0, self.side)]
        centre = geo.addPoint(0, 0, 0)
        inner = [geo.addPoint(self.a, 0, 0), geo.addPoint(0, self.a, 0)]
        corners = [geo.addPoint(x, y, 0) for x, y in outer]
        arc = geo.addCircleArc(inner[0], centre, inner[1])
        curves = [geo.addLine(inner[0], corners[0])]
        if self.scene == "lame":
            curves.append(geo.addCircleArc(corners[0], centre, corners[1]))
        else:
            curves += [geo.addLine(corners[k], corners[k + 1]) for k in range(len(corners) - 1)]
        curves += [geo.addLine(corners[-1], inner[1]), -arc]
        geo.addPlaneSurface([geo.addCurveLoop(curves)])
        geo.synchronize()
        field = gmsh.model.mesh.field
        distance = field.add("Distance")
        field.setNumbers(distance, "CurvesList", [arc])
        size = field.add("MathEval")
        field.setString(size, "F", f"{h0} * (1 + F{distance} / {self.a})")
        field.setAsBackgroundMesh(size)
        for key in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
            gmsh.option.setNumber(key, 0)
        gmsh.model.mesh.generate(2)
        _, xyz, _ = gmsh.model.mesh.getNodes()
        types, _, connectivity = gmsh.model.mesh.getElements(2)
        gmsh.finalize()
        x = xyz.reshape(-1, 3)[:, :2]
        triangles = connectivity[list(types).index(2)].reshape(-1, 3).astype(np.int64) - 1
        used = np.unique(triangles)
        renumber = np.zeros(x.shape[0], dtype=np.int64)
        renumber[used] = np.arange(used.size)
        linear = skfem.MeshTri1(x[used].T.copy(), renumber[triangles].T.copy())
        if order == 1:
            return linear
        quadratic = skfem.MeshTri2.from_mesh(linear)
        doflocs = quadratic.doflocs.copy()
        radii = [self.a] + ([self.b] if self.scene == "lame" else [])
        for radius in radii:
            ends = np.hypot(*linear.p[:, linear.facets])  # (2, facets)
            on_arc = np.nonzero(np.all(np.abs(ends - radius) < 1e-9 * radius, axis=0))[0]
            d = quadratic.dofs.get_facet_dofs(on_arc).flatten()
            doflocs[:, d] *= radius / np.hypot(*doflocs[:, d])
        return skfem.MeshTri2(doflocs, quadratic.t)

    def edges(self, mesh):
        """Boundary facets: (left, bottom, loaded by the exact traction)."""
        x = mesh.p[:, mesh.facets]  # (2, 2, facets)
        tol = 1e-9 * self.a
        on = lambda test: np.nonzero(np.all(test(x[0], x[1]), axis=0))[0]  # noqa: E731
        left, bottom = on(lambda x, y: np.abs(x) < tol), on(lambda x, y: np.abs(y) < tol)
        if self.scene == "lame":
            loaded = on(lambda x, y: np.abs(np.hypot(x, y) - self.a) < 1e-9 * self.a)
        else:
            loaded = on(lambda x, y: np.maximum(x, y) > self.side * (1 - 1e-12))
        return left, bottom, loaded


def rigid_body_modes(basis, free):
    """Translations and the rotation at the free unknowns (pyamg's near-null space)."""
    ux, uy = basis.split_indices()
    x = basis.doflocs
    b = np.zeros((basis.N, 3))
    b[ux, 0], b[uy, 1] = 1.0, 1.0
    b[ux, 2], b[uy, 2] = -x[1, ux], x[0, uy]
    return b[free]


def solve(plate, n, order, solver, kind="polar"):
    times = {}
    clock = time.perf_counter()
    mesh = plate.mesh(n, order) if kind == "polar" else plate.unstructured(n, order)
    element = skfem.ElementVector(ELEMENTS[order]())
    basis = skfem.Basis(mesh, element, intorder=2 * order)
    times["mesh"] = time.perf_counter() - clock
    clock = time.perf_counter()
    stiffness = skfem.asm(linear_elasticity(plate.lam, plate.mu), basis)
    left, bottom, loaded = plate.edges(mesh)
    facets = skfem.FacetBasis(mesh, element, facets=loaded, intorder=2 * order + 2)

    @skfem.LinearForm
    def traction(v, w):
        s = plate.stress(*w.x)
        sigma = np.array([[s[0], s[2]], [s[2], s[1]]])
        return dot(np.einsum("ij...,j...->i...", sigma, w.n), v)

    load = skfem.asm(traction, facets)
    fixed = np.concatenate([basis.get_dofs(left).all("u^1"), basis.get_dofs(bottom).all("u^2")])
    times["assembly"] = time.perf_counter() - clock
    clock = time.perf_counter()
    a, rhs, u, free = skfem.condense(stiffness, load, D=fixed)
    converged, iterations = True, None
    if solver == "direct":
        u[free] = skfem.solve(a, rhs)
    else:
        hierarchy = pyamg.smoothed_aggregation_solver(a.tocsr(), B=rigid_body_modes(basis, free))
        residuals = []
        u[free] = hierarchy.solve(rhs, tol=SOLVER_TOLERANCE, accel="cg", maxiter=MAX_ITERATIONS, residuals=residuals)
        iterations = len(residuals) - 1
        if residuals[-1] > SOLVER_TOLERANCE * residuals[0]:
            converged = False
    times["solve"] = time.perf_counter() - clock
    clock = time.perf_counter()
    # Values and gradients at every element's own nodes, then averaged per node.
    scalar = ELEMENTS[order]()
    at_nodes = (scalar.doflocs.T.copy(), np.ones(scalar.doflocs.shape[0]))
    nodal = skfem.Basis(mesh, element, quadrature=at_nodes)
    numbering = skfem.Basis(mesh, scalar, quadrature=at_nodes).element_dofs  # (local, elements)
    field = nodal.interpolate(u)
    g = field.grad  # (2, 2, elements, local)
    trace = g[0, 0] + g[1, 1]
    raw = np.array([plate.lam * trace + 2 * plate.mu * g[0, 0], plate.lam * trace + 2 * plate.mu * g[1, 1], plate.mu * (g[0, 1] + g[1, 0])])
    nodes = numbering.max() + 1
    ids = numbering.T.ravel()
    count = np.bincount(ids, minlength=nodes)
    averaged = np.array([np.bincount(ids, weights=c.ravel(), minlength=nodes) / count for c in raw])
    times["stress"] = time.perf_counter() - clock
    # Errors (not timed).
    xy = nodal.global_coordinates().value  # (2, elements, local)
    xn = np.zeros((2, nodes))
    xn[:, ids] = xy.reshape(2, -1)
    exact_u, exact_s = plate.displacement(*xy), plate.stress(*xn)
    exact_raw = plate.stress(*xy)
    e_u = np.abs(field.value - exact_u).max() / np.abs(exact_u).max()
    e_s = np.abs(averaged - exact_s).max() / np.abs(exact_s).max()
    e_raw = np.abs(raw - exact_raw).max() / np.abs(exact_raw).max()
    return {
        "scene": plate.scene,
        "config": f"P{order} {solver}" + ("" if kind == "polar" else f", {kind}"),
        "n": n,
        "nodes": int(nodes),
        "unknowns": int(basis.N),
        "iterations": iterations,
        "converged": converged,
        "e_inf_u": float(e_u),
        "e_inf_sigma": float(e_s),
        "e_inf_sigma_raw": float(e_raw),
        "times_s": times,
        "seconds": sum(times.values()),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scene", choices=["lame", "kirsch"])
    parser.add_argument("--order", type=int, choices=[1, 2, 3], default=2)
    parser.add_argument("--solver", choices=["direct", "amg"], default="direct")
    parser.add_argument("--n", type=int, default=16, help="elements over the quarter turn at the inner arc")
    parser.add_argument("--mesh", choices=["polar", "unstructured"], default="polar")
    args = parser.parse_args()
    print(json.dumps(solve(Plate(args.scene), args.n, args.order, args.solver, args.mesh)))


if __name__ == "__main__":
    main()
