"""True displacement errors of bracket runs against a P2 finite-element solution.

For each solution.vtu given, the displacement of every node is compared with the
finite-element displacement at the same point (benches/fem_reference.py's mesh and
model: P2 triangles, size H, graded to H/20 at the re-entrant corner; default
H = 1 mm, where the tip deflection has converged to 4 digits). Printed per run: the
nodes, the true e_inf(u) (the largest nodal error over the largest finite-element
displacement) and where it is, the run's estimated e_inf(u) (`estimated_error` in
solution.vtu), the tip deflection's error, and the largest true error near each
singular corner and away from them. The finite-element solution is cached in
output/fem_bracket_H.pkl.

    pip install scikit-fem gmsh numpy
    python3 benches/fem_errors.py [--h 0.001] RUN/solution.vtu ...
"""
import os
import pickle
import sys

import numpy as np
import skfem

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fem_reference  # noqa: E402
from section_forces import read_vtu  # noqa: E402

CORNERS = [(0.06, 0.14), (0.0, 0.0), (0.06, 0.0)]
HOLES = [((0.03, 0.05), 0.012), ((0.14, 0.17), 0.01)]
TIP = (0.2, 0.17)


def finite_elements(h):
    """The finite-element mesh and displacement (cached)."""
    cache = f"output/fem_bracket_{h}.pkl"
    if os.path.exists(cache):
        return pickle.load(open(cache, "rb"))
    mesh, _, u, _, _ = fem_reference.displacement_field(h, True, "base")
    os.makedirs("output", exist_ok=True)
    pickle.dump((mesh, u), open(cache, "wb"))
    return mesh, u


def displacement_at(mesh, u, points):
    """Finite-element displacement at `points` (n x 2). Points on the boundary are moved
    inside by a hair: onto the box by 1e-12, off the holes' polygons by 1 % of the radius."""
    basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTriP2()), intorder=4)
    q = np.clip(points[:, :2].T.copy(), 1e-12, 0.2 - 1e-12)
    for centre, radius in HOLES:
        dx, dy = q[0] - centre[0], q[1] - centre[1]
        r = np.hypot(dx, dy)
        near = r < 1.01 * radius
        q[0][near] = centre[0] + dx[near] / r[near] * 1.01 * radius
        q[1][near] = centre[1] + dy[near] / r[near] * 1.01 * radius
    return np.vstack([probe(basis, u, q[:, k : k + 1000]) for k in range(0, q.shape[1], 1000)])


def probe(basis, u, q):
    """Displacement at the columns of `q`; a chunk with a point outside the mesh (on a
    straight edge, by round-off) is split until that point is found and moved by 1e-9 m
    in the first of eight directions that lands inside."""
    try:
        return (basis.probes(q) @ u).reshape(2, -1).T
    except ValueError:
        if q.shape[1] > 1:
            half = q.shape[1] // 2
            return np.vstack([probe(basis, u, q[:, :half]), probe(basis, u, q[:, half:])])
    for angle in np.arange(8) * np.pi / 4:
        try:
            return (basis.probes(q + 1e-9 * np.array([[np.cos(angle)], [np.sin(angle)]])) @ u).reshape(2, -1).T
        except ValueError:
            continue
    raise ValueError(f"point {q[:, 0]} is outside the finite-element mesh")


def main():
    args = sys.argv[1:]
    h = 0.001
    if args[:1] == ["--h"]:
        h, args = float(args[1]), args[2:]
    mesh, u = finite_elements(h)
    scale = np.abs(displacement_at(mesh, u, np.array([TIP]))).max()
    for path in args:
        run = read_vtu(path)
        points, displacement = run["Points"], run["displacement"][:, :2]
        fe = displacement_at(mesh, u, points)
        error = np.hypot(*(displacement - fe).T) / np.hypot(*fe.T).max()
        estimate = run.get("estimated_error", np.full(len(points), np.nan))
        worst = np.argmax(error)
        tip = np.argmin(np.hypot(points[:, 0] - TIP[0], points[:, 1] - TIP[1]))
        tip_error = (displacement[tip, 1] - fe[tip, 1]) / scale
        near = [np.hypot(points[:, 0] - c[0], points[:, 1] - c[1]) < 0.01 for c in CORNERS]
        away = ~np.any(near, axis=0)
        corners = ", ".join(f"{error[m].max():.2e}" for m in near)
        print(
            f"{path}: {len(points)} nodes, true e_inf(u) {error.max():.2e} at ({points[worst, 0]:.4f}, {points[worst, 1]:.4f}), "
            f"estimated {np.nanmax(estimate):.2e}, tip uy {tip_error:+.2e}; within 1 cm of the corners {corners}, elsewhere {error[away].max():.2e}"
        )


if __name__ == "__main__":
    main()
