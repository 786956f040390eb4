"""The smallest singular values of an exported Navier system and where its softest
mode lives: the tool behind the README's analysis of the scattered-node bracket
(Known limits, re-entrant corners).

Reads a folder written by `mlsm run SCENE --export-system DIR` (matrix.mtx,
unknowns.csv), scales every row to unit 2-norm (as the solver's equilibration does),
takes the dense SVD (systems of up to a few thousand unknowns) and prints, for the
two smallest singular values: the rows that carry the left vector (the equations that
nearly depend on each other), the unknowns that carry the right vector, the right
vector's share on ghost nodes, and how much of it a rigid-body motion
`u = a - theta y, v = b + theta x` of the real nodes explains.

    pip install numpy scipy
    mlsm --quiet run problems/bracket.toml --spacing 0.004 --export-system /tmp/sys
    python3 benches/near_null_mode.py /tmp/sys
"""
import csv
import sys

import numpy as np
import scipy.io
import scipy.sparse as sp


def main(folder, modes=2, shown=6):
    a = scipy.io.mmread(folder + "/matrix.mtx").tocsr()
    rows = list(csv.DictReader(open(folder + "/unknowns.csv")))
    xy = np.array([[float(r["x"]), float(r["y"])] for r in rows])
    ghost = np.array([int(r["ghost"]) for r in rows]) == 1
    component = np.array([int(r["component"]) for r in rows])
    scale = 1.0 / np.sqrt(np.asarray(a.multiply(a).sum(1)).ravel())
    u, s, vt = np.linalg.svd((sp.diags(scale) @ a).toarray())
    print("smallest singular values:", " ".join(f"{v:.3e}" for v in s[::-1][:6]))
    rigid = np.zeros((len(rows), 3))
    rigid[component == 0, 0] = 1.0
    rigid[component == 0, 2] = -xy[component == 0, 1]
    rigid[component == 1, 1] = 1.0
    rigid[component == 1, 2] = xy[component == 1, 0]
    real = ~ghost
    for k in range(1, modes + 1):
        left, right = u[:, -k], vt[-k]
        print(f"mode {k}: singular value {s[-k]:.3e}")
        for name, vector in (("rows", left), ("unknowns", right)):
            top = np.argsort(-np.abs(vector))[:shown]
            where = ", ".join(f"({xy[i, 0]:.4f}, {xy[i, 1]:.4f}) {'xy'[component[i]]}{' ghost' if ghost[i] else ''} {vector[i]:+.3f}" for i in top)
            print(f"  {name}: {where}")
        coef = np.linalg.lstsq(rigid[real], right[real], rcond=None)[0]
        unexplained = np.sum((rigid[real] @ coef - right[real]) ** 2) / np.sum(right[real] ** 2)
        print(f"  on ghosts {np.sum(right[ghost] ** 2):.3f} of the vector; rigid motion theta = {coef[2]:+.3f} "
              f"explains {1 - unexplained:.3f} of it on the real nodes")


if __name__ == "__main__":
    main(sys.argv[1])
