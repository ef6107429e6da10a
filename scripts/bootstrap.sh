#!/usr/bin/env bash
# Create .venv (Python 3.11) and install the pinned dependencies and this
# package (editable). Re-installs only when requirements.txt or setup.py change.
# Usage: source scripts/bootstrap.sh   (sets VENV_PY)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"
PY="${PYTHON:-python3.11}"
if ! command -v "$PY" >/dev/null 2>&1; then
  echo "bootstrap: $PY not found; the ROS 2 Jazzy wheels need CPython 3.11 (set PYTHON=...)" >&2
  exit 1
fi
if [ ! -x "$VENV/bin/python" ]; then
  echo "bootstrap: creating $VENV" >&2
  "$PY" -m venv "$VENV"
fi
STAMP="$VENV/.pa10_dnbs-installed"
WANT="$(cat "$ROOT/requirements.txt" "$ROOT/setup.py" "$ROOT/setup.cfg" | sha256sum | cut -d' ' -f1)"
if [ ! -f "$STAMP" ] || [ "$(cat "$STAMP")" != "$WANT" ]; then
  echo "bootstrap: installing pinned dependencies (requirements.txt)" >&2
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check -r "$ROOT/requirements.txt"
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --no-deps -e "$ROOT"
  echo "$WANT" > "$STAMP"
fi
VENV_PY="$VENV/bin/python"
export VENV_PY
