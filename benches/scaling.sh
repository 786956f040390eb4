#!/usr/bin/env bash
# Cost against size for one solver: per-stage seconds, iterations, peak memory and
# errors of a scene at several spacings, with the default error estimate (as users run
# it; ESTIMATE=none turns it off, ESTIMATE=<method> picks another). One Markdown row per run.
# Usage: bash benches/scaling.sh SCENE "H1 H2 ..." SOLVER [EDIT ...]
#   SOLVER: "gmres" (GMRES(30)+AMG), "auto", "lu", "bicgstab-ilu0"; EDIT: scene_variant.py edits,
#   e.g. 'basis="tensor"' degree=2 'weight="gaussian"' sigma=1 support=13
# Example: bash benches/scaling.sh cantilever "0.0387 0.0194 0.01225" gmres 'basis="tensor"' degree=2 'weight="gaussian"' sigma=1 support=13
# MLSM_BIN=path runs that binary instead of building this tree (before/after runs).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${MLSM_BIN:-}" ]; then cargo build --release --quiet; fi
bin=${MLSM_BIN:-target/release/mlsm}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
scene=$1; spacings=$2; solver=$3; shift 3
case $solver in
  gmres) edits=('solver.kind="gmres"') ;;
  auto) edits=('solver.kind="auto"') ;;
  lu) edits=('solver.kind="lu"') ;;
  bicgstab-ilu0) edits=('solver.kind="bicgstab"' 'solver.preconditioner="ilu0"' 'solver.max_iterations=5000') ;;
  *) echo "unknown solver $solver" >&2; exit 2 ;;
esac
python3 benches/scene_variant.py "problems/$scene.toml" "$tmp/s.toml" "estimate.method=\"${ESTIMATE:-auto}\"" "${edits[@]}" "$@" > /dev/null
echo "| nodes | unknowns | nonzeros | method | iterations | nodes+supports+shapes s | assembly s | solve s (setup + iterations) | estimate s | total s | run peak MB | e_inf(u) | estimated e_inf(u) | e_inf(sigma) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for h in $spacings; do
  if "$bin" --quiet run "$tmp/s.toml" --spacing "$h" --out "$tmp/o" 2> "$tmp/err"; then
    python3 - "$tmp/o/summary.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
s, t, e = d["solver"], d["timings_s"], d["errors"]
geo = sum(t.get(k, 0) for k in ("nodes", "supports", "shapes"))
x = d.get("estimated_errors") or {}
est_u = f"{x['e_inf_u']:.2e} ({x['method']})" if x.get("e_inf_u") is not None else "-"
print(f"| {d['nodes']} | {d['unknowns']} | {d['nonzeros']} | {s['method']} | {s['iterations']} | {geo:.2f} | {t['assembly']:.2f} | "
      f"{t['solve']:.2f} ({s['setup_seconds']:.2f} + {s['solve_seconds']:.2f}) | {t.get('estimate', 0):.2f} | {t['total']:.2f} | "
      f"{d['peak_memory_bytes'] / 1e6:.0f} | {e['e_inf_u']:.3e} | {est_u} | {e['e_inf_sigma']:.3e} |")
EOF
  else
    echo "| h = $h failed: $(tail -c 200 "$tmp/err" | tr '\n|' '  ') |"
  fi
done
