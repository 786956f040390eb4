#!/usr/bin/env bash
# Direct against iterative solves of the same systems: sparse LU, BiCGSTAB+ILUT and
# BiCGSTAB+ILU(0) on the shipped cantilever (grid) and Kirsch (scattered, graded)
# at a few spacings, the error estimate off. One Markdown row per run: nodes,
# unknowns, solver, iterations, solve seconds (setup + iterations), total seconds,
# peak memory of the solve stage and of the run, e_inf(u), e_inf(sigma).
# Usage: bash benches/solvers.sh ["cantilever=0.0625 0.03125" "kirsch=0.04 0.02"]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin=target/release/mlsm
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ $# -gt 0 ]; then runs=("$@"); else runs=("cantilever=0.0625 0.03125" "kirsch=0.04 0.02"); fi
echo "| scene | h | nodes | unknowns | solver | iterations | solve s | total s | solve peak MB | run peak MB | e_inf(u) | e_inf(sigma) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for entry in "${runs[@]}"; do
  scene=${entry%%=*}
  for h in ${entry#*=}; do
    for solver in 'kind="lu"' 'kind="bicgstab" preconditioner="ilut" max_iterations=5000' 'kind="bicgstab" preconditioner="ilu0" max_iterations=5000'; do
      edits=('estimate.method="none"')
      for kv in $solver; do edits+=("solver.$kv"); done
      python3 benches/scene_variant.py "problems/$scene.toml" "$tmp/s.toml" "${edits[@]}" > /dev/null
      if "$bin" --quiet run "$tmp/s.toml" --spacing "$h" --out "$tmp/o" 2> "$tmp/err"; then
        python3 - "$tmp/o/summary.json" "$scene" "$h" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
s, t, e = d["solver"], d["timings_s"], d["errors"]
peaks = d.get("peak_memory_by_stage_bytes", {})
print(f"| {sys.argv[2]} | {sys.argv[3]} | {d['nodes']} | {d['unknowns']} | {s['method']} | {s['iterations']} | "
      f"{t['solve']:.2f} | {t['total']:.2f} | {peaks.get('solve', 0) / 1e6:.0f} | {d['peak_memory_bytes'] / 1e6:.0f} | "
      f"{e['e_inf_u']:.3e} | {e['e_inf_sigma']:.3e} |")
EOF
      else
        echo "| $scene | $h | | | $solver | failed: $(tail -c 160 "$tmp/err" | tr '\n|' '  ') | | | | | | |"
      fi
    done
  done
done
