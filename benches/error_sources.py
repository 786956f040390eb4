"""Where the displacement error of a static Navier run comes from, row by row.

With `A u_h = b` the exported system (`mlsm run SCENE --export-system DIR`) and `u*`
the exact solution at every unknown's position (ghosts included: the closed forms of
Lame and Kirsch extend smoothly outside the plate), the truncation error of the rows
is `tau = A u* - b` and the error of the run `u_h - u* = -A^-1 tau`. The rows are split
into groups, and `-A^-1 tau_group` is the part of the error each group causes (the
parts add up to the whole). Printed per group: its rows, the largest part of e_inf(u)
it causes (relative to the largest exact component, as `mlsm` reports e_inf(u)) and
where.

Groups: displacement rows (a single 1), traction rows (in a ghost's row), Navier rows
at boundary nodes and ghosts, Navier rows of interior nodes by their distance to the
boundary in spacings (below 2.5, 2.5-5, beyond).

    mlsm run problems/lame.toml --export-system DIR
    output/fem-venv/bin/python benches/error_sources.py lame DIR   # numpy, scipy: benches/time_to_accuracy.sh installs them
"""
import csv
import os
import sys

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from exported_system import load  # noqa: E402
from fem_plates import Plate  # noqa: E402


def groups(a, d):
    """A label per row (see the module's doc), which unknowns are at real nodes, and
    the unknowns' positions and components."""
    with open(f"{d}/unknowns.csv") as f:
        rows = list(csv.DictReader(f))
    n = a.shape[0]
    single = np.diff(a.indptr) == 1
    node = np.array([int(r["node"]) for r in rows])
    comp = np.array([int(r["component"]) for r in rows])
    ghost = np.array([r["ghost"].strip().lower() in ("1", "true") for r in rows])
    xy = np.array([(float(r["x"]), float(r["y"])) for r in rows])
    real = ~ghost
    # A ghost's owner is the nearest real node (it sits one spacing out along the normal).
    tree = cKDTree(xy[real])
    spacing = np.median(tree.query(xy[real], k=3)[0][:, 2])
    owner_row = np.flatnonzero(real)[tree.query(xy[ghost])[1]]
    owner = {node[g]: node[o] for g, o in zip(np.flatnonzero(ghost), owner_row)}
    owners = set(owner.values())
    own = {(node[i], comp[i]): i for i in range(n) if real[i]}
    dist = cKDTree(xy[real][np.isin(node[real], list(owners))]).query(xy)[0] / spacing
    label = np.empty(n, dtype=object)
    for i in range(n):
        if single[i]:
            label[i] = "displacement rows"
        elif ghost[i]:
            # the traction, unless the owner's own row of this component holds a displacement
            label[i] = "Navier rows at boundary nodes" if single[own[(owner[node[i]], comp[i])]] else "traction rows"
        elif node[i] in owners:
            label[i] = "Navier rows at boundary nodes"
        elif dist[i] < 2.5:
            label[i] = "Navier rows, interior, < 2.5 h"
        elif dist[i] < 5:
            label[i] = "Navier rows, interior, 2.5-5 h"
        else:
            label[i] = "Navier rows, interior, >= 5 h"
    return label, real, xy, comp


def main(scene, d):
    a, b, xy, row_scale = load(d)
    # rows equilibrated as mlsm solves them: SuperLU loses the solution without it
    # (traction and Navier rows differ by 1 / h in scale)
    a, b = (sp.diags(row_scale) @ a).tocsr(), row_scale * b
    label, real, xy, comp = groups(a, d)
    exact = Plate(scene).displacement(xy[:, 0], xy[:, 1])  # (2, unknowns)
    u_star = exact[comp, np.arange(a.shape[0])]
    tau = a @ u_star - b
    lu = spla.splu(a.tocsc())
    scale = np.abs(u_star[real]).max()
    u_h = lu.solve(b)
    total = np.abs(u_h - u_star)[real].max() / scale
    print(f"{scene} {d}: {real.sum() // 2} nodes; e_inf(u) {total:.2e} (LU of the exported system)")
    for g in sorted(set(label)):
        t = np.where(label == g, tau, 0.0)
        e = -lu.solve(t)
        part = np.abs(e)[real]
        i = np.flatnonzero(real)[part.argmax()]
        print(f"  {g:34} {np.sum(label == g):6} rows: e_inf(u) part {part.max() / scale:.2e} at ({xy[i, 0]:.4g}, {xy[i, 1]:.4g})")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
