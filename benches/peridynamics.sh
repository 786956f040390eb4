#!/usr/bin/env bash
# Per-stage timings of the static peridynamic solve of problems/pd_manufactured.toml
# (unit square, Dirichlet collar, m = 3) at about 1e4 and 1e5 free nodes, for the
# asymptotically compatible weights and the full-area rule, with the default solver
# (BiCGSTAB + ILU(0), tolerance 1e-10) and with sparse LU.
# Usage: bash benches/peridynamics.sh [horizon ...]   (default: 0.03 0.0095)
# Prints one markdown table row per run, read from each run's summary.json.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
horizons=("$@")
[ ${#horizons[@]} -gt 0 ] || horizons=(0.03 0.0095)
echo "| rule | solver | nodes | bonds | nodes s | families s | weights s | assembly s | solve s | iterations | total s | peak MB | e_inf(u) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for d in "${horizons[@]}"; do
  for rule in ac full-area; do
    for solver in bicgstab lu; do
      scene="output/bench_pd_${rule}_${solver}.toml"
      sed "s/quadrature = \"ac\"/quadrature = \"$rule\"/" problems/pd_manufactured.toml > "$scene"
      [ "$solver" = lu ] && printf '\n[peridynamics.solver]\nkind = "lu"\n' >> "$scene"
      out="output/bench_pd_${rule}_${solver}_$d"
      ./target/release/mlsm --quiet run "$scene" --model peridynamics --horizon "$d" --out "$out"
      python3 - "$out/summary.json" "$rule" "$solver" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
t = s["timings_s"]
mem = s.get("peak_memory_bytes") or 0
print(f"| {sys.argv[2]} | {sys.argv[3]} | {s['nodes']} | {s['bonds']} | {t['nodes']:.3f} | {t['families']:.3f} | {t['weights']:.3f} | {t['assembly']:.3f} | {t['solve']:.2f} | {s['solver']['iterations']} | {t['total']:.2f} | {mem/2**20:.0f} | {s['errors']['e_inf_u']:.2e} |")
PY
    done
  done
done
