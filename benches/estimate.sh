#!/usr/bin/env bash
# Cost and effectivity of the error estimate on the shipped static scenes: one
# `mlsm run` each; seconds of the run without the estimate, of the estimate
# (timings_s.estimate), estimated and true e_inf(u), e_inf(sigma) from summary.json.
# Usage: bash benches/estimate.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
echo "| scene | nodes | run s | estimate s | reference | e_inf(u) | est. | e_inf(sigma) | est. |"
echo "|---|---|---|---|---|---|---|---|---|"
for scene in cantilever manufactured_dirichlet manufactured_traction lame kirsch flamant steel_plate bracket; do
  out="output/bench_estimate_$scene"
  ./target/release/mlsm --quiet run "problems/$scene.toml" --out "$out" 2> /dev/null
  python3 - "$out/summary.json" "$scene" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); t = s["timings_s"]; e = s.get("errors") or {}; x = s["estimated_errors"]
f = lambda v: "-" if v is None else f"{v:.2e}"
run = t["total"] - t["estimate"] - t.get("output", 0)
print(f"| {sys.argv[2]} | {s['nodes']} | {run:.2f} | {t['estimate']:.2f} | degree {x['reference_degree']} | {f(e.get('e_inf_u'))} | {f(x['e_inf_u'])} | {f(e.get('e_inf_sigma'))} | {f(x['e_inf_sigma'])} |")
PY
done
