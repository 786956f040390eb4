#!/usr/bin/env bash
# `--target-error 1e-2` (e_inf(u)) on the bracket from its shipped 2 mm spacing, local
# against uniform refinement, on four scattered node sets (nodes.seed 1-4; 3 is the
# shipped one), each result checked against finite elements (benches/fem_errors.py,
# needs `pip install scikit-fem gmsh numpy`).
# Usage: [SEEDS="1 2 3 4"] [MODES="local uniform"] [BUDGET=4m] bash benches/bracket_target.sh
#   (README, "Refining to an error target"; BENCHMARKS.md, "The bracket to an error target")
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
out=output/bench_bracket_target
mkdir -p "$out"
for seed in ${SEEDS:-1 2 3 4}; do
  python3 benches/scene_variant.py problems/bracket.toml "$out/seed$seed.toml" "nodes.seed=$seed"
  for mode in ${MODES:-local uniform}; do
    run="$out/seed$seed-$mode"
    ./target/release/mlsm --quiet run "$out/seed$seed.toml" --target-error 1e-2 --refinement "$mode" \
      --budget "${BUDGET:-4m}" --out "$run" 2> /dev/null || true
    python3 - "$run/summary.json" "$seed" "$mode" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); t = s["target"]
steps = ", ".join(f"{x['nodes']} ({x['estimate']:.2e})" for x in t["steps"])
secs = sum(x["seconds"] for x in t["steps"])
print(f"seed {sys.argv[2]}, {sys.argv[3]}: {t['stop']}, step written {t['best_step']}, {secs:.1f} s of steps; nodes (estimate): {steps}")
PY
    python3 benches/fem_errors.py "$run/solution.vtu"
  done
done
