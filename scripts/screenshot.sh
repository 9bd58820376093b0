#!/usr/bin/env bash
# Render docs/rerun_screenshot.png: the Rerun viewer with the default blueprint,
# headless, on the CPU (no GPU or display needed).
#   1. installs Debian's CPU Vulkan driver (mesa-vulkan-drivers, libvulkan1) if missing;
#   2. disables the viewer's usage analytics (rerun analytics disable);
#   3. writes an .rrd of a bundled recording with `hop-impedance view --rrd`;
#   4. opens it in the headless viewer (loopback only), pauses at TIME_S, saves the PNG.
# Usage: scripts/screenshot.sh [RECORDING] [OUT.png]   (env: TIME_S, PY)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PY:-.venv/bin/python}
REC=${1:-recordings/sim_2p20hz_hard.mcap}
OUT=${2:-docs/rerun_screenshot.png}
TIME_S=${TIME_S:-2.35}

if ! dpkg -s mesa-vulkan-drivers libvulkan1 >/dev/null 2>&1; then
    SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq mesa-vulkan-drivers libvulkan1
fi
"$PY" -m rerun_cli analytics disable >/dev/null
RRD=$(mktemp --suffix=.rrd)
trap 'rm -f "$RRD"' EXIT
"$PY" -m hop_impedance.cli view "$REC" --rrd "$RRD"
"$PY" -m hop_impedance.viz.screenshot "$RRD" "$OUT" --time-s "$TIME_S" 2>/dev/null
echo "screenshot: $OUT"
