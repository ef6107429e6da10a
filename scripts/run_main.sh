#!/usr/bin/env bash
# The main job: bootstrap the venv, then run the ROS 2 node graph (plant, seven
# DNBS joint-controller processes, reference) for 20 s of simulated time in
# lockstep, with metrics, figures and report in runs/main/ and every topic in
# the MCAP bag runs/main_bag/ (both replaced if present).
# Extra arguments go to `pa10-dnbs launch`, e.g. --mode realtime or --out DIR.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$ROOT/scripts/bootstrap.sh"
cd "$ROOT"
mkdir -p runs
exec "$ROOT/.venv/bin/pa10-dnbs" launch --mode lockstep --controller dnbs --duration 20 --out runs/main \
    --record runs/main_bag --force "$@"
