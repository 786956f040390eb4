#!/usr/bin/env bash
# Fuzz the scene files for FUZZ_SECONDS (default 600): random mutations of the shipped
# scenes through `mlsm check` and `mlsm run --strict` (benches/fuzz_scenes.rs), each run
# limited to FUZZ_RUN_LIMIT seconds (default 60). Prints the table of outcomes and the
# findings (saved to output/fuzz/); record them in BENCHMARKS.md, "Fuzzing the scenes".
# Usage: [FUZZ_SECONDS=600] [FUZZ_RUN_LIMIT=60] bash benches/fuzz.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo bench --bench fuzz_scenes --quiet
