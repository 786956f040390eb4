#!/usr/bin/env bash
# Observed orders on scattered nodes: Kirsch, Lame and the manufactured solution with
# traction on two sides (scattered fill), each at LEVELS halvings of a coarse spacing,
# for the least-squares default (monomials, degree 2) and RBF-FD PHS (r^3) with
# degree 2, 4 and 6. Prints one Markdown row per level and a fit row per series:
# errors, per-step and least-squares orders, and the worst single-step growth.
# Usage: bash benches/orders.sh [LEVELS] [SCENE ...]   (default: 4 halvings, all three)
# Environment: BASES="phs 4;monomials 2" picks the bases; EDITS="material.nu=0.5 ..."
# adds scene edits (benches/scene_variant.py syntax) to every run and to the label;
# COARSE="lame=0.001" overrides a coarse spacing. Kirsch runs on its own graded density
# (h = min(H, H/8 + 0.625 H d), d the distance to the hole, H = 0.32 at the coarsest
# level); EDITS="-nodes.refine" COARSE="kirsch=0.16" gives the uniform series.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
levels=${1:-4}
shift || true
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(manufactured_traction lame kirsch)
declare -A coarse=([manufactured_traction]=0.1 [lame]=0.0016 [kirsch]=0.32)
declare -A extra=([manufactured_traction]='nodes.fill="scattered"' [lame]='' [kirsch]='nodes.refine.spacing=0.04 nodes.refine.growth=0.2')
for kv in ${COARSE:-}; do coarse[${kv%%=*}]=${kv#*=}; done
IFS=';' read -ra bases <<< "${BASES:-monomials 2;phs 2;phs 4;phs 6}"
edits=${EDITS:-}
tmp=output/bench_orders
mkdir -p "$tmp"
echo "| scene | basis | N | e_inf(u) | order | e_inf(sigma) | order | seconds | peak MB |"
echo "|---|---|---|---|---|---|---|---|---|"
for scene in "${scenes[@]}"; do
  for basis in "${bases[@]}"; do
    set -- $basis
    scene_file="$tmp/${scene}_$1_$2.toml"
    python3 benches/scene_variant.py "problems/$scene.toml" "$scene_file" "basis=\"$1\"" "degree=$2" "estimate.method=\"none\"" "nodes.spacing=${coarse[$scene]}" ${extra[$scene]} $edits
    out="$tmp/${scene}_$1_$2"
    if ! /usr/bin/time -f "%M" -o "$out.mem" ./target/release/mlsm --quiet convergence "$scene_file" --levels "$levels" --out "$out" 2> "$out.err"; then
      echo "| $scene | $1 $2${edits:+ $edits} | failed: $(tail -c 200 "$out.err" | tr '\n' ' ') | | | | | | |"
      continue
    fi
    python3 - "$out/convergence.json" "$scene" "$1 $2${edits:+ $edits}" "$(tail -1 "$out.mem")" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))
f = lambda o: "-" if o is None else f"{o:.2f}"
rows = t["levels"]
for l in rows:
    print(f"| {sys.argv[2]} | {sys.argv[3]} | {l['nodes']} | {l['e_inf_u']:.2e} | {f(l['order_e_inf_u'])} | {l['e_inf_sigma']:.2e} | {f(l['order_e_inf_sigma'])} | {l['seconds']:.1f} | |")
grow = max(max(b['e_inf_u'] / a['e_inf_u'], b['e_inf_sigma'] / a['e_inf_sigma']) for a, b in zip(rows, rows[1:]))
print(f"| {sys.argv[2]} | {sys.argv[3]} | fit | | {f(t['fitted_order_e_inf_u'])} | | {f(t['fitted_order_e_inf_sigma'])} | worst step x{grow:.2f} | {int(sys.argv[4]) // 1024} |")
PY
  done
done
