"""Time to accuracy: mlsm against scikit-fem P1/P2/P3 on Kirsch and Lame, side by side.

Run by benches/time_to_accuracy.sh (which installs the pinned Python packages and
builds mlsm); not part of CI. For each scene every configuration is swept from coarse
to fine, the configurations taking turns (one run of each in a round, so a change in
the machine's load touches all of them alike):

- mlsm, the shipped scene with PHS r^3 + degree 4 and + degree 6, each as users run it
  (the error estimate on, the default) and with `estimate.method = "none"`; the
  spacing (`--spacing`, which scales a graded spacing as a whole) from twice the
  scene's down by 2^(1/4) a step;
- mlsm `--preset fast|balanced|accurate` (one run each) and `--target-error E` at every
  target below (one run each, on the target's own norm);
- scikit-fem (benches/fem_plates.py): P1, P2, P3 with a direct solve (SuperLU) and
  P2, P3 with CG + smoothed-aggregation AMG (pyamg) on graded polar meshes (a mapped
  mesh, which these two plates allow and a general plate does not), and P2, P3 with the
  direct solve on unstructured gmsh meshes of the same grading; the element count over
  the quarter turn up by 2^(1/4) a step.

A sweep stops once both of its errors are below the smallest targets, or a run takes
longer than --cap seconds in program. For each target the table gives, per side, the
cheapest run that reached it: its in-program time (mlsm: summary.json's total;
scikit-fem: mesh, assembly, solve, nodal stresses) and its whole-process time (process
start to exit, Python's imports and our output files included).

    bash benches/time_to_accuracy.sh [--scenes lame,kirsch] [--cap 30] [--repeat 1]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time
import tomllib

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
MLSM = os.path.join(ROOT, "target", "release", "mlsm")
OUT = os.path.join(ROOT, "output", "time_to_accuracy")
TARGETS = {"e_inf_u": [1e-4, 1e-5, 1e-6, 1e-7], "e_inf_sigma": [1e-3, 1e-4, 1e-5, 1e-6]}
STEP = 2 ** 0.25
# scikit-fem configurations: (order, solver, mesh)
FEM = [(1, "direct", "polar"), (2, "direct", "polar"), (3, "direct", "polar"), (2, "amg", "polar"), (3, "amg", "polar")]
FEM += [(2, "direct", "unstructured"), (3, "direct", "unstructured")]


def timed(command):
    """(stdout, whole-process seconds); raises with the command's stderr on failure."""
    clock = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, cwd=ROOT, timeout=3600)
    seconds = time.perf_counter() - clock
    if done.returncode not in (0, 4):
        raise RuntimeError(f"{' '.join(command)} exited {done.returncode}: {done.stderr.strip()[-400:]}")
    return done.stdout, seconds


class Sweep:
    """One configuration's runs, coarse to fine; `next()` gives the next job or None."""

    def __init__(self, side, name, jobs):
        self.side, self.name, self.jobs, self.done = side, name, iter(jobs), False

    def next(self):
        return None if self.done else next(self.jobs, None)


def variant(scene, name, edits):
    """A scene file with `edits` (benches/scene_variant.py's key=value)."""
    path = os.path.join(OUT, "scenes", f"{scene}_{name}.toml")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    subprocess.run([sys.executable, "benches/scene_variant.py", f"problems/{scene}.toml", path, *edits], cwd=ROOT, check=True, capture_output=True)
    return path


def mlsm_job(scene, label, path, args):
    def run():
        folder = os.path.join(OUT, "runs", f"{scene}_{label}")
        _, seconds = timed([MLSM, "--quiet", "run", path, "--out", folder, *args])
        s = json.load(open(os.path.join(folder, "summary.json")))
        row = {"nodes": s["nodes"], "seconds": s["timings_s"]["total"], "process_s": seconds}
        row.update({k: s["errors"][k] for k in TARGETS})
        if s.get("target"):
            row["target_reached"] = s["target"]["reached"]
        return row

    return label, run


def fem_job(scene, order, solver, mesh, n):
    def run():
        command = ["benches/fem_plates.py", scene, "--order", str(order), "--solver", solver, "--mesh", mesh, "--n", str(n)]
        out, seconds = timed([sys.executable, *command])
        r = json.loads(out)
        row = {"nodes": r["nodes"], "seconds": r["seconds"], "process_s": seconds, "converged": r["converged"]}
        row.update({k: r[k] for k in TARGETS})
        return row

    return f"P{order} {solver} {mesh} n={n}", run


def sweeps(scene, cap):
    spec = tomllib.load(open(os.path.join(ROOT, "problems", f"{scene}.toml"), "rb"))
    h0 = float(spec["nodes"]["spacing"])
    out = []
    for degree in (4, 6):
        for estimate in ("default", "none"):
            edits = ['basis="phs"', f"degree={degree}"] + (['estimate.method="none"'] if estimate == "none" else [])
            name = f"phs{degree}_{estimate}"
            path = variant(scene, name, edits)
            spacings = [h0 * 2 / STEP**k for k in range(40)]
            jobs = [mlsm_job(scene, f"{name}_h{h:.4g}", path, ["--spacing", repr(h)]) for h in spacings]
            out.append(Sweep("mlsm" if estimate == "default" else "mlsm, estimate off", f"PHS degree {degree}", jobs))
    shipped = os.path.join("problems", f"{scene}.toml")
    for preset in ("fast", "balanced", "accurate"):
        out.append(Sweep("mlsm", f"preset {preset}", [mlsm_job(scene, f"preset_{preset}", shipped, ["--preset", preset])]))
    for norm, targets in TARGETS.items():
        for t in targets:
            job = mlsm_job(scene, f"target_{norm}_{t:g}", shipped, ["--target-error", f"{t:g}", "--target-norm", norm, "--budget", f"{10 * cap:g}s"])
            out.append(Sweep(f"target {norm} {t:g}", "--target-error", [job]))
    counts = sorted({2 * math.ceil(2 * STEP**k) for k in range(60)})
    for order, solver, mesh in FEM:
        name = f"P{order} {solver}" + ("" if mesh == "polar" else f", {mesh}")
        side = "scikit-fem" if mesh == "polar" else "scikit-fem, unstructured"
        out.append(Sweep(side, name, [fem_job(scene, order, solver, mesh, n) for n in counts]))
    return out


def finished(row, cap):
    small = all(row[k] <= min(v) for k, v in TARGETS.items())
    return small or row["seconds"] > cap


def measure(scene, cap, repeat, log):
    """Every sweep of `scene` in rounds; returns the rows (min times over repeats)."""
    rows = {}
    for rep in range(repeat):
        active = sweeps(scene, cap)
        while active:
            for sweep in list(active):
                job = sweep.next()
                if job is None:
                    active.remove(sweep)
                    continue
                label, run = job
                key = (sweep.side, sweep.name, label)
                try:
                    row = run()
                except (RuntimeError, subprocess.TimeoutExpired) as failure:
                    print(f"  {scene} {sweep.side} {label}: failed ({failure})", file=sys.stderr)
                    sweep.done = True
                    continue
                row.update(scene=scene, side=sweep.side, config=sweep.name, run=label, repeat=rep)
                log.write(json.dumps(row) + "\n")
                log.flush()
                print(f"  {scene} {sweep.side:18} {label:34} {row['nodes']:>8} nodes {row['seconds']:8.3f} s  u {row['e_inf_u']:.2e}  sigma {row['e_inf_sigma']:.2e}", file=sys.stderr)
                if key in rows:
                    for k in ("seconds", "process_s"):
                        rows[key][k] = min(rows[key][k], row[k])
                else:
                    rows[key] = row
                if finished(row, cap) or row.get("converged") is False:
                    sweep.done = True
    return list(rows.values())


def cheapest(rows, side, norm, target):
    ok = [r for r in rows if r["side"] == side and r[norm] <= target and r.get("converged", True)]
    return min(ok, key=lambda r: r["seconds"]) if ok else None


def cell(r):
    return f"{r['seconds']:.3g} / {r['process_s']:.3g} ({r['config']}, {r['nodes']})" if r else "not within the cap"


def ratio(a, b):
    return f"{a['seconds'] / b['seconds']:.2g}" if a and b else "-"


def table(scene, rows):
    lines = [
        f"**{scene}**: seconds in program / whole process (configuration, nodes); ratio = mlsm / scikit-fem (polar mesh, or unstructured where said) in program",
        "",
        "| target | mlsm, default run | mlsm, estimate off | `--target-error` | scikit-fem, polar mesh | scikit-fem, unstructured | ratio default | ratio off | ratio target | ratio default, unstructured |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for norm, targets in TARGETS.items():
        for t in targets:
            sides = ("mlsm", "mlsm, estimate off", "scikit-fem", "scikit-fem, unstructured")
            ours, off, fem, general = (cheapest(rows, s, norm, t) for s in sides)
            tr = next((r for r in rows if r["side"] == f"target {norm} {t:g}"), None)
            target = f"{tr['seconds']:.3g} / {tr['process_s']:.3g} ({tr['nodes']}, true {tr[norm]:.1e})" if tr else "failed"
            ok = tr if tr and tr[norm] <= t else None
            cells = [cell(ours), cell(off), target, cell(fem), cell(general), ratio(ours, fem), ratio(off, fem), ratio(ok, fem), ratio(ours, general)]
            lines.append(f"| {norm} {t:g} | " + " | ".join(cells) + " |")
    lines += ["", f"**{scene}**, scikit-fem per configuration: seconds in program (nodes) of the cheapest run reaching each target", ""]
    configs = sorted({r["config"] for r in rows if r["side"].startswith("scikit-fem")})
    lines += ["| target | " + " | ".join(configs) + " |", "|---|" + "---|" * len(configs)]
    for norm, targets in TARGETS.items():
        for t in targets:
            cells = []
            for c in configs:
                same = [r for r in rows if r["config"] == c]
                r = cheapest(same, same[0]["side"], norm, t)
                cells.append(f"{r['seconds']:.3g} ({r['nodes']})" if r else "-")
            lines.append(f"| {norm} {t:g} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", default="lame,kirsch")
    parser.add_argument("--cap", type=float, default=30.0, help="stop a sweep after a run longer than this (s, in program)")
    parser.add_argument("--repeat", type=int, default=1, help="passes over every run; the smallest times are kept")
    args = parser.parse_args()
    os.makedirs(OUT, exist_ok=True)
    tables = []
    with open(os.path.join(OUT, "runs.jsonl"), "w") as log:
        for scene in args.scenes.split(","):
            rows = measure(scene, args.cap, args.repeat, log)
            tables.append(table(scene, rows))
    text = "\n\n".join(tables)
    open(os.path.join(OUT, "table.md"), "w").write(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
