#!/usr/bin/env bash
# Every benchmark, one JSON object per line: ./bench/run.sh  (after ./run.sh has made .venv)
# Figures are ratios measured side by side in the same run; absolute numbers depend on the
# host (the simulate line names its CPU and SIMD width), so compare only like with like.
set -euo pipefail
cd "$(dirname "$0")/.."
Z=".venv/bin/zoetic"
[ -x "$Z" ] || { echo "no .venv: run ./run.sh test (or ./run.sh demo) first" >&2; exit 2; }
"$Z" bench simulate --json | tail -n 1
"$Z" bench learn --json | tail -n 1
"$Z" bench skills --json | tail -n 1
"$Z" bench san --json | tail -n 1
"$Z" bench ray --json 2>/dev/null | tail -n 1
"$Z" bench jax --json | tail -n 1
"$Z" bench gym --json | tail -n 1
"$Z" bench vision --json | tail -n 1
"$Z" bench aquarium --skills both --json | tail -n 1
"$Z" bench aquarium --perception vision --json | tail -n 1
"$Z" bench stunts --json | tail -n 1
"$Z" bench track --json | tail -n 1
"$Z" bench render --json | tail -n 1
"$Z" bench readme --json | tail -n 1
