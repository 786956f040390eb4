#!/usr/bin/env bash
# Behaviour unchanged, bit for bit: run every shipped scene (and, for a scene with a
# [peridynamics] table, its peridynamic model too) with one binary into a folder, then
# compare two such folders: every .vtu/.pvd byte for byte, every .csv to 1e-12 (a
# dynamic run's energies are parallel sums: the same binary twice differs in the last
# digit), and the results of every summary.json (errors, estimates, probes,
# equilibrium, sizes, warnings; timings and memory left out).
#
#   bash benches/identical.sh run  DIR [MLSM]   # MLSM defaults to target/release/mlsm
#   bash benches/identical.sh diff DIR_BEFORE DIR_AFTER
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
run)
    out=$2; mlsm=${3:-target/release/mlsm}
    mkdir -p "$out"
    for scene in problems/*.toml; do
        name=$(basename "$scene" .toml)
        "$mlsm" run -q "$scene" --out "$out/$name" >"$out/$name.log" 2>&1 || echo "exit $?" >>"$out/$name.log"
        if grep -q '^\[peridynamics\]' "$scene"; then
            "$mlsm" run -q "$scene" --model peridynamics --out "$out/$name.pd" >"$out/$name.pd.log" 2>&1 || echo "exit $?" >>"$out/$name.pd.log"
        fi
    done
    ;;
diff)
    python3 - "$2" "$3" <<'PY'
import json, pathlib, sys
a, b = map(pathlib.Path, sys.argv[1:3])
keys = ["nodes", "boundary_nodes", "ghost_nodes", "unknowns", "nonzeros", "errors",
        "estimated_errors", "equilibrium", "probes", "warnings", "singular_corners"]

def strip(v):
    """The value without its wall-clock and memory figures (they differ run to run)."""
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if "seconds" not in k and "memory" not in k and not k.endswith("_s")}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v

def csv_close(ta, tb):
    """Numbers equal to 1e-12 relative: the energies of a dynamic run are parallel sums
    whose order varies from run to run (the same binary twice differs in the last digit)."""
    la, lb = ta.splitlines(), tb.splitlines()
    if len(la) != len(lb):
        return False
    for x, y in zip(la, lb):
        for u, v in zip(x.split(","), y.split(",")):
            try:
                fu, fv = float(u), float(v)
            except ValueError:
                if u != v:
                    return False
                continue
            if abs(fu - fv) > 1e-12 * max(abs(fu), abs(fv)):
                return False
    return True

bad, n = [], 0
for fa in sorted(p for p in a.rglob("*") if p.is_file()):
    rel = fa.relative_to(a)
    fb = b / rel
    if not fb.exists():
        bad.append(f"{rel}: missing after"); continue
    if fa.suffix in (".vtu", ".pvd"):
        n += 1
        if fa.read_bytes() != fb.read_bytes():
            bad.append(f"{rel}: bytes differ")
    elif fa.suffix == ".csv":
        n += 1
        if not csv_close(fa.read_text(), fb.read_text()):
            bad.append(f"{rel}: values differ")
    elif fa.name == "summary.json":
        n += 1
        ja, jb = json.loads(fa.read_text()), json.loads(fb.read_text())
        for k in keys:
            if strip(ja.get(k)) != strip(jb.get(k)):
                bad.append(f"{rel}: {k} differs: {strip(ja.get(k))!r:.300} vs {strip(jb.get(k))!r:.300}")
    elif fa.suffix == ".log":
        la = [l for l in fa.read_text().splitlines() if l.startswith("exit")]
        lb = [l for l in fb.read_text().splitlines() if l.startswith("exit")]
        if la != lb:
            bad.append(f"{rel}: exit codes {la} vs {lb}")
print(f"{n} files compared, {len(bad)} differences")
for x in bad:
    print("  " + x)
sys.exit(1 if bad else 0)
PY
    ;;
*)
    echo "usage: $0 run DIR [MLSM] | diff BEFORE AFTER" >&2; exit 2 ;;
esac
