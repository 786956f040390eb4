#!/usr/bin/env bash
# The bracket's error estimate under refinement at its re-entrant corner: the tip
# deflection of the run (least squares p = 2, the scenes' setting) and of the
# estimate's reference (PHS r^3 + degree 4, 30 nodes) on the same node sets, the
# shipped 2 mm spacing graded towards the corner (0.06, 0.14) to SPACING at growth
# 0.1 ([nodes.refine] points), for the L without holes and the bracket. Finite
# elements (benches/fem_reference.py): L -4.8938e-4 m, bracket -4.975e-4 m.
# POINTS="[[0.06, 0.14], [0.0, 0.0], [0.06, 0.0]]" grades towards the clamped corners
# of the base as well.
# Usage: [POINTS=...] bash benches/corner_reference.sh   (BENCHMARKS.md, "The bracket's estimate
# under corner refinement")
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
tmp=output/bench_corner_reference
mkdir -p "$tmp"
echo "| scene | corner spacing | nodes | tip, least squares p = 2 | tip, PHS p = 4 | estimated e_inf(u) | estimated rel_l2(u) |"
echo "|---|---|---|---|---|---|---|"
for scene in benches/bracket_variants/L.toml problems/bracket.toml; do
  name=$(basename "$scene" .toml)
  for corner in none 0.0007 0.00025; do
    refine=()
    [ "$corner" = none ] || refine=("nodes.refine.points=${POINTS:-[[0.06, 0.14]]}" "nodes.refine.spacing=$corner" nodes.refine.growth=0.1)
    python3 benches/scene_variant.py "$scene" "$tmp/${name}_p2.toml" 'estimate.method="higher-degree"' "${refine[@]}"
    python3 benches/scene_variant.py "$scene" "$tmp/${name}_p4.toml" 'approximation.basis="phs"' approximation.degree=4 -approximation.support 'estimate.method="none"' "${refine[@]}"
    for basis in p2 p4; do
      ./target/release/mlsm --quiet run "$tmp/${name}_$basis.toml" --spacing 0.002 --out "$tmp/${name}_${basis}_$corner" 2> /dev/null
    done
    python3 - "$tmp/${name}_p2_$corner/summary.json" "$tmp/${name}_p4_$corner/summary.json" "$name" "$corner" <<'PY'
import json, sys
p2, p4 = (json.load(open(f)) for f in sys.argv[1:3])
tip = lambda s: next(p["value"] for p in s["probes"] if p["name"] == "tip_deflection")
e = p2["estimated_errors"]
print(f"| {sys.argv[3]} | {sys.argv[4]} | {p2['nodes']} | {tip(p2):.4e} | {tip(p4):.4e} | {e['e_inf_u']:.2e} | {e['rel_l2_u']:.2e} |")
PY
  done
done
