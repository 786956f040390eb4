#!/usr/bin/env bash
# Behaviour check for refactorings: run every shipped scene (both models where the
# scene has a [peridynamics] table), one comparison and one convergence study with a
# given binary, then compare two such result folders:
#   * every .vtu must be byte-identical;
#   * every number in summary.json / compare.json / convergence.json / *.csv must be
#     equal, apart from timings, peak memory and throughput (keys named in IGNORED)
#     and the available memory that `auto`'s reason quotes;
#     energies (ROUNDOFF) are sums reduced by rayon in an order that varies from run
#     to run, so they are compared to 1e-12 relative (two runs of one binary differ
#     in the last digit there).
# New keys in the second folder are allowed (listed), missing or changed ones are not.
#
# Usage:
#   bash benches/behaviour.sh record DIR [BINARY]   # default BINARY: target/release/mlsm
#   bash benches/behaviour.sh check  BEFORE AFTER
# Typical use: record with the binary of the old commit, record with the new one,
# then check; the exit code is 0 only when nothing changed.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:?record or check}
if [ "$mode" = record ]; then
  dir=${2:?output folder}
  bin=${3:-target/release/mlsm}
  rm -rf "$dir" && mkdir -p "$dir"
  for scene in problems/*.toml; do
    name=$(basename "$scene" .toml)
    "$bin" --quiet run "$scene" --out "$dir/$name"
    if grep -q '^\[peridynamics\]' "$scene" && ! grep -q '^model = "peridynamics"' "$scene"; then
      "$bin" --quiet run "$scene" --model peridynamics --out "$dir/${name}_pd"
    fi
    if grep -q '^model = "peridynamics"' "$scene"; then
      "$bin" --quiet run "$scene" --model navier --out "$dir/${name}_navier"
    fi
  done
  # The iterative solver with each preconditioner (the shipped scenes use LU).
  for pc in ilut ilu0 jacobi; do
    mkdir -p output/behaviour_scenes
    scene="output/behaviour_scenes/kirsch_bicgstab_$pc.toml"
    { cat problems/kirsch.toml; printf '\n[solver]\nkind = "bicgstab"\npreconditioner = "%s"\nmax_iterations = 20000\n' "$pc"; } > "$scene"
    "$bin" --quiet run "$scene" --spacing 0.1 --out "$dir/kirsch_bicgstab_$pc" || echo "kirsch with $pc: exit $?" > "$dir/kirsch_bicgstab_$pc.failed"
  done
  "$bin" --quiet compare problems/pd_manufactured.toml --levels 1 --quadratures ac,full-area --out "$dir/compare_pd_manufactured"
  "$bin" --quiet compare problems/steel_plate.toml --levels 1 --reference-spacing 0.02 --out "$dir/compare_steel_plate"
  "$bin" --quiet convergence problems/manufactured_traction.toml --levels 1 --out "$dir/convergence_manufactured_traction"
  echo "recorded: $dir"
  exit 0
fi
[ "$mode" = check ] || { echo "usage: behaviour.sh record DIR [BINARY] | check BEFORE AFTER" >&2; exit 2; }
python3 - "${2:?before}" "${3:?after}" <<'PY'
import csv, json, os, re, sys

before, after = sys.argv[1], sys.argv[2]
IGNORED = ("timings", "seconds", "peak_memory", "per_second", "total_seconds", "version")
ROUNDOFF = ("energ", "kinetic", "elastic", "external", "total")

AVAILABLE = re.compile(r"of the [0-9.]+ GB available")

def same(path, a, b):
    if a == b:
        return True
    # `auto`'s reason quotes the memory available at the time of the run.
    if isinstance(a, str) and isinstance(b, str) and AVAILABLE.sub("", a) == AVAILABLE.sub("", b):
        return True
    if any(k in path for k in ROUNDOFF):
        try:
            a, b = float(a), float(b)
            return abs(a - b) <= 1e-12 * max(abs(a), abs(b))
        except (TypeError, ValueError):
            return False
    return False

def ignored(path):
    return any(k in path for k in IGNORED)

def leaves(x, path=""):
    if isinstance(x, dict):
        for k, v in x.items():
            yield from leaves(v, f"{path}.{k}")
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield from leaves(v, f"{path}[{i}]")
    else:
        yield path, x

def csv_leaves(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    head = rows[0]
    for r, row in enumerate(rows[1:]):
        for k, v in zip(head, row):
            yield f"[{r}].{k}", v

problems, checked, added = [], 0, set()
for root, _, files in os.walk(before):
    for f in sorted(files):
        a = os.path.join(root, f)
        b = os.path.join(after, os.path.relpath(a, before))
        rel = os.path.relpath(a, before)
        if not os.path.exists(b):
            problems.append(f"{rel}: missing in {after}")
            continue
        if f.endswith(".vtu") or f.endswith(".pvd"):
            if open(a, "rb").read() != open(b, "rb").read():
                problems.append(f"{rel}: files differ")
            checked += 1
        elif f.endswith(".json") or f.endswith(".csv"):
            la = dict(leaves(json.load(open(a))) if f.endswith(".json") else csv_leaves(a))
            lb = dict(leaves(json.load(open(b))) if f.endswith(".json") else csv_leaves(b))
            for k, v in la.items():
                if ignored(k):
                    continue
                if k not in lb:
                    problems.append(f"{rel}: {k} missing")
                elif not same(k, v, lb[k]):
                    problems.append(f"{rel}: {k}: {v!r} -> {lb[k]!r}")
            added.update(f"{rel}: {k}" for k in lb if k not in la)
            checked += 1
print(f"compared {checked} files")
for k in sorted(added):
    print(f"  new key {k}")
for p in problems:
    print(f"DIFF {p}")
sys.exit(1 if problems else 0)
PY
