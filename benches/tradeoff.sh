#!/usr/bin/env bash
# The speed-accuracy fronts of the shipped static Navier scenes with an exact solution:
# `mlsm tradeoff` on each with the same budget, then one Markdown table per scene of
# the runs on the front of seconds against e_inf(sigma) (exact errors).
# Usage: bash benches/tradeoff.sh [BUDGET_SECONDS] [SCENE ...]   (default 120, all seven)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
budget=${1:-120}
shift || true
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(cantilever cantilever_traction manufactured_dirichlet manufactured_traction lame kirsch flamant)
out=output/bench_tradeoff
mkdir -p "$out"
for scene in "${scenes[@]}"; do
  ./target/release/mlsm --quiet tradeoff "problems/$scene.toml" --budget "$budget" --out "$out/$scene"
done
python3 - "$out" "${scenes[@]}" <<'PY'
import json, sys
out = sys.argv[1]
for scene in sys.argv[2:]:
    s = json.load(open(f"{out}/{scene}/tradeoff.json"))
    ok = [r for r in s["runs"] if r["status"] == "ok"]
    print(f"\n{scene}: {len(ok)} runs in {s['elapsed_s']:.0f} s (budget {s['budget_s']:.0f} s); front of seconds against e_inf(sigma):\n")
    print("| run | family | spacing | nodes | seconds | peak MB | e_inf(u) | e_inf(sigma) | estimated e_inf(sigma) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in sorted((r for r in ok if r["on_front_sigma"]), key=lambda r: r["seconds"]):
        x, e = r.get("exact") or {}, r.get("estimated") or {}
        f = lambda v: "-" if v is None else f"{v:.2e}"
        print(f"| {r['id']} | {r['family']} | {r['spacing']:.4g} | {r['nodes']} | {r['seconds']:.3f} | {(r['peak_memory_bytes'] or 0) / 1e6:.0f} | {f(x.get('e_inf_u'))} | {f(x.get('e_inf_sigma'))} | {f(e.get('e_inf_sigma'))} |")
    for fam in s["families"]:
        print(f"- {fam['name']}: {fam['runs']} runs; stopped: {fam['stopped']}")
PY
