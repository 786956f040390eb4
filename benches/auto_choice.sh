#!/usr/bin/env bash
# `auto`'s choice between sparse LU and GMRES + AMG: each system solved by `lu`, by
# `gmres` (AMG) and by `auto`, with the estimated LU factor bytes (`34 N^0.26` per
# nonzero) that `auto` decides by. Error estimate off; one run each.
# Usage: bash benches/auto_choice.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
out=output/bench_auto_choice
mkdir -p "$out"
cases=(
  "manufactured_traction 0.05"
  "manufactured_dirichlet 0.025"
  "kirsch 0.16"
  "manufactured_traction 0.025"
  "bracket 0.002"
  "manufactured_dirichlet 0.0125"
  "cantilever 0.25"
  "lame 2.5e-4"
  "kirsch 0.08"
  "flamant 0.03"
  "bracket 0.001"
  "lame 2.5e-4 basis=\"phs\" degree=6"
  "kirsch 0.08 basis=\"phs\" degree=6"
  "manufactured_dirichlet 0.00625"
  "kirsch 0.04 basis=\"phs\" degree=6"
)
echo "| scene | spacing | approximation | nodes | nonzeros | LU factors (est.) MB | lu solve s | gmres+amg solve s (iterations) | auto: method, solve s | lu / gmres | run peak MB lu / gmres |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for c in "${cases[@]}"; do
  read -r scene h approx <<< "$c"
  for kind in lu gmres auto; do
    # shellcheck disable=SC2086
    python3 benches/scene_variant.py "problems/$scene.toml" "$out/$kind.toml" "solver.kind=\"$kind\"" 'estimate.method="none"' $approx > /dev/null
    rm -rf "$out/$kind"
    ./target/release/mlsm --quiet run "$out/$kind.toml" --spacing "$h" --out "$out/$kind" 2> /dev/null || true
  done
  python3 - "$out" "$scene" "$h" "${approx:-shipped}" <<'PY'
import json, os, sys
out, scene, h, approx = sys.argv[1:]
def load(k):
    p = f"{out}/{k}/summary.json"
    return json.load(open(p)) if os.path.exists(p) else None
lu, gm, au = load("lu"), load("gmres"), load("auto")
n, nnz = lu["unknowns"], lu["nonzeros"]
factors = nnz * 34 * n ** 0.26 / 1e6
solve = lambda s: s["timings_s"]["solve"]
g = f"{solve(gm):.3f} ({gm['solver']['iterations']})" if gm else "failed"
ratio = f"{solve(lu) / solve(gm):.1f}" if gm else "-"
a = f"{au['solver']['method'].split(' [')[0]}, {solve(au):.3f}" if au else "failed"
peak = f"{lu['peak_memory_bytes'] / 1e6:.0f} / " + (f"{gm['peak_memory_bytes'] / 1e6:.0f}" if gm else "-")
print(f"| {scene} | {h} | {approx} | {lu['nodes']} | {nnz} | {factors:.0f} | {solve(lu):.3f} | {g} | {a} | {ratio} | {peak} |")
PY
done
