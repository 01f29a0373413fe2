#!/usr/bin/env bash
# One entry point for a fresh machine: creates .venv, installs zoetic into it, then runs.
#   ./run.sh demo          install and run the demo (a shark learns to swim)
#   ./run.sh test          install and run the checks (ruff + the test suite)
#   ./run.sh <args>        any zoetic command, e.g. ./run.sh simulate snake --seconds 5
set -euo pipefail
cd "$(dirname "$0")"

PY="${PYTHON:-}"
if [ -z "$PY" ]; then
  for cand in python3.11 python3.12 python3.13 python3; do
    if command -v "$cand" >/dev/null 2>&1; then PY="$cand"; break; fi
  done
fi
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
# shellcheck disable=SC1091
. .venv/bin/activate
stamp=".venv/.zoetic-installed"
want="$(sha256sum pyproject.toml | cut -c1-16)"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  python -m pip install --quiet --upgrade pip
  python -m pip install --quiet -e ".[test]"
  echo "$want" > "$stamp"
fi

# The web viewer's script (three.js + web/viewer.js, bundled by esbuild) is built, not kept in git.
# web/node_modules also holds the Khronos glTF validator that the tests run.
bundle=src/zoetic/web/static/viewer.js
if command -v npm >/dev/null 2>&1; then
  if [ ! -f "$bundle" ] || [ ! -d web/node_modules/gltf-validator ] \
     || [ web/viewer.js -nt "$bundle" ] || [ web/package-lock.json -nt "$bundle" ]; then
    (cd web && npm ci --no-audit --no-fund --loglevel=error && npm run --silent build) >&2
  fi
elif [ ! -f "$bundle" ]; then
  echo "note: npm not found, so the web viewer (zoetic view) is not built" >&2
fi

cmd="${1:-demo}"
[ $# -gt 0 ] && shift
case "$cmd" in
  demo) exec zoetic demo "$@" ;;
  test)
    ruff check src tests scripts
    exec python -m pytest "$@"
    ;;
  *) exec zoetic "$cmd" "$@" ;;
esac
