#!/usr/bin/env bash
# What the `local-model` estimate of a peridynamic run costs: each scene run by the
# peridynamic model with the default estimate and with `none`, back to back, PAIRS
# times alternated; with BEFORE set (another build's binary), its runs with the default
# estimate alternate with them too. Prints per scene: nodes, the run's seconds without
# the estimate, the estimate's seconds (this binary / BEFORE) and its share of the run,
# the estimate of e_inf(u) and the reference's own. Medians over the pairs.
#
# Usage: [BEFORE=path/to/old/mlsm] bash benches/pd_estimate.sh [SCENE[:HORIZON]]...
# Environment: PAIRS (default 3), MLSM (default target/release/mlsm).
source "$(dirname "$0")/paired.sh"
[ ${#scenes[@]} -gt 0 ] || scenes=(pd_manufactured pd_trig pd_tension steel_plate_dynamic plate_pulse)
echo "| scene | nodes | run s (none) | estimate s: this / before | share: this / before | e_inf(u) est. | reference's own |"
echo "|---|---|---|---|---|---|---|"
for spec in "${scenes[@]}"; do
  name=${spec%%:*}; args=(--model peridynamics); [ "$name" != "$spec" ] && args+=(--horizon "${spec#*:}")
  python3 benches/scene_variant.py "problems/$name.toml" "$work/none.toml" 'estimate.method="none"' > /dev/null
  for k in $(seq "$PAIRS"); do
    "$MLSM" --quiet run "$work/none.toml" "${args[@]}" --out "$work/o_none_$k" > /dev/null 2>&1
    "$MLSM" --quiet run "problems/$name.toml" "${args[@]}" --out "$work/o_this_$k" > /dev/null 2>&1
    [ -z "${BEFORE:-}" ] || "$BEFORE" --quiet run "problems/$name.toml" "${args[@]}" --out "$work/o_before_$k" > /dev/null 2>&1
  done
  python3 - "$work" "$PAIRS" "$spec" <<'PY'
import json, os, statistics, sys
work, pairs, spec = sys.argv[1], int(sys.argv[2]), sys.argv[3]
runs = lambda m: [json.load(open(f"{work}/o_{m}_{k}/summary.json")) for k in range(1, pairs + 1) if os.path.exists(f"{work}/o_{m}_{k}")]
none, this, before = runs("none"), runs("this"), runs("before")
med = lambda v: statistics.median(v) if v else float("nan")
run_s = med([s["timings_s"]["total"] - s["timings_s"].get("output", 0) for s in none])
est = lambda rs: med([s["timings_s"].get("estimate", 0.0) for s in rs])
a, b = est(this), est(before)
x = this[0]["estimated_errors"]
own = x.get("reference_estimated_e_inf_u")
print(f"| {spec} | {this[0]['nodes']} | {run_s:.3f} | {a:.3f} / {b:.3f} | {a / run_s:.1f} / {b / run_s:.1f} | {x['e_inf_u']:.2e} | {'-' if own is None else f'{own:.1e}'} |")
PY
done
