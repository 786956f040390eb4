"""Section forces of the bracket's column and arm from a run's solution.vtu: the
check behind the README's analysis of re-entrant corners (Known limits) and
`src/models/navier/sector/`.

Statics fixes them: a tip load F (5 MPa over the 0.06 m tip) gives in the column
(0 <= x <= 0.06) an axial force N = -F, no shear (V = 0) and a moment of magnitude
F * 0.17 (M/M_statics = -1 with the moment taken as the integral of sigma_yy (x - 0.03)),
and in the arm at x a shear V = -F and a moment F (0.2 - x) (M/M_statics = +1). A discrete solution that violates them carries a spurious load between
the sections. Stresses within 3 mm of a section are fitted by a quadratic across and
linear along it, then integrated across.

    mlsm --quiet run problems/bracket.toml --spacing 0.002 --out /tmp/b
    python3 benches/section_forces.py /tmp/b/solution.vtu
"""
import base64
import re
import struct
import sys

import numpy as np

F = 5e6 * 0.06


def read_vtu(path):
    """Point coordinates and point fields of a vtkio VTU with inline binary arrays."""
    text = open(path, 'rb').read().decode('latin1')
    fields = {}
    pattern = r'<DataArray type="(\w+)" Name="([^"]+)"(?: NumberOfComponents="(\d+)")?[^>]*format="binary"[^>]*>([^<]*)</DataArray>'
    kinds = {'Float64': '<f8', 'Float32': '<f4', 'Int32': '<i4', 'Int64': '<i8', 'UInt8': 'u1', 'UInt64': '<u8', 'Int8': 'i1', 'UInt32': '<u4'}
    for m in re.finditer(pattern, text):
        raw = base64.b64decode(m.group(4).strip())
        size = struct.unpack('<Q', raw[:8])[0]
        values = np.frombuffer(raw[8:8 + size], dtype=kinds[m.group(1)])
        components = int(m.group(3) or 1)
        fields[m.group(2)] = values.reshape(-1, components) if components > 1 else values
    return fields


def resultants(p, normal_stress, shear_stress, across, along, at, centre, width=0.06, band=0.003, within=None):
    """(N, V, M) through the section `along = at`, integrated over `across` in
    [centre - width/2, centre + width/2]."""
    m = np.abs(p[:, along] - at) < band
    if within is not None:
        m &= within
    t, s = p[m, across] - centre, p[m, along] - at
    basis = np.column_stack([np.ones(m.sum()), t, t ** 2, s, t * s])
    cn = np.linalg.lstsq(basis, normal_stress[m], rcond=None)[0]
    cs = np.linalg.lstsq(basis, shear_stress[m], rcond=None)[0]
    w3 = width ** 3 / 12
    return cn[0] * width + cn[2] * w3, cs[0] * width + cs[2] * w3, cn[1] * w3


def main(path):
    d = read_vtu(path)
    p = d['Points'][:, :2]
    sxx, syy, sxy = d['sigma_xx'], d['sigma_yy'], d['sigma_xy']
    print('section            N/F     V/F     M/M_statics')
    for y in (0.02, 0.05, 0.08, 0.11):
        n, v, mo = resultants(p, syy, sxy, 0, 1, y, 0.03, within=p[:, 0] <= 0.06)
        print(f'column y = {y:.2f}  {n / F:+.3f}  {v / F:+.3f}  {mo / (F * 0.17):+.3f}')
    for x in (0.09, 0.12, 0.15, 0.18):
        n, v, mo = resultants(p, sxx, sxy, 1, 0, x, 0.17, within=p[:, 1] >= 0.14)
        print(f'arm x = {x:.2f}     {n / F:+.3f}  {v / F:+.3f}  {mo / (F * (0.2 - x)):+.3f}')


if __name__ == '__main__':
    main(sys.argv[1])
