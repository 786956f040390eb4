"""Reading a system written by `mlsm run SCENE --export-system DIR` for the pyamg
prototypes (benches/pyamg_*.py): the matrix, right-hand side and node positions, the
rows equilibrated as mlsm solves them, and the rigid-body modes."""
import csv

import numpy as np
import scipy.io as sio
import scipy.sparse as sp


def load(d):
    """(A, b, xy, s): the matrix (CSR) and right-hand side as assembled, the position of
    each unknown's node, and the row scales 1 / max_j |a_ij| that mlsm equilibrates with."""
    a = sio.mmread(f'{d}/matrix.mtx').tocsr()
    b = sio.mmread(f'{d}/rhs.mtx')
    b = np.asarray(b.toarray() if sp.issparse(b) else b).ravel()
    xy = np.zeros((a.shape[0], 2))
    with open(f'{d}/unknowns.csv') as f:
        rows = csv.reader(f)
        next(rows)
        for r in rows:
            xy[int(r[0])] = (float(r[3]), float(r[4]))
    return a, b, xy, 1 / abs(a).max(axis=1).toarray().ravel()


def rigid_body_modes(xy):
    """The three rigid-body modes (1, 0), (0, 1), (-y, x) at every unknown (x, y interleaved)."""
    comp = np.arange(xy.shape[0]) % 2
    modes = np.zeros((xy.shape[0], 3))
    modes[comp == 0, 0], modes[comp == 1, 1] = 1, 1
    modes[comp == 0, 2], modes[comp == 1, 2] = -xy[comp == 0, 1], xy[comp == 1, 0]
    return modes
