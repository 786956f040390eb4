#!/usr/bin/env bash
# Time to accuracy against scikit-fem (benches/time_to_accuracy.py says what is run and
# how it is timed). Installs the pinned Python packages of benches/fem-requirements.txt
# into output/fem-venv on first use, builds mlsm, and runs the sweeps; the table goes to
# stdout and output/time_to_accuracy/table.md, every run to .../runs.jsonl.
# Run by hand, not by CI: about 30-60 minutes on 2 cores with the default cap.
# Usage: bash benches/time_to_accuracy.sh [--scenes lame,kirsch] [--cap 30] [--repeat 1]
set -euo pipefail
cd "$(dirname "$0")/.."
venv=output/fem-venv
if ! "$venv/bin/python" -c "import skfem, pyamg, gmsh" 2> /dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet -r benches/fem-requirements.txt
fi
cargo build --release --quiet
exec "$venv/bin/python" benches/time_to_accuracy.py "$@"
