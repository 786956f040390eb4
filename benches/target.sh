#!/usr/bin/env bash
# `mlsm run --target-error`: local against uniform refinement, and both against the
# cheapest uniform scaling of the scene's spacing that reaches the target.
# For each scene and target: the history of --refinement local and uniform (nodes,
# estimate, true error per step; stop), and the "ladder" minimum: the spacing
# function scaled by 2^(-k/4), k = 0, 1, ..., the first level whose estimate is at or
# below the target (what a user who knew the answer would run).
# Usage: bash benches/target.sh [SCENE:START_SPACING:NORM ...]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
cases=("$@")
if [ ${#cases[@]} -eq 0 ]; then
  cases=(kirsch:0.16:e_inf_u kirsch:0.16:e_inf_sigma lame:1e-3:e_inf_u manufactured_traction:0.1:e_inf_u)
fi
mlsm=./target/release/mlsm
for case in "${cases[@]}"; do
  IFS=: read -r scene start norm <<< "$case"
  for target in 1e-3 1e-4 1e-5; do
    for mode in local uniform; do
      out="output/bench_target/$scene-$norm-$target-$mode"
      $mlsm --quiet run "problems/$scene.toml" --spacing "$start" --target-error "$target" --target-norm "$norm" \
        --refinement "$mode" --out "$out" 2> /dev/null || true
      python3 - "$out/summary.json" "$scene" "$norm" "$target" "$mode" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); t = s["target"]
f = lambda v: "-" if v is None else f"{v:.2e}"
steps = ", ".join(f"{x['nodes']} ({f(x['estimate'])}/{f(x['error'])})" for x in t["steps"])
secs = sum(x["seconds"] for x in t["steps"])
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {sys.argv[5]} | {t['steps'][-1]['nodes'] if t['reached'] else '-'} | {secs:.1f} | {t['stop']} | {steps} |")
PY
    done
    # The ladder: the first uniform scaling that reaches the target.
    for k in $(seq 0 16); do
      h=$(python3 -c "print(f'{$start * 2 ** (-$k / 4):.4g}')")
      out="output/bench_target/$scene-ladder"
      $mlsm --quiet run "problems/$scene.toml" --spacing "$h" --out "$out" 2> /dev/null || true
      hit=$(python3 - "$out/summary.json" "$norm" "$target" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); e = s["estimated_errors"][sys.argv[2]]
print(f"{s['nodes']} {e:.2e} {(s.get('errors') or {}).get(sys.argv[2], float('nan')):.2e} {s['timings_s']['total']:.1f}" if e <= float(sys.argv[3]) else "")
PY
)
      if [ -n "$hit" ]; then
        read -r nodes est err secs <<< "$hit"
        echo "| $scene | $norm | $target | ladder (h = $h) | $nodes | $secs | reached | $nodes ($est/$err) |"
        break
      fi
    done
  done
done
