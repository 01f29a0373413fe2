#!/usr/bin/env bash
# Every benchmark, one JSON object per line, then one table of every figure beside its
# reference (the same run's baseline, the papers' figures, bench/reference.json's previous
# figure): ./bench/run.sh [--quick] [--save-reference]   (after ./run.sh has made .venv)
# Figures are ratios measured side by side in the same run; absolute numbers depend on the
# host (the table's title names its CPU and SIMD width), so compare only like with like.
set -euo pipefail
cd "$(dirname "$0")/.."
Z=".venv/bin/zoetic"
[ -x "$Z" ] || { echo "no .venv: run ./run.sh test (or ./run.sh demo) first" >&2; exit 2; }
exec "$Z" bench all --lines "$@"
