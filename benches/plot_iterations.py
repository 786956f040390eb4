"""Iterations against nodes on log-linear axes as an SVG, from `nodes:iterations` pairs.

Usage: python3 benches/plot_iterations.py OUT.svg "TITLE" [LABEL] N:IT N:IT ... [LABEL N:IT ...]
An argument without a colon starts a new series with that label (shown in a legend);
the numbers are the measured ones listed in BENCHMARKS.md (GMRES + AMG sections).
"""
import math
import sys

out, title = sys.argv[1], sys.argv[2]
series = []
for arg in sys.argv[3:]:
    if ':' in arg:
        if not series:
            series.append(('', []))
        series[-1][1].append(tuple(map(float, arg.split(':'))))
    else:
        series.append((arg, []))
pairs = [p for _, s in series for p in s]
W, H, L, R, T, B = 640, 400, 70, 20, 40, 60
lo, hi = math.floor(math.log10(min(n for n, _ in pairs))), math.ceil(math.log10(max(n for n, _ in pairs)))
ymax = max(10.0, math.ceil(max(i for _, i in pairs) / 10.0) * 10.0 + 10.0)
x = lambda n: L + (math.log10(n) - lo) / (hi - lo) * (W - L - R)
y = lambda i: H - B - i / ymax * (H - T - B)
svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<text x="{W / 2}" y="22" text-anchor="middle" font-size="14">{title}</text>',
       f'<line x1="{L}" y1="{H - B}" x2="{W - R}" y2="{H - B}" stroke="black"/>',
       f'<line x1="{L}" y1="{T}" x2="{L}" y2="{H - B}" stroke="black"/>']
for e in range(lo, hi + 1):
    svg.append(f'<line x1="{x(10 ** e)}" y1="{T}" x2="{x(10 ** e)}" y2="{H - B}" stroke="#ddd"/>')
    svg.append(f'<text x="{x(10 ** e)}" y="{H - B + 18}" text-anchor="middle">1e{e}</text>')
for k in range(0, int(ymax) + 1, 10):
    svg.append(f'<line x1="{L}" y1="{y(k)}" x2="{W - R}" y2="{y(k)}" stroke="#eee"/>')
    svg.append(f'<text x="{L - 8}" y="{y(k) + 4}" text-anchor="end">{k}</text>')
svg.append(f'<text x="{(L + W - R) / 2}" y="{H - 15}" text-anchor="middle">nodes</text>')
svg.append(f'<text x="18" y="{(T + H - B) / 2}" text-anchor="middle" transform="rotate(-90 18 {(T + H - B) / 2})">iterations to 1e-10</text>')
colours = ['#1f77b4', '#d62728', '#2ca02c', '#9467bd', '#ff7f0e']
for k, (label, pts) in enumerate(series):
    c, pts = colours[k % len(colours)], sorted(pts)
    svg.append(f'<polyline fill="none" stroke="{c}" stroke-width="2" points="' + ' '.join(f'{x(n):.1f},{y(i):.1f}' for n, i in pts) + '"/>')
    for n, i in pts:
        svg.append(f'<circle cx="{x(n):.1f}" cy="{y(i):.1f}" r="4" fill="{c}"/>')
        svg.append(f'<text x="{x(n):.1f}" y="{y(i) - 9:.1f}" text-anchor="middle" font-size="11" fill="{c}">{int(i)}</text>')
    if label:
        svg.append(f'<line x1="{L + 12}" y1="{T + 14 + 18 * k}" x2="{L + 36}" y2="{T + 14 + 18 * k}" stroke="{c}" stroke-width="2"/>')
        svg.append(f'<text x="{L + 42}" y="{T + 18 + 18 * k}">{label}</text>')
svg.append('</svg>')
open(out, 'w').write('\n'.join(svg) + '\n')
