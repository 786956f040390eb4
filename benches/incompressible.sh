#!/usr/bin/env bash
# Near-incompressible plane strain: observed orders of the displacement and the
# displacement-pressure forms at nu = 0.3, 0.49, 0.4999, 0.5 on the Lame ring
# (scattered nodes, 5 levels from h = 1e-3) and the manufactured solution with
# traction on two sides (scattered, 5 levels from h = 0.1; nu = 0.5 is refused there:
# the field is not divergence-free), RBF-FD PHS r^3 + degree 4 and least squares of
# degree 2. One Markdown table (benches/orders.sh rows). Usage: bash benches/incompressible.sh [LEVELS]
set -euo pipefail
cd "$(dirname "$0")/.."
levels=${1:-4}
export BASES="phs 4;monomials 2" COARSE="lame=0.001"
header=1
for scene in lame manufactured_traction; do
  for run in "0.3 displacement" "0.3 displacement-pressure" "0.49 displacement-pressure" "0.4999 displacement-pressure" "0.5 displacement-pressure"; do
    set -- $run
    [ "$scene" = manufactured_traction ] && [ "$1" = 0.5 ] && continue
    EDITS="material.nu=$1 formulation=\"$2\"" bash benches/orders.sh "$levels" "$scene" | tail -n +$((header ? 1 : 3))
    header=0
  done
done
