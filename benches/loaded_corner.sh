#!/usr/bin/env bash
# Re-entrant corners with loaded edges or a body force, balanced with the loads inside
# their sector (src/models/navier/sector/loads.rs):
# 1. the shipped bracket with a vertical traction SHELF (Pa, default -1e6) on the
#    inner horizontal edge, one of the corner's two edges: the tip deflection against
#    P2 finite elements (`python3 benches/fem_reference.py holes base --shelf -1e6`:
#    -6.2530e-4 m at h = 1 mm, -6.2521e-4 at 2 mm), and the solver `auto` ended with;
# 2. the L with a smooth manufactured field (benches/bracket_variants/L_manufactured.toml,
#    its tractions on both corner edges, its body force): e_inf(u) and e_inf(sigma).
# Usage: [SPACINGS="0.004 ..."] [SEEDS="3 1"] [MLSM=path/to/mlsm] bash benches/loaded_corner.sh
#   (BENCHMARKS.md, "Loaded re-entrant corners")
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
mlsm=${MLSM:-./target/release/mlsm}
out=output/bench_loaded_corner
mkdir -p "$out"
python3 - "${SHELF:--1e6}" "$out/shelf.toml" <<'PY'
import sys
text = open("problems/bracket.toml").read()
edge = 'part = "inner_h"\nkind = "traction"'
assert edge in text, "the bracket's inner_h edge changed"
open(sys.argv[2], "w").write(text.replace(edge, edge + f"\nvalue = [0.0, {sys.argv[1]}]") + '\n[estimate]\nmethod = "none"\n')
PY
echo "| scene | spacing (mm) | seed | nodes | result | solver |"
echo "|---|---|---|---|---|---|"
for scene in shelf L_manufactured; do
  [ "$scene" = shelf ] && source="$out/shelf.toml" || source=benches/bracket_variants/L_manufactured.toml
  for h in ${SPACINGS:-0.004 0.003 0.002 0.0015 0.001}; do
    for seed in ${SEEDS:-3 1}; do
      python3 benches/scene_variant.py "$source" "$out/run.toml" "nodes.seed=$seed"
      "$mlsm" --quiet run "$out/run.toml" --spacing "$h" --out "$out/run" 2> /dev/null || true
      python3 - "$out/run/summary.json" "$scene" "$h" "$seed" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
if s.get("errors"):
    result = f"e_inf(u) {s['errors']['e_inf_u']:.2e}, e_inf(sigma) {s['errors']['e_inf_sigma']:.2e}"
else:
    tip = next(p["value"] for p in s["probes"] if p["name"] == "tip_deflection")
    result = f"tip {tip:.4e} m ({100 * (tip / -6.2530e-4 - 1):+.1f} %)"
method = s["solver"]["method"].split(" ")[0]
print(f"| {sys.argv[2]} | {1e3 * float(sys.argv[3]):g} | {sys.argv[4]} | {s['nodes']} | {result} | {method}, {s['solver']['iterations']} it |")
PY
    done
  done
done
