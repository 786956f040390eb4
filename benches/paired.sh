# Shared setup of the scripts that alternate runs in pairs (estimate.sh,
# dynamic_estimate.sh, pd_estimate.sh); sourced, not run: strict mode, the repository
# as working directory, MLSM (built when unset), PAIRS (default 3), a scratch folder
# `work` removed on exit, and `scenes` from the script's arguments.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[1]}")/.."
[ -n "${MLSM:-}" ] || { cargo build --release --quiet; MLSM=target/release/mlsm; }
PAIRS=${PAIRS:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scenes=("$@")
