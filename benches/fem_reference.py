"""Finite-element reference values for the L bracket (problems/bracket.toml), an
independent check of the meshless solution where no closed form exists.

P2 triangles (scikit-fem) on a gmsh mesh of size h, graded to h/20 at the re-entrant
corner (0.06, 0.14); plane stress, E = 210e9 Pa, nu = 0.3, shear traction -5e6 Pa on
the tip x = 0.2, clamped base y = 0 (or the back x = 0 with `back`). Prints, per mesh
size, the node count, the tip deflection uy(0.2, 0.17) and the von Mises stress at
(0.03, 0.062) (probe hole1_von_mises).

    pip install scikit-fem gmsh
    python3 benches/fem_reference.py holes base        # the shipped bracket
    python3 benches/fem_reference.py noholes base      # the L alone
    python3 benches/fem_reference.py noholes base 0.06,0.14 0.2,0.17   # and u there
    python3 benches/fem_reference.py holes base --shelf -1e6   # and a load on inner_h
With points (x,y) after the clamp, also the displacement (ux, uy) at each. With
`--shelf T`, also a vertical traction T (Pa) on the inner horizontal edge y = 0.14,
one of the re-entrant corner's two edges.
"""
import sys

import gmsh
import numpy as np
import skfem
from skfem.models.elasticity import lame_parameters, linear_elasticity

E, NU, SHEAR = 210e9, 0.3, -5e6
VERTICES = [(0, 0), (0.06, 0), (0.06, 0.14), (0.2, 0.14), (0.2, 0.2), (0, 0.2)]
CORNER = (0.06, 0.14)


def mesh(h, holes):
    """Triangles of the bracket, size h, h/20 at the re-entrant corner."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    occ = gmsh.model.occ
    points = [occ.addPoint(x, y, 0) for x, y in VERTICES]
    lines = [occ.addLine(points[k], points[(k + 1) % 6]) for k in range(6)]
    surface = occ.addPlaneSurface([occ.addCurveLoop(lines)])
    if holes:
        discs = [(2, occ.addDisk(0.03, 0.05, 0, 0.012, 0.012)), (2, occ.addDisk(0.14, 0.17, 0, 0.01, 0.01))]
        occ.cut([(2, surface)], discs)
    occ.synchronize()
    corner = [t for d, t in gmsh.model.getEntities(0) if np.allclose(gmsh.model.getValue(0, t, [])[:2], CORNER)]
    field = gmsh.model.mesh.field
    distance = field.add("Distance")
    field.setNumbers(distance, "PointsList", corner)
    size = field.add("Threshold")
    field.setNumber(size, "InField", distance)
    field.setNumber(size, "SizeMin", h / 20)
    field.setNumber(size, "SizeMax", h)
    field.setNumber(size, "DistMin", 0.0)
    field.setNumber(size, "DistMax", 0.05)
    field.setAsBackgroundMesh(size)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.model.mesh.generate(2)
    _, xyz, _ = gmsh.model.mesh.getNodes()
    _, _, connectivity = gmsh.model.mesh.getElements(2)
    gmsh.finalize()
    x = xyz.reshape(-1, 3)[:, :2]
    triangles = connectivity[0].reshape(-1, 3) - 1
    used = np.unique(triangles)
    renumber = -np.ones(len(x), int)
    renumber[used] = np.arange(len(used))
    return skfem.MeshTri(x[used].T.copy(), renumber[triangles].T.copy())


SHELF = 0.0


def displacement_field(h, holes, clamp):
    """The mesh, the P2 basis, the displacement and the plane-stress Lame parameters."""
    m = mesh(h, holes)
    element = skfem.ElementVector(skfem.ElementTriP2())
    basis = skfem.Basis(m, element, intorder=4)
    lam, mu = lame_parameters(E, NU)
    lam = 2 * mu * lam / (lam + 2 * mu)  # plane stress
    stiffness = skfem.asm(linear_elasticity(lam, mu), basis)
    tip = skfem.FacetBasis(m, element, facets=m.facets_satisfying(lambda x: np.abs(x[0] - 0.2) < 1e-9), intorder=4)
    load = skfem.asm(skfem.LinearForm(lambda v, w: SHEAR * v[1]), tip)
    if SHELF:
        on_shelf = lambda x: (np.abs(x[1] - 0.14) < 1e-9) & (x[0] > 0.06 - 1e-9)
        shelf = skfem.FacetBasis(m, element, facets=m.facets_satisfying(on_shelf), intorder=4)
        load = load + skfem.asm(skfem.LinearForm(lambda v, w: SHELF * v[1]), shelf)
    axis = 1 if clamp == "base" else 0
    clamped = basis.get_dofs(lambda x: np.abs(x[axis]) < 1e-9).all()
    u = skfem.solve(*skfem.condense(stiffness, load, D=clamped))
    return m, basis, u, lam, mu


def solve(h, holes, clamp, points=()):
    m, basis, u, lam, mu = displacement_field(h, holes, clamp)
    uy = (basis.probes(np.array([[0.2 - 1e-12], [0.17]])) @ u)[1]
    # Von Mises from the P2 displacement gradient (P1 per triangle) at the probe point.
    gradient = skfem.Basis(m, skfem.ElementTriP1(), intorder=4)
    grad = [[gradient.project(basis.interpolate(u).grad[c][d]) for d in range(2)] for c in range(2)]
    at = np.array([[0.03], [0.062]])
    g = [[(gradient.probes(at) @ grad[c][d])[0] for d in range(2)] for c in range(2)]
    exx, eyy, exy = g[0][0], g[1][1], 0.5 * (g[0][1] + g[1][0])
    sxx = (lam + 2 * mu) * exx + lam * eyy
    syy = lam * exx + (lam + 2 * mu) * eyy
    sxy = 2 * mu * exy
    von_mises = np.sqrt(sxx**2 - sxx * syy + syy**2 + 3 * sxy**2)
    at = np.array(points, float).T.reshape(2, -1) - np.array([[1e-12], [0.0]])
    displacement = (basis.probes(at) @ u).reshape(2, -1).T if len(points) else []
    return m.p.shape[1], uy, von_mises, displacement


if __name__ == "__main__":
    if "--shelf" in sys.argv:
        at = sys.argv.index("--shelf")
        SHELF = float(sys.argv[at + 1])
        del sys.argv[at:at + 2]
    holes = sys.argv[1] == "holes" if len(sys.argv) > 1 else True
    clamp = sys.argv[2] if len(sys.argv) > 2 else "base"
    points = [tuple(map(float, p.split(","))) for p in sys.argv[3:]]
    for h in [0.004, 0.002, 0.001, 0.0005]:
        nodes, uy, vm, displacement = solve(h, holes, clamp, points)
        print(f"h = {h}: {nodes} nodes, tip uy = {uy:.6e} m, von Mises at hole1 = {vm:.6e} Pa", flush=True)
        for (x, y), (ux, uy_) in zip(points, displacement):
            print(f"  u({x}, {y}) = ({ux:.6e}, {uy_:.6e}) m", flush=True)
