#!/usr/bin/env bash
# Build pa10_dnbs with colcon in a temporary workspace (as a ROS 2 workspace would), then run an installed
# executable from outside the source tree: the node executables must be in lib/pa10_dnbs (where `ros2 run`
# looks) and the installed package must find its config and URDF through the ament index.
# Usage: bash scripts/check_colcon.sh   (after scripts/bootstrap.sh; CI runs it)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$ROOT/scripts/bootstrap.sh"
WS="$(mktemp -d -t pa10_colcon_XXXXXX)"
trap 'rm -rf "$WS"' EXIT
mkdir -p "$WS/src"
git -C "$ROOT" ls-files -z | (cd "$ROOT" && xargs -0 cp --parents -t "$WS/src" 2>/dev/null) || cp -r "$ROOT"/{package.xml,setup.py,setup.cfg,resource,pa10_dnbs,config,urdf} "$WS/src/"
cd "$WS"
PATH="$ROOT/.venv/bin:$PATH" timeout 300 colcon build --base-paths src >"$WS/build.log" 2>&1 || { cat "$WS/build.log"; exit 1; }
for exe in pa10-dnbs plant_node joint_controller_node reference_node wire_monitor recorder_node; do
  [ -x "install/pa10_dnbs/lib/pa10_dnbs/$exe" ] || { echo "check_colcon: $exe not in install/pa10_dnbs/lib/pa10_dnbs" >&2; exit 1; }
done
# shellcheck disable=SC1091
set +u; . install/setup.sh; set -u   # colcon-core writes the POSIX sh scripts
OUT="$WS/run"
(cd / && timeout 120 "$WS/install/pa10_dnbs/lib/pa10_dnbs/pa10-dnbs" simulate --controller pid --duration 0.05 \
    --out "$OUT" --no-progress) >"$WS/run.log" 2>&1 || { cat "$WS/run.log"; exit 1; }
grep -q "share/pa10_dnbs/config/default.yaml" "$OUT/metrics.json" \
  || { echo "check_colcon: the installed package did not use its installed config:" >&2; grep config_file "$OUT/metrics.json" >&2; exit 1; }
# the compiled DNBS step from the installed package's default config (dnbs.kernel: auto) and its C source, built
# into a fresh cache; this machine has a C compiler, so auto must pick the compiled step and say so
(cd / && PA10_DNBS_CACHE="$WS/cache" timeout 120 "$WS/install/pa10_dnbs/lib/pa10_dnbs/pa10-dnbs" simulate \
    --controller dnbs --duration 0.05 --out "$WS/run_c" --no-progress --no-figures) >"$WS/run_c.log" 2>&1 \
  || { cat "$WS/run_c.log"; exit 1; }
grep -q "^dnbs.kernel: auto -> c" "$WS/run_c.log" && ls "$WS/cache"/libdnbs_kernel-*.so >/dev/null 2>&1 \
  || { echo "check_colcon: the installed package did not build its DNBS kernel:" >&2; cat "$WS/run_c.log" >&2; exit 1; }
# every arm preset is installed with its files (share/pa10_dnbs/urdf/<arm>/): the installed package runs the iiwa
(cd / && timeout 120 "$WS/install/pa10_dnbs/lib/pa10_dnbs/pa10-dnbs" simulate --arm iiwa --controller pid \
    --duration 0.05 --out "$WS/run_iiwa" --no-progress --no-figures) >"$WS/run_iiwa.log" 2>&1 \
  || { cat "$WS/run_iiwa.log"; exit 1; }
grep -q "share/pa10_dnbs/urdf/iiwa/arm.yaml" "$WS/run_iiwa.log" \
  || { echo "check_colcon: the installed package did not read its installed iiwa arm:" >&2; cat "$WS/run_iiwa.log" >&2; exit 1; }
echo "check_colcon: colcon installed lib/pa10_dnbs/{pa10-dnbs, plant_node, ...}; the installed pa10-dnbs ran with $(grep -o '"config_file": "[^"]*"' "$OUT/metrics.json"), its default dnbs.kernel: auto built the DNBS kernel, and --arm iiwa ran from its installed arm file"
