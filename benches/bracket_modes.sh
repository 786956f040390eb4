#!/usr/bin/env bash
# The scattered-node bracket's failure, measured (README, Known limits, re-entrant
# corners): for each variant in benches/bracket_variants/, on scattered nodes and on a
# grid, the tip probe at h = 4, 2, 1 mm and, at 4 mm, the two smallest singular values
# of the row-scaled system with the rigid-motion share of the softest mode
# (benches/near_null_mode.py; needs `pip install numpy scipy`).
#   bash benches/bracket_modes.sh [variant ...]     (default: column notch L fillet)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
mlsm=target/release/mlsm
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
variants=("${@:-column notch L fillet}")
for variant in ${variants[@]}; do
    for fill in scattered grid; do
        scene="$work/$variant-$fill.toml"
        # A grid is not relaxed (relaxation would scatter it).
        relax=5
        [ "$fill" = grid ] && relax=0
        sed "s/^fill = \"scattered\"/fill = \"$fill\"/; s/^relax = 5/relax = $relax/" "benches/bracket_variants/$variant.toml" >"$scene"
        probes=""
        for h in 0.004 0.002 0.001; do
            # A refused or failed level (exit 2 or 3) is printed as such.
            value=$({ "$mlsm" run "$scene" --spacing "$h" --out "$work/out" 2>/dev/null || echo "probe failed($?)"; } | awk '/^probe/ {print $NF}')
            probes="$probes $value"
        done
        rm -rf "$work/system"
        modes="none (the run failed)"
        if "$mlsm" --quiet run "$scene" --spacing 0.004 --out "$work/out" --export-system "$work/system" 2>/dev/null; then
            modes=$(python3 benches/near_null_mode.py "$work/system" | awk '/^smallest/ {print $4, $5} /explains/ {print "rigid", $(NF-6); exit}' | tr '\n' ' ')
        fi
        echo "$variant $fill: probe at 4/2/1 mm:$probes; smallest singular values and rigid share at 4 mm: $modes"
    done
done
