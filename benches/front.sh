#!/usr/bin/env bash
# Time against accuracy per shipped scene with an exact solution: a sweep over the
# basis (least-squares monomials of degree 2 with the default support, RBF-FD PHS r^3
# with degree 2, 4, 6, and the scene's own [approximation]) and three spacings
# (`--spacing`, which scales a graded spacing function as a whole). Each run is one
# `mlsm run`; seconds are its total wall time (summary.json), memory its peak.
# Prints one Markdown table per scene; rows on the Pareto front of (seconds,
# e_inf(sigma)) are marked `*`, the scene's shipped setting `(shipped)`.
# Usage: bash benches/front.sh [SCENE ...]   (default: all five)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(cantilever manufactured_traction lame kirsch flamant)
declare -A spacings=(
  [cantilever]="0.25 0.125 0.0625"
  [manufactured_traction]="0.05 0.025 0.0125"
  [lame]="5e-4 2.5e-4 1.25e-4"
  [kirsch]="0.08 0.04 0.02"
  [flamant]="0.06 0.03 0.015"
)
tmp=output/bench_front
mkdir -p "$tmp"
csv="$tmp/front.csv"
echo "scene,basis,spacing,nodes,seconds,peak_mb,e_inf_u,e_inf_sigma" > "$csv"
for scene in "${scenes[@]}"; do
  for basis in "shipped" "monomials 2" "phs 2" "phs 4" "phs 6"; do
    set -- $basis
    scene_file="$tmp/${scene}_${1}_${2:-}.toml"
    if [ "$1" = shipped ]; then
      cp "problems/$scene.toml" "$scene_file"
    else
      python3 benches/scene_variant.py "problems/$scene.toml" "$scene_file" "basis=\"$1\"" "degree=$2" "estimate.method=\"none\""
    fi
    for h in ${spacings[$scene]}; do
      out="$tmp/${scene}_${1}_${2:-}_$h"
      if ! timeout 300 ./target/release/mlsm --quiet run "$scene_file" --spacing "$h" --out "$out" 2> "$out.err"; then
        echo "$scene,$basis,$h,failed,,,," >> "$csv"
        continue
      fi
      python3 - "$out/summary.json" "$scene" "$basis" "$h" >> "$csv" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
e = s["errors"]
print(f"{sys.argv[2]},{sys.argv[3]},{sys.argv[4]},{s['nodes']},{s['timings_s']['total']:.3f},{s['peak_memory_bytes'] / 2**20:.0f},{e['e_inf_u']:.3e},{e['e_inf_sigma']:.3e}")
PY
    done
  done
done
python3 - "$csv" <<'PY'
import csv, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r["nodes"] != "failed"]
failed = [r for r in csv.DictReader(open(sys.argv[1])) if r["nodes"] == "failed"]
for scene in dict.fromkeys(r["scene"] for r in rows):
    rs = sorted((r for r in rows if r["scene"] == scene), key=lambda r: float(r["seconds"]))
    best = float("inf")
    print(f"\n{scene}\n\n| basis | spacing | nodes | seconds | peak MB | e_inf(u) | e_inf(sigma) | front |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rs:
        es = float(r["e_inf_sigma"])
        front = es < best
        best = min(best, es)
        name = "(shipped)" if r["basis"] == "shipped" else r["basis"]
        print(f"| {name} | {r['spacing']} | {r['nodes']} | {float(r['seconds']):.2f} | {r['peak_mb']} | {r['e_inf_u']} | {r['e_inf_sigma']} | {'*' if front else ''} |")
for r in failed:
    print(f"failed: {r['scene']} {r['basis']} at {r['spacing']}")
PY
