"""Prototype (not shipped): can the displacement-pressure system be solved iteratively?
GMRES preconditioned by the block upper-triangular [[A_uu, B], [0, S]], with one
smoothed-aggregation V-cycle (pyamg) or an exact solve for A_uu and a diagonal S:
the exact Schur complement's diagonal (small systems only) or the SIMPLE
approximation diag(D) - diag(C diag(A_uu)^-1 B); and the spread of the Schur
complement's eigenvalues against its diagonal. Needs `pip install scipy pyamg`.
    RESTART=300 python3 benches/pyamg_saddle_point.py DIR
with DIR written by `mlsm run SCENE --export-system DIR` on a u-p scene
(`formulation = "displacement-pressure"`, `solver.kind = "lu"`).
BENCHMARKS.md, "The displacement-pressure form and the iterative solvers".
"""
import csv
import os
import sys

import numpy as np
import pyamg
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from pyamg.relaxation.utils import relaxation_as_linear_operator

from exported_system import load

restart = int(os.environ.get('RESTART', '30'))
d = sys.argv[1]
a0, b, xy, s = load(d)
component = np.zeros(a0.shape[0], int)
with open(f'{d}/unknowns.csv') as f:
    rows = csv.reader(f)
    next(rows)
    for r in rows:
        component[int(r[0])] = int(r[2])
A, b = (sp.diags(s) @ a0).tocsr(), s * b  # row equilibration, as mlsm solves
u, p = np.where(component < 2)[0], np.where(component == 2)[0]
Auu, B, C, D = A[u][:, u].tocsr(), A[u][:, p].tocsr(), A[p][:, u].tocsr(), A[p][:, p].tocsr()

# Rigid-body modes of the displacement block, centred and scaled as mlsm does.
xu, cu = xy[u], np.arange(len(u)) % 2
centre, size = xu.mean(0), abs(xu - xu.mean(0)).max()
modes = np.zeros((len(u), 3))
modes[cu == 0, 0], modes[cu == 1, 1] = 1, 1
modes[cu == 0, 2], modes[cu == 1, 2] = -(xu[cu == 0, 1] - centre[1]) / size, (xu[cu == 1, 0] - centre[0]) / size
Ab = Auu.tobsr(blocksize=(2, 2))
BH = relaxation_as_linear_operator(('block_gauss_seidel', {'sweep': 'symmetric', 'iterations': 2}),
                                   Ab.T.tobsr(blocksize=(2, 2)), np.zeros((len(u), 1))) @ modes
gs = ('block_gauss_seidel', {'sweep': 'symmetric'})
ml = pyamg.smoothed_aggregation_solver(Ab, B=modes, BH=BH, symmetry='nonsymmetric', strength=('symmetric', {'theta': 0.0}),
                                       presmoother=gs, postsmoother=gs, improve_candidates=None, max_coarse=400)
res = []
pyamg.krylov.fgmres(Auu, np.random.default_rng(1).standard_normal(len(u)), M=ml.aspreconditioner(), tol=1e-10,
                    maxiter=10, restart=30, residuals=res)
print(f'{A.shape[0]} unknowns; the displacement block alone: GMRES(30) + SA-AMG {len(res) - 1} iterations')


def run(name, s_diag, solve_u):
    def apply(r):
        z = np.zeros_like(r)
        z[p] = r[p] / s_diag
        z[u] = solve_u(r[u] - B @ z[p])
        return z
    res = []
    x, _ = pyamg.krylov.fgmres(A, b, M=spla.LinearOperator(A.shape, matvec=apply), tol=1e-10, maxiter=max(1, 600 // restart),
                               restart=restart, residuals=res)
    true = np.linalg.norm(b - A @ x) / np.linalg.norm(b)
    print(f'{name}: GMRES({restart}) {len(res) - 1} iterations, true relative residual {true:.1e}', flush=True)


simple = D.diagonal() - (C @ sp.diags(1 / Auu.diagonal()) @ B).diagonal()
if A.shape[0] < 20000:
    X = spla.splu(Auu.tocsc()).solve(B.toarray())
    S = D.toarray() - C @ X
    sd = np.diag(S)
    ev = np.linalg.eigvals(S / sd[:, None])
    print('eigenvalues of S diag(S)^-1: |lambda| percentiles 0/1/5/50/95/99/100:',
          np.array2string(np.percentile(abs(ev), [0, 1, 5, 50, 95, 99, 100]), precision=3),
          f'; {(ev.real < 0).sum()} with a negative real part')
    run('exact A_uu, S = diag of the exact Schur complement', sd, spla.splu(Auu.tocsc()).solve)
    run('AMG on A_uu, S = diag of the exact Schur complement', sd, ml.aspreconditioner().matvec)
run('AMG on A_uu, S = SIMPLE diagonal', simple, ml.aspreconditioner().matvec)
