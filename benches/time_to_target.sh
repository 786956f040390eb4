#!/usr/bin/env bash
# Time to reach e_inf(sigma) <= TARGET (default 1e-4) on Kirsch and Lame with the old
# default (least-squares monomials of degree 2, default support) and the RBF-FD
# setting (PHS r^3 + degree 4), side by side in one run on the same machine. Each
# series refines the uniform spacing by 1/sqrt(2) per step from a coarse start until
# the target is met, or the node count passes MAX_NODES (default 3e5: sparse LU
# memory then passes 10 GB) and the series is reported as not reaching it.
# Usage: bash benches/time_to_target.sh [TARGET] [MAX_NODES]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
target=${1:-1e-4}
max_nodes=${2:-300000}
declare -A coarse=([kirsch]=0.08 [lame]=5e-4)
tmp=output/bench_target
mkdir -p "$tmp"
echo "| scene | basis | steps | nodes | seconds (last run) | seconds (all runs) | e_inf(sigma) | reached |"
echo "|---|---|---|---|---|---|---|---|"
for scene in kirsch lame; do
  for basis in "monomials 2" "phs 4"; do
    set -- $basis
    file="$tmp/${scene}_$1_$2.toml"
    python3 benches/scene_variant.py "problems/$scene.toml" "$file" "basis=\"$1\"" "degree=$2" "estimate.method=\"none\"" > /dev/null
    sed -i '/^\[nodes.refine\]/,/^$/d' "$file"
    h=${coarse[$scene]}
    step=0
    total=0
    while :; do
      out="$tmp/${scene}_$1_$2_$step"
      ./target/release/mlsm --quiet run "$file" --spacing "$h" --out "$out"
      read -r nodes secs es <<< "$(python3 -c "import json; s = json.load(open('$out/summary.json')); print(s['nodes'], s['timings_s']['total'], s['errors']['e_inf_sigma'])")"
      total=$(python3 -c "print($total + $secs)")
      reached=$(python3 -c "print('yes' if $es <= $target else 'no')")
      next=$(python3 -c "print($nodes * 2)")
      if [ "$reached" = yes ] || [ "$next" -gt "$max_nodes" ]; then
        printf "| %s | %s | %d | %d | %.2f | %.2f | %.2e | %s |\n" "$scene" "$basis" $((step + 1)) "$nodes" "$secs" "$total" "$es" "$reached"
        break
      fi
      h=$(python3 -c "print($h / 2 ** 0.5)")
      step=$((step + 1))
    done
  done
done
