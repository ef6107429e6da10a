#!/usr/bin/env bash
# The main job: bootstrap the venv, then the 20 s closed loop (DNBS and the PID
# baseline) with metrics, figures and report in runs/main/ (replaced if present).
# Extra arguments go to `pa10-dnbs simulate`, e.g. --out DIR.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$ROOT/scripts/bootstrap.sh"
cd "$ROOT"
exec "$ROOT/.venv/bin/pa10-dnbs" simulate --controller both --duration 20 --out runs/main --force "$@"
