#!/usr/bin/env bash
# Create .venv (if missing) and install the project with pinned versions (requirements.lock).
# Usage: source scripts/setup.sh   (sets $PY to the venv's python)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${REPLICATION_VENV:-$ROOT/.venv}"
if [ ! -x "$VENV/bin/python" ]; then
    "${PYTHON:-python3}" -m venv "$VENV"
fi
PY="$VENV/bin/python"
"$PY" -m pip install --quiet --disable-pip-version-check --upgrade pip
# the distribution was named replication before it became camimu-replication: an older venv's install goes first
if "$PY" -m pip show --quiet replication >/dev/null 2>&1; then
    "$PY" -m pip uninstall --quiet --yes replication
fi
"$PY" -m pip install --quiet --disable-pip-version-check -c "$ROOT/requirements.lock" -e "$ROOT[study,test,notebooks,docs]"
export PY
echo "setup done: $PY (replication and its pinned dependencies installed)" >&2
