"""Prototype (not shipped): pyamg's smoothed aggregation on a system exported by
`mlsm run SCENE --export-system DIR`, with the left near-null candidates `BH` relaxed
by symmetric block Gauss-Seidel on `A^T y = 0` for 0, 1, 2, 4 iterations (and `B`
relaxed instead), to see which side of the nonsymmetric hierarchy matters.
Needs `pip install scipy pyamg`. Usage: python3 benches/pyamg_left_null.py DIR
(BENCHMARKS.md, "The multigrid on scattered node sets with symmetry edges").
"""
import sys

import numpy as np
import pyamg
import scipy.sparse as sp
from pyamg.relaxation.utils import relaxation_as_linear_operator

from exported_system import load, rigid_body_modes

a0, b, xy, s = load(sys.argv[1])
A, b = (sp.diags(s) @ a0).tobsr(blocksize=(2, 2)), s * b  # row equilibration, as mlsm solves
B = rigid_body_modes(xy)
gs = ('block_gauss_seidel', {'sweep': 'symmetric'})
zero = np.zeros((A.shape[0], 1))
relax = lambda M, its: relaxation_as_linear_operator(('block_gauss_seidel', {'sweep': 'symmetric', 'iterations': its}), M, zero) @ B
AT = A.T.tobsr(blocksize=(2, 2))
cases = {'none': (B, B)}
for its in (1, 2, 4):
    cases[f'BH relaxed {its}'] = (B, relax(AT, its))
cases['B relaxed 4'] = (relax(A, 4), B)
for name, (right, left) in cases.items():
    ml = pyamg.smoothed_aggregation_solver(A, B=right.copy(), BH=left.copy(), symmetry='nonsymmetric', strength='symmetric',
                                           presmoother=gs, postsmoother=gs, max_coarse=400, improve_candidates=None)
    res = []
    ml.solve(b, tol=1e-10, accel='gmres', maxiter=400, residuals=res)
    print(f'{name}: levels {[l.A.shape[0] for l in ml.levels]}, {len(res) - 1} iterations, relative residual {res[-1] / res[0]:.1e}')
