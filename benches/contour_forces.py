"""Resultant force and moment of the tractions on circles around the bracket's holes,
from a run's solution.vtu: the check behind the holes' ring balances
(`src/models/navier/sector/`, BENCHMARKS.md "Balanced holes").

A traction-free hole carries no resultant: the integral of sigma n over any circle
that encloses the hole and nothing else is zero, and so is its moment. A discrete
solution that puts a load on the hole shows it here. At each of 400 midpoints on the
circle the stress is fitted by degree-2 least squares over the 12 nearest nodes, and
the traction sigma n integrated by the midpoint rule. Printed in units of the tip
load F (5 MPa over the 0.06 m tip) and, for the moment about the circle's centre, of
F x 0.1 m.

    mlsm --quiet run problems/bracket.toml --spacing 0.002 --out /tmp/b
    python3 benches/contour_forces.py /tmp/b/solution.vtu
    python3 benches/contour_forces.py /tmp/b/solution.vtu 0.03 0.05 0.014 0.02   # centre, radii
"""
import sys

import numpy as np

from section_forces import F, read_vtu

# The bracket's holes: centre and radii of the circles tried (beyond the hole's radius,
# inside the solid, no other boundary within).
HOLES = [('hole1', (0.03, 0.05), [0.014, 0.016, 0.02, 0.025]), ('hole2', (0.14, 0.17), [0.012, 0.014, 0.016, 0.019])]
POINTS, FIT = 400, 12


def resultant(points, stress, centre, radius):
    """(force x, force y, moment) of the tractions on the circle, by the midpoint rule."""
    force, moment = np.zeros(2), 0.0
    ds = radius * 2 * np.pi / POINTS
    for t in (np.arange(POINTS) + 0.5) * 2 * np.pi / POINTS:
        normal = np.array([np.cos(t), np.sin(t)])
        q = np.asarray(centre) + radius * normal
        near = np.argsort(np.hypot(*(points - q).T))[:FIT]
        x = points[near] - q
        basis = np.stack([np.ones(FIT), x[:, 0], x[:, 1], x[:, 0] ** 2, x[:, 0] * x[:, 1], x[:, 1] ** 2], 1)
        sxx, syy, sxy = np.linalg.lstsq(basis, stress[near], rcond=None)[0][0]
        traction = np.array([sxx * normal[0] + sxy * normal[1], sxy * normal[0] + syy * normal[1]])
        force += traction * ds
        arm = radius * normal
        moment += (arm[0] * traction[1] - arm[1] * traction[0]) * ds
    return force[0], force[1], moment


def main():
    fields = read_vtu(sys.argv[1])
    points = fields['Points'][:, :2]
    stress = np.stack([fields['sigma_xx'], fields['sigma_yy'], fields['sigma_xy']], 1)
    holes = HOLES
    if len(sys.argv) > 4:
        holes = [('circle', (float(sys.argv[2]), float(sys.argv[3])), [float(r) for r in sys.argv[4:]])]
    print('contour  radius   Fx/F     Fy/F     M/(F 0.1 m)')
    for name, centre, radii in holes:
        for r in radii:
            fx, fy, m = resultant(points, stress, centre, r)
            print(f'{name:8} {r:.4f}  {fx / F:+.3f}   {fy / F:+.3f}   {m / (F * 0.1):+.3f}')


if __name__ == '__main__':
    main()
