#!/usr/bin/env bash
# Throughput of the explicit time loop on problems/steel_plate_dynamic.toml with
# about 1e5 nodes and a short end time (2e-5 s): peridynamics (Verlet and RK4, m = 3
# and m = 6) in bond updates per second per thread and steps per second, and MLSM
# elastodynamics (RK4, tensor-quadratic, 13-node supports) in seconds per step per node.
# Usage: bash benches/dynamics.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
echo "| model | integrator | setting | nodes | bonds | steps | loop s | steps/s | bond updates/s/thread | s per step per node | peak MB |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for case in "peridynamics verlet 0.0052 3" "peridynamics rk4 0.0052 3" "peridynamics verlet 0.0104 6" "navier rk4 0.00173 6"; do
  set -- $case
  model=$1 integ=$2 size=$3 m=$4
  scene="output/bench_dyn_$model.toml"
  sed -e "s/end_time = 1e-3/end_time = 2e-5/" -e "s/integrator = \"rk4\"/integrator = \"$integ\"/" -e "s/snapshots = 20/snapshots = 1/" -e "s/^m = 6/m = $m/" problems/steel_plate_dynamic.toml > "$scene"
  out="output/bench_dyn_${model}_${integ}_$m"
  if [ "$model" = peridynamics ]; then
    ./target/release/mlsm --quiet run "$scene" --horizon "$size" --out "$out"
    setting="delta $size, m = $m"
  else
    ./target/release/mlsm --quiet run "$scene" --model navier --spacing "$size" --out "$out"
    setting="h = $size"
  fi
  python3 - "$out/summary.json" "$model" "$integ" "$setting" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
r = s["integration"]
bonds = s.get("bonds", "-")
bu = s.get("bond_updates_per_second_per_thread")
mem = (s.get("peak_memory_bytes") or 0) / 2**20
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {s['nodes']} | {bonds} | {r['steps']} | {r['seconds']:.2f} | {r['steps']/r['seconds']:.1f} | {('%.2e' % bu) if bu else '-'} | {s['seconds_per_step_per_node']:.2e} | {mem:.0f} |")
PY
done
