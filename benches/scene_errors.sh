#!/bin/bash
# The shipped static scenes' errors and estimates with two binaries, side by side:
# a change meant to keep results (a faster kernel, a refactoring) shows here as equal
# digits. Usage: BEFORE=/path/to/old/mlsm AFTER=target/release/mlsm bash benches/scene_errors.sh [scene ...]
set -euo pipefail
cd "$(dirname "$0")/.."
BEFORE=${BEFORE:?set BEFORE to the old binary}
AFTER=${AFTER:-target/release/mlsm}
scenes=${*:-cantilever cantilever_traction manufactured_dirichlet manufactured_traction lame kirsch flamant gravity_dam steel_plate bracket}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
printf '| scene | binary | exit | e_inf(u) | e_inf(sigma) | estimated e_inf(u) | estimated e_inf(sigma) |\n|---|---|---|---|---|---|---|\n'
for scene in $scenes; do
  for which in before after; do
    bin=$BEFORE; [ "$which" = after ] && bin=$AFTER
    rc=0; "$bin" -q run "problems/$scene.toml" --out "$out/$which/$scene" >/dev/null 2>&1 || rc=$?
    python3 - "$out/$which/$scene/summary.json" "$scene" "$which" "$rc" <<'PY'
import json, sys
path, scene, which, rc = sys.argv[1:]
try:
    s = json.load(open(path))
except OSError:
    print(f"| {scene} | {which} | {rc} | - | - | - | - |"); sys.exit()
def g(d, k):
    v = (d or {}).get(k)
    return f"{v:.6e}" if isinstance(v, (int, float)) else "-"
e, est = s.get("errors"), s.get("estimated_errors")
print(f"| {scene} | {which} | {rc} | {g(e,'e_inf_u')} | {g(e,'e_inf_sigma')} | {g(est,'e_inf_u')} | {g(est,'e_inf_sigma')} |")
PY
  done
done
