#!/usr/bin/env bash
# What the error estimate of a dynamic Navier run costs, as users run it: each scene
# run by the Navier model with the default estimate (`auto`, Richardson's from the run
# at twice the spacing), with `refined` (half the spacing, the default before
# 2026-11-28) and with `none`, back to back, PAIRS times alternated. Prints per scene:
# nodes, the method auto took, seconds without the estimate, the estimate's seconds
# and share of the run under auto and refined, the whole run's time and peak ratios
# (auto / none), and the two estimates of e_inf(u) with their ratio. Medians over the
# pairs.
#
# Usage: bash benches/dynamic_estimate.sh [SCENE[:SPACING]]...
#   e.g. bash benches/dynamic_estimate.sh steel_plate_dynamic:0.005
# Environment: PAIRS (default 3), MLSM (default target/release/mlsm).
source "$(dirname "$0")/paired.sh"
[ ${#scenes[@]} -gt 0 ] || scenes=(steel_plate_dynamic plate_pulse)
echo "| scene | nodes | auto took | run s (none) | estimate s: auto / refined | share of run: auto / refined | total auto / none | peak auto / none | e_inf(u): auto / refined (ratio) |"
echo "|---|---|---|---|---|---|---|---|---|"
for spec in "${scenes[@]}"; do
  name=${spec%%:*}; args=(); [ "$name" != "$spec" ] && args+=(--spacing "${spec#*:}")
  for method in auto refined none; do
    python3 benches/scene_variant.py "problems/$name.toml" "$work/$method.toml" "estimate.method=\"$method\"" > /dev/null
    sed -i 's/^model = .*/model = "navier"/' "$work/$method.toml"
  done
  for k in $(seq "$PAIRS"); do
    for method in none auto refined; do
      "$MLSM" --quiet run "$work/$method.toml" "${args[@]}" --out "$work/o_${method}_$k" > /dev/null 2>&1
    done
  done
  python3 - "$work" "$PAIRS" "$spec" <<'PY'
import json, statistics, sys
work, pairs, spec = sys.argv[1], int(sys.argv[2]), sys.argv[3]
runs = lambda m: [json.load(open(f"{work}/o_{m}_{k}/summary.json")) for k in range(1, pairs + 1)]
none, auto, refined = runs("none"), runs("auto"), runs("refined")
med = statistics.median
total = lambda s: s["timings_s"]["total"] - s["timings_s"].get("output", 0)
est = lambda s: s["timings_s"].get("estimate", 0.0)
run_s = med(total(s) for s in none)
a, r = med(est(s) for s in auto), med(est(s) for s in refined)
t_ratio = med(total(x) / total(n) for x, n in zip(auto, none))
m_ratio = med(x["peak_memory_bytes"] / n["peak_memory_bytes"] for x, n in zip(auto, none))
xa, xr = auto[0]["estimated_errors"], refined[0]["estimated_errors"]
print(f"| {spec} | {auto[0]['nodes']} | {xa['method']} | {run_s:.2f} | {a:.2f} / {r:.2f} | {a / run_s:.2f} / {r / run_s:.2f} | {t_ratio:.2f} | {m_ratio:.2f} | {xa['e_inf_u']:.2e} / {xr['e_inf_u']:.2e} ({xa['e_inf_u'] / xr['e_inf_u']:.2f}) |")
PY
done
