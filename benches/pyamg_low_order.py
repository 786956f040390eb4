"""Prototype (not shipped): GMRES on one exported system preconditioned by pyamg's
smoothed aggregation built on that system, or on a second system exported on the
same nodes (a low-order discretisation), scaled by the first system's row scales.
Needs `pip install scipy pyamg`. Usage:
    python3 benches/pyamg_low_order.py SYSTEM_DIR [AUXILIARY_DIR ...]
with directories written by `mlsm run SCENE --export-system DIR` (the same scene and
spacing, e.g. approximation.degree = 6 and 2; both must have the same unknowns).
BENCHMARKS.md, "A low-order operator for the multigrid".
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
zero = np.zeros((A.shape[0], 1))


def run(name, M, theta):
    # The left candidates relaxed by two symmetric block Gauss-Seidel sweeps on M^T, as mlsm does.
    BH = relaxation_as_linear_operator(('block_gauss_seidel', {'sweep': 'symmetric', 'iterations': 2}),
                                       M.T.tobsr(blocksize=(2, 2)), zero) @ B
    gs = ('block_gauss_seidel', {'sweep': 'symmetric'})
    ml = pyamg.smoothed_aggregation_solver(M, B=B, BH=BH, symmetry='nonsymmetric', strength=('symmetric', {'theta': theta}),
                                           presmoother=gs, postsmoother=gs, improve_candidates=None, max_coarse=400)
    res = []
    x, _ = pyamg.krylov.fgmres(A, b, M=ml.aspreconditioner(), tol=1e-10, maxiter=10, restart=30, residuals=res)
    true = np.linalg.norm(b - A @ x) / np.linalg.norm(b)
    print(f'{name}, theta {theta}: {len(res) - 1} iterations, true relative residual {true:.1e}, '
          f'operator complexity {ml.operator_complexity():.2f}, levels {[l.A.shape[0] for l in ml.levels]}', flush=True)


for theta in (0.0, 0.05):
    run('multigrid on the system', A, theta)
for d in sys.argv[2:]:
    aux = load(d)[0]
    assert aux.shape == A.shape, f'{d}: {aux.shape} unknowns against {A.shape}'
    for theta in (0.0, 0.05):
        run(f'multigrid on {d} (system row scales)', (sp.diags(s) @ aux).tobsr(blocksize=(2, 2)), theta)
