#!/usr/bin/env bash
# The bracket's tip deflection and estimate over spacings and node seeds: how steadily
# a run converges at a re-entrant corner. For each spacing in SPACINGS and seed in
# SEEDS (3 is the shipped node set), the tip's error against finite elements
# (-4.975e-4 m, benches/fem_reference.py), the estimated e_inf(u), and the solver
# `auto` ended with.
# Usage: [SPACINGS="0.005 0.004 ..."] [SEEDS="3 1"] bash benches/bracket_spacings.sh
#   (BENCHMARKS.md, "Ghosts at balanced corners for least squares")
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
out=output/bench_bracket_spacings
mkdir -p "$out"
echo "| spacing (mm) | seed | nodes | tip error | estimated e_inf(u) | solver |"
echo "|---|---|---|---|---|---|"
for h in ${SPACINGS:-0.005 0.004 0.0035 0.003 0.0025 0.002 0.0015 0.001}; do
  for seed in ${SEEDS:-3 1}; do
    python3 benches/scene_variant.py problems/bracket.toml "$out/seed$seed.toml" "nodes.seed=$seed"
    ./target/release/mlsm --quiet run "$out/seed$seed.toml" --spacing "$h" --out "$out/run" 2> /dev/null || true
    python3 - "$out/run/summary.json" "$h" "$seed" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
tip = next(p["value"] for p in s["probes"] if p["name"] == "tip_deflection")
method = s["solver"]["method"].split(" ")[0]
print(f"| {1e3 * float(sys.argv[2]):g} | {sys.argv[3]} | {s['nodes']} | {100 * (tip / -4.975e-4 - 1):+.1f} % | {s['estimated_errors']['e_inf_u']:.2e} | {method}, {s['solver']['iterations']} it |")
PY
  done
done
