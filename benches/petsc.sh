#!/usr/bin/env bash
# The PETSc path (feature `petsc`) against size and ranks: per-stage seconds (slowest
# rank), iterations, rank 0's peak memory, halo per rank and errors of a scene at
# several spacings, on each number of ranks, with PETSc options passed through.
# Usage: bash benches/petsc.sh SCENE "H1 H2 ..." "RANKS..." "PETSC OPTIONS" [EDIT ...]
# Example: bash benches/petsc.sh cantilever "0.0387 0.0194" "1 2" "-pc_type gamg" 'basis="tensor"' degree=2 'weight="gaussian"' sigma=1 support=13
# MLSM_BIN=path runs another build (e.g. an earlier commit's, for before/after tables).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-petsc.sh > /dev/null
if [ -z "${MLSM_BIN:-}" ]; then cargo build --release --quiet --features petsc; fi
bin=${MLSM_BIN:-target/release/mlsm}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
scene=$1; spacings=$2; ranks=$3; options=$4; shift 4
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
python3 benches/scene_variant.py "problems/$scene.toml" "$tmp/s.toml" 'estimate.method="none"' 'solver.kind="petsc"' 'solver.max_iterations=5000' "$@" > /dev/null
echo "| ranks | nodes | unknowns | method | iterations | nodes+supports+shapes s | assembly s | solve s (setup + iterations) | total s | rank 0 peak MB | halo per rank | e_inf(u) | e_inf(sigma) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for h in $spacings; do
  for p in $ranks; do
    # shellcheck disable=SC2086
    if mpirun --oversubscribe -n "$p" "$bin" --quiet run "$tmp/s.toml" --spacing "$h" --out "$tmp/o" -- $options 2> "$tmp/err"; then
      python3 - "$tmp/o/summary.json" "$p" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
s, e = d["solver"], d["errors"]
ranks = s["ranks"]
slowest = lambda name: max(dict(r).get(name, 0.0) for r in ranks["stage_seconds"])
geo = sum(slowest(k) for k in ("nodes", "supports", "shapes"))
total = d["timings_s"]["total"]
print(f"| {sys.argv[2]} | {d['nodes']} | {d['unknowns']} | {s['method']} | {s['iterations']} | {geo:.2f} | {slowest('assembly'):.2f} | "
      f"{slowest('solve'):.2f} ({s['setup_seconds']:.2f} + {s['solve_seconds']:.2f}) | {total:.2f} | {d['peak_memory_bytes'] / 1e6:.0f} | "
      f"{'/'.join(str(x) for x in ranks['halo_unknowns'])} | {e['e_inf_u']:.3e} | {e['e_inf_sigma']:.3e} |")
PY
    else
      echo "| $p | h = $h failed: $(tail -c 300 "$tmp/err" | tr '\n|' '  ') |"
    fi
  done
done
