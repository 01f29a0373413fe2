#!/usr/bin/env bash
# One entry point for a fresh machine: creates .venv, installs zoetic into it, then runs.
#   ./run.sh demo          install and run the demo (a shark learns to swim)
#   ./run.sh test          install, then run the checks: ruff, the default test tier, the slow tier
#   ./run.sh test ARGS     ruff, then pytest ARGS only (e.g. tests/test_web.py, or -m slow)
#   ./run.sh build-viewer  bundle web/ into src/zoetic/web/static/viewer.js and stamp its sources
#   ./run.sh <args>        any zoetic command, e.g. ./run.sh simulate snake --seconds 5
# Python 3.11+ is all `demo` and the other commands need. `test` and `build-viewer` also need
# Debian's nodejs and npm (to build the viewer and run the glTF validator) and chromium (the
# viewer's browser test): run as root, this script installs them with apt-get; otherwise it
# names the command to run and stops.
set -euo pipefail
cd "$(dirname "$0")"

# Install the Debian packages that are missing (as root), or say how and exit 1. Each argument
# is COMMAND:PACKAGE, the command that must work and the package that brings it.
need_debian() {
  local missing=() want
  for want in "$@"; do
    case "${want%%:*}" in
      ensurepip) "$PY" -c "import ensurepip" >/dev/null 2>&1 || missing+=("${want#*:}") ;;
      *) command -v "${want%%:*}" >/dev/null 2>&1 || missing+=("${want#*:}") ;;
    esac
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "installing ${missing[*]} with apt-get" >&2
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
      "${missing[@]}" >/dev/null
  else
    echo "error: ./run.sh $cmd needs ${missing[*]}; install them, e.g." >&2
    echo "  sudo apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
}

cmd="${1:-demo}"
[ $# -gt 0 ] && shift

# web/node_modules: esbuild and three.js (the viewer's build) and the Khronos glTF validator
# (a test). The built viewer itself is in git, so the other commands need none of this.
# npm ci runs again whenever web/package-lock.json changes (its hash is kept in node_modules).
npm_ci() {
  need_debian node:nodejs npm:npm
  local lock
  lock="$(sha256sum web/package-lock.json | cut -c1-16)"
  if [ "$(cat web/node_modules/.zoetic-lock 2>/dev/null)" != "$lock" ]; then
    (cd web && npm ci --no-audit --no-fund --loglevel=error) >&2
    echo "$lock" > web/node_modules/.zoetic-lock
  fi
}

if [ "$cmd" = build-viewer ]; then  # needs npm only, not Python
  npm_ci
  (cd web && npm run --silent build)
  echo "built src/zoetic/web/static/viewer.js and viewer.sources.json: commit both" >&2
  exit 0
fi

PY="${PYTHON:-}"
if [ -z "$PY" ]; then
  for cand in python3.11 python3.12 python3.13 python3; do
    if command -v "$cand" >/dev/null 2>&1; then PY="$cand"; break; fi
  done
fi
[ -n "$PY" ] || { echo "error: zoetic needs Python 3.11 or newer (python3.11)" >&2; exit 1; }
if [ ! -x .venv/bin/python ]; then
  need_debian ensurepip:python3-venv
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

case "$cmd" in
  demo) exec zoetic demo "$@" ;;
  test)
    npm_ci
    need_debian chromium:chromium
    ruff check src tests scripts experiments
    ruff format --check src tests scripts experiments
    if [ $# -gt 0 ]; then exec python -m pytest "$@"; fi
    python -m pytest            # the default tier
    exec python -m pytest -m 'slow and not long'  # the slow tier: JAX compiles, Ray clusters, searches
    ;;
  *) exec zoetic "$cmd" "$@" ;;
esac
