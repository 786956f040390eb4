"""Prototype (not shipped): why smoothed aggregation fails on the L bracket, from one
exported system's leading block (the nodes' unknowns; a bordered system's
multipliers dropped), rows equilibrated as mlsm solves them:
1. the eigenvalues of D^-1 A (D the 2x2 node blocks) with negative real part, and the
   node where each eigenvector is largest: modes that no Gauss-Seidel-type smoother
   damps (dense: a few thousand unknowns at most);
2. the growth per symmetric block Gauss-Seidel sweep (power iteration), with 2x2 node
   blocks and with every node within R local spacings of the corner `--corner X Y`
   solved together as one block (an exact local solve), for each R of `--patch`;
3. FGMRES(30) to 1e-10 (at most 300 iterations) on a random right-hand side with
   pyamg's smoothed aggregation (rigid-body modes, nonsymmetric, theta 0, two levels,
   the exact coarse solve) and the smoother of 2., against the smoother alone.
Needs `pip install scipy pyamg`. Usage:
    python3 benches/l_multigrid.py DIR H --corner 0.06 0.14 --patch 0 20 30
with DIR written by `mlsm run SCENE --spacing H --export-system DIR`.
BENCHMARKS.md, "The multigrid on the L: what fails".
"""
import argparse
import json

import numpy as np
import pyamg
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from exported_system import load, rigid_body_modes

ap = argparse.ArgumentParser()
ap.add_argument('dir')
ap.add_argument('h', type=float)
ap.add_argument('--corner', type=float, nargs=2, default=[0.06, 0.14])
ap.add_argument('--patch', type=float, nargs='*', default=[0.0])
args = ap.parse_args()

a0, _, xy, s = load(args.dir)
multipliers = json.load(open(f'{args.dir}/system.json')).get('multipliers', 0)
n = a0.shape[0] - multipliers
A = (sp.diags(s) @ a0).tocsr()[:n, :n].tocsr()
xy = xy[:n]
node_xy = xy[::2]
N = n // 2

if n <= 6000:
    dense = A.toarray()
    d_inv = sp.block_diag([np.linalg.pinv(dense[k:k + 2, k:k + 2]) for k in range(0, n, 2)]).toarray()
    w, v = np.linalg.eig(d_inv @ dense)
    negative = np.where(w.real < 0)[0]
    print(f'D^-1 A: {len(negative)} of {n} eigenvalues with negative real part')
    for i in negative[np.argsort(w.real[negative])][:6]:
        k = int(np.argmax(np.abs(v[0::2, i]) + np.abs(v[1::2, i])))
        print(f'  {w[i]:.3g} largest at ({node_xy[k][0]:.4g}, {node_xy[k][1]:.4g})')


def block_gauss_seidel(groups):
    """A symmetric block Gauss-Seidel sweep over `groups` (lists of nodes, in order)."""
    order = np.array([2 * k + c for g in groups for k in g for c in (0, 1)])
    inverse = np.empty(n, int)
    inverse[order] = np.arange(n)
    p = A[order][:, order].tocoo()
    block = np.repeat(np.arange(len(groups)), [2 * len(g) for g in groups])
    factors = []
    for keep in (block[p.row] >= block[p.col], block[p.row] <= block[p.col]):
        factors.append(sla.splu(sp.csc_matrix((p.data[keep], (p.row[keep], p.col[keep])), shape=(n, n))))

    def sweep(_, x, b):
        for f in factors:
            x += f.solve((b - A @ x)[order])[inverse]
    return sweep


rng = np.random.default_rng(0)
rhs = rng.standard_normal(n)
B = rigid_body_modes(xy)
for radius in args.patch:
    inside = np.hypot(node_xy[:, 0] - args.corner[0], node_xy[:, 1] - args.corner[1]) < radius * args.h
    groups = sorted([list(np.where(inside)[0])] * bool(inside.any()) + [[k] for k in range(N) if not inside[k]], key=min)
    sweep = block_gauss_seidel(groups)
    e = rng.standard_normal(n)
    for _ in range(30):
        before = np.linalg.norm(e)
        sweep(A, e, np.zeros(n))
        growth = np.linalg.norm(e) / before
        e /= np.linalg.norm(e)
    ml = pyamg.smoothed_aggregation_solver(A, B=B, symmetry='nonsymmetric', strength=('symmetric', {'theta': 0.0}),
                                           max_coarse=400, max_levels=2, keep=False)
    ml.levels[0].presmoother = ml.levels[0].postsmoother = sweep
    smoother_only = sla.LinearOperator((n, n), matvec=lambda r: (lambda x: (sweep(A, x, r), x)[1])(np.zeros(n)))
    line = f'patch {radius:g} h ({inside.sum()} nodes): growth per sweep {growth:.3g}'
    for name, m in (('two-level', ml.aspreconditioner()), ('smoother alone', smoother_only)):
        res = []
        pyamg.krylov.fgmres(A, rhs, M=m, restart=30, maxiter=10, tol=1e-10, residuals=res)
        line += f'; {name}: {len(res) - 1} iterations to {res[-1] / res[0]:.2e}'
    print(line, flush=True)
