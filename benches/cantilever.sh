#!/usr/bin/env bash
# Per-stage timings of the Timoshenko cantilever (variant A, tensor-quadratic basis,
# 13-node supports, sparse LU) at about 1e4, 1e5 and 4e5 nodes.
# Usage: bash benches/cantilever.sh [spacing ...]   (default: 0.125 0.039 0.0195)
# Prints one markdown table row per size, read from each run's summary.json.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
spacings=("$@")
[ ${#spacings[@]} -gt 0 ] || spacings=(0.125 0.039 0.0195)
echo "| nodes | unknowns | nodes s | supports s | shapes s | shapes us/node/core | assembly s | solve s | post s | estimate s | output s | total s | peak MB | bytes/node | e_inf(u) | e_inf(sigma) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for h in "${spacings[@]}"; do
  out="output/bench_cantilever_$h"
  ./target/release/mlsm --quiet run problems/cantilever.toml --spacing "$h" --out "$out"
  python3 - "$out/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
t = s["timings_s"]
n = s["nodes"]
mem = s.get("peak_memory_bytes") or 0
us = t["shapes"] * s["threads"] / n * 1e6
print(f"| {n} | {s['unknowns']} | {t['nodes']:.3f} | {t['supports']:.3f} | {t['shapes']:.3f} | {us:.2f} | {t['assembly']:.3f} | {t['solve']:.2f} | {t['post']:.3f} | {t.get('estimate', 0):.2f} | {t['output']:.3f} | {t['total']:.2f} | {mem/2**20:.0f} | {mem/n:.0f} | {s['errors']['e_inf_u']:.2e} | {s['errors']['e_inf_sigma']:.2e} |")
PY
done
