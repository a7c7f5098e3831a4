#!/usr/bin/env bash
# clang-tidy over every product source (about 14 minutes on 2 cores); with no finding, the commit
# checked is recorded in benchmarks/results/tidy-full.json, from which the test suite's
# tidy.clang_tidy_base_layers checks only what changed. Needs a configured build (compile_commands.json)
# and product folders without uncommitted changes.  Usage: benchmarks/tidy_full.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
python3 tests/tidy/check_tidy.py "${1:-build}" --jobs "$(nproc)" --record benchmarks/results/tidy-full.json
