#!/usr/bin/env bash
# Create .venv (if missing), install what the requirements files list, the package
# itself (editable) and build the hop_impedance_msgs interface package into the venv.
# Each step is skipped when its inputs have not changed, so re-running is quick.
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON=${PYTHON:-python3}
VENV=${VENV:-.venv}
STAMPS="$VENV/.stamps"

need() { # need NAME FILES... : true if the stamp for NAME is older than any of FILES
  local stamp="$STAMPS/$1"; shift
  [ ! -f "$stamp" ] && return 0
  for f in "$@"; do [ "$f" -nt "$stamp" ] && return 0; done
  return 1
}
done_() { mkdir -p "$STAMPS"; touch "$STAMPS/$1"; }

if [ ! -x "$VENV/bin/python" ]; then
  echo "setup: creating $VENV with $($PYTHON --version 2>&1)"
  "$PYTHON" -m venv "$VENV"
  "$VENV/bin/python" -m pip install --quiet --upgrade pip setuptools wheel
fi
PIP="$VENV/bin/python -m pip install --quiet --disable-pip-version-check"

if need requirements requirements/*.txt; then
  echo "setup: installing Python packages (ROS 2 wheels, numpy, scipy, osqp, mcap, rerun-sdk, test tools)"
  $PIP -r requirements/runtime.txt -r requirements/ros.txt -r requirements/test.txt
  done_ requirements
fi
if need package setup.py setup.cfg; then
  echo "setup: installing hop_impedance (editable)"
  $PIP --no-deps -e .
  done_ package
fi
# Generates and compiles msg_defs/ unless unchanged (it keeps its own hash stamp).
"$VENV/bin/python" scripts/build_msgs.py
# Rerun's SDK and viewer send usage analytics unless told not to (config in ~/.config/rerun).
if [ ! -f "$STAMPS/rerun-analytics-off-$(id -u)" ] || [ ! -f "${XDG_CONFIG_HOME:-$HOME/.config}/rerun/analytics.json" ]; then
  "$VENV/bin/rerun" analytics disable >/dev/null 2>&1 || "$VENV/bin/python" -m rerun analytics disable >/dev/null 2>&1 || true
  done_ "rerun-analytics-off-$(id -u)"
fi
