#!/usr/bin/env bash
# What the error estimate costs, as users run it: every shipped static scene (or the
# scenes given) with the default estimate (`auto`), with `higher-degree` (the
# certificate, the default before 2026-11-28) and with `none`, back to back, PAIRS
# times alternated. Prints per scene: the method `auto` took, seconds without the
# estimate, the estimate's seconds under auto and under higher-degree, the estimate's
# share of the run, the whole run's time and peak-memory ratios (auto / none), and
# the effectivities (estimate / true error) where the scene has an exact solution.
# Medians over the pairs.
#
# Usage: bash benches/estimate.sh [SCENE[:SPACING][@key=value,...]]...
#   e.g. bash benches/estimate.sh kirsch "cantilever:0.035@approximation.basis=tensor"
# Environment: PAIRS (default 3), MLSM (default target/release/mlsm), METHODS (default
# "none auto higher-degree"; leave higher-degree out at 1e6 nodes, where it takes minutes);
# BEFORE=<another build's mlsm> adds its `auto` run to each alternation (columns
# "before": its estimate's seconds, its total / none and its peak / none).
source "$(dirname "$0")/paired.sh"
if [ ${#scenes[@]} -eq 0 ]; then
  scenes=(cantilever cantilever_traction manufactured_dirichlet manufactured_traction lame kirsch flamant gravity_dam steel_plate bracket)
fi
echo "| scene | nodes | auto took | run s (none) | estimate s: auto / higher-degree | share of run: auto / higher-degree | total auto / none | peak auto / none | eff u / sigma (auto) |"
echo "|---|---|---|---|---|---|---|---|---|"
for spec in "${scenes[@]}"; do
  base=${spec%%@*}; edits=""; [ "$base" != "$spec" ] && edits=${spec#*@}
  name=${base%%:*}; spacing=""; [ "$name" != "$base" ] && spacing=${base#*:}
  args=(); [ -n "$spacing" ] && args=(--spacing "$spacing")
  kv=(); IFS=',' read -ra kv <<< "$edits"
  for method in auto higher-degree none; do
    python3 benches/scene_variant.py "problems/$name.toml" "$work/$method.toml" "estimate.method=\"$method\"" "${kv[@]/#/}" > /dev/null
  done
  methods=${METHODS:-none auto higher-degree}
  [ -n "${BEFORE:-}" ] && methods="$methods before"
  for k in $(seq "$PAIRS"); do
    for method in $methods; do
      bin=$MLSM; file=$method
      [ "$method" = before ] && { bin=$BEFORE; file=auto; }
      "$bin" --quiet run "$work/$file.toml" "${args[@]}" --out "$work/o_${method}_$k" > /dev/null 2>&1
    done
  done
  python3 - "$work" "$PAIRS" "$spec" <<'PY'
import json, statistics, sys
work, pairs, spec = sys.argv[1], int(sys.argv[2]), sys.argv[3]
def runs(m):
    return [json.load(open(f"{work}/o_{m}_{k}/summary.json")) for k in range(1, pairs + 1)]
import os
none, auto = runs("none"), runs("auto")
hd = runs("higher-degree") if os.path.exists(f"{work}/o_higher-degree_1") else [{"timings_s": {"estimate": float("nan")}}]
med = statistics.median
total = lambda s: s["timings_s"]["total"] - s["timings_s"].get("output", 0)
est = lambda s: s["timings_s"].get("estimate", 0.0)
run_s = med(total(s) for s in none)
a_est, h_est = med(est(s) for s in auto), med(est(s) for s in hd)
t_ratio = med(total(a) / total(n) for a, n in zip(auto, none))
m_ratio = med(a["peak_memory_bytes"] / n["peak_memory_bytes"] for a, n in zip(auto, none))
x = auto[0]["estimated_errors"]; e = auto[0].get("errors")
eff = "-"
if e and x:
    eff = f"{x['e_inf_u'] / e['e_inf_u']:.2f} / {x['e_inf_sigma'] / e['e_inf_sigma']:.2f}"
took = x["method"] if x else "none"
row = f"| {spec} | {auto[0]['nodes']} | {took} | {run_s:.2f} | {a_est:.2f} / {h_est:.2f} | {a_est / run_s:.2f} / {h_est / run_s:.2f} | {t_ratio:.2f} | {m_ratio:.2f} | {eff} |"
if os.path.exists(f"{work}/o_before_1"):
    before = runs("before")
    b_t = med(total(b) / total(n) for b, n in zip(before, none))
    b_m = med(b["peak_memory_bytes"] / n["peak_memory_bytes"] for b, n in zip(before, none))
    bx = before[0]["estimated_errors"]
    b_eff = f"{bx['e_inf_u'] / e['e_inf_u']:.2f}" if e and bx else (f"{bx['e_inf_u']:.2e} / {x['e_inf_u']:.2e}" if bx and x else "-")
    row += f" before: estimate {med(est(s) for s in before):.2f} s, total {b_t:.2f}, peak {b_m:.2f}, {bx['method'] if bx else 'none'}, e_inf(u) {b_eff} |"
print(row)
PY
done
