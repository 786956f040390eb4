"""Prototype (not shipped): the spectral radius of block Gauss-Seidel's error
propagation `I - L^-1 A` on an exported system (rows equilibrated as mlsm solves), by
power iteration, for 2x2 node blocks (mlsm's smoother) and for blocks that join each
node with its ghost; and the node where the dominant mode is largest.
Needs `pip install scipy`. Usage: python3 benches/gauss_seidel_radius.py DIR
with DIR written by `mlsm run SCENE --export-system DIR`.
BENCHMARKS.md, "A low-order operator for the multigrid".
"""
import sys

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from scipy.spatial import cKDTree

from exported_system import load

a0, _, xy, s = load(sys.argv[1])
A = (sp.diags(s) @ a0).tocsr()
n = A.shape[0]
ghost = np.zeros(n // 2, bool)
with open(f'{sys.argv[1]}/unknowns.csv') as f:
    next(f)
    for line in f:
        r = line.split(',')
        ghost[int(r[1])] = int(r[5]) == 1
node_xy = xy[::2]


def radius(order, sizes, iterations=60):
    """Power iteration on I - L^-1 P A P^T with P the permutation `order` and L the
    block lower triangle of blocks of `sizes` unknowns; returns (radius, mode in the
    original numbering)."""
    p = A[order][:, order].tocoo()
    block = np.repeat(np.arange(len(sizes)), sizes)
    keep = block[p.row] >= block[p.col]
    lower = sp.csr_matrix((p.data[keep], (p.row[keep], p.col[keep])), shape=A.shape).tocsc()
    lu = sla.splu(lower)
    x = np.random.default_rng(0).standard_normal(n)
    rho = 0.0
    for _ in range(iterations):
        y = x - lu.solve(p.tocsr() @ x)
        rho = np.linalg.norm(y) / np.linalg.norm(x)
        x = y / np.linalg.norm(y)
    mode = np.empty(n)
    mode[order] = x
    return rho, mode


def report(name, rho, mode):
    k = int(np.argmax(np.abs(mode))) // 2
    print(f'{name}: spectral radius {rho:.3f}, dominant mode largest at node {k} ({node_xy[k][0]:.4g}, {node_xy[k][1]:.4g}) (ghost: {ghost[k]})')


# 2x2 blocks, the unknowns in their own order.
report('2x2 node blocks', *radius(np.arange(n), [2] * (n // 2)))
# Each ghost joined to the nearest real node (its owner, placed along the normal).
real, gh = np.where(~ghost)[0], np.where(ghost)[0]
owner = real[cKDTree(node_xy[real]).query(node_xy[gh])[1]]
members = {k: [k] for k in real}
for g, o in zip(gh, owner):
    members[o].append(g)
order = np.array([2 * m + c for k in real for m in members[k] for c in (0, 1)])
report('node + ghost blocks', *radius(order, [2 * len(members[k]) for k in real]))
