#!/usr/bin/env python3
"""What bond breaking costs an explicit step: the seed's steel plate (steel_plate_dynamic,
m = 6, Verlet at dt = 2e-7 s, snapshots off, estimate off) at two horizons (about 1e5
and 1e6 bonds per thread on 2 threads), the linear and the bond-stretch law, each
without [peridynamics.fracture], with a critical stretch no bond reaches (s0 = 1: the
bookkeeping alone) and with s0 = 2e-4 (bonds break in the middle); PAIRS rounds,
alternated. Prints the step's seconds (median over the rounds of the stepping time,
energies and snapshots excluded: summary.json's integration.seconds), its ratio to the
same law without fracture, and the integrate stage's (which includes the energy sums
every step) with its ratio.

With BEFORE=<binary>, the runs without fracture are also made with that binary in the
same rounds (alternated), and a second table gives the speed-up of MLSM over BEFORE.

Usage: python3 benches/fracture_step.py   (MLSM: the binary, default target/release/mlsm;
PAIRS: rounds, default 3; BEFORE: an earlier binary, optional)"""
import json, os, statistics, subprocess, sys, tempfile

mlsm = os.environ.get("MLSM", "target/release/mlsm")
before = os.environ.get("BEFORE")
pairs = int(os.environ.get("PAIRS", "3"))
base = open("problems/steel_plate_dynamic.toml").read()
base = base.replace('integrator = "rk4"', 'integrator = "verlet"').replace("snapshots = 20", "snapshots = 0\ntime_step = 2e-7")
base += '\n[estimate]\nmethod = "none"\n'
fracture = {"none": "", "s0 = 1": "\n[peridynamics.fracture]\ncritical_stretch = 1.0\n", "s0 = 2e-4": "\n[peridynamics.fracture]\ncritical_stretch = 2e-4\n"}
laws = ["linear", "bond-stretch"]
work = tempfile.mkdtemp()


def run(binary, law, table, delta, end):
    """(stepping s, integrate s, bonds, broken bonds) of one run."""
    text = base.replace("end_time = 1e-3", f"end_time = {end}").replace("horizon = 0.1", f"horizon = {delta}")
    if law == "bond-stretch":
        text = text.replace('quadrature = "full-area"', 'quadrature = "full-area"\nforce = "bond-stretch"')
    scene = os.path.join(work, "s.toml")
    open(scene, "w").write(text + table)
    out = os.path.join(work, "out")
    r = subprocess.run([binary, "run", scene, "--out", out, "-q"], capture_output=True, text=True)
    if r.returncode:
        sys.exit(r.stderr)
    s = json.load(open(os.path.join(out, "summary.json")))
    return s["integration"]["seconds"], s["timings_s"]["integrate"], s["bonds"], (s.get("fracture") or {}).get("broken_bonds", "-")


print("| delta | bonds | law | fracture | stepping s (median) | ratio | integrate s | ratio | bonds broken |")
print("|---|---|---|---|---|---|---|---|---|")
speedups = []
for delta, end in [(0.075, "2e-4"), (0.0237, "4e-5")]:
    times, info, earlier = {}, {}, {}
    for _ in range(pairs):
        for law in laws:
            for name, table in fracture.items():
                stepping, integrate, bonds, broken = run(mlsm, law, table, delta, end)
                times.setdefault((law, name), []).append((stepping, integrate))
                info[(law, name)] = (bonds, broken)
            if before:
                stepping, integrate, _, _ = run(before, law, "", delta, end)
                earlier.setdefault(law, []).append((stepping, integrate))
    med = lambda k, xs: statistics.median(x[k] for x in xs)
    for law in laws:
        plain, plain_integrate = med(0, times[(law, "none")]), med(1, times[(law, "none")])
        for name in fracture:
            t, t_integrate = med(0, times[(law, name)]), med(1, times[(law, name)])
            bonds, broken = info[(law, name)]
            print(f"| {delta} | {bonds} | {law} | {name} | {t:.3f} | {t / plain:.2f} | {t_integrate:.3f} | {t_integrate / plain_integrate:.2f} | {broken} |", flush=True)
        if before:
            old, old_integrate = med(0, earlier[law]), med(1, earlier[law])
            speedups.append(f"| {delta} | {info[(law, 'none')][0]} | {law} | {old:.3f} / {plain:.3f} | {old / plain:.2f} | {old_integrate:.3f} / {plain_integrate:.3f} | {old_integrate / plain_integrate:.2f} |")
if before:
    print("\n| delta | bonds | law | stepping s: before / after | speed-up | integrate s: before / after | speed-up |")
    print("|---|---|---|---|---|---|---|")
    print("\n".join(speedups))
