#!/usr/bin/env bash
# Create .venv (if missing), install what the requirements files list, the package
# itself (editable) and build the interface packages (hop_impedance_msgs, mocap4r2_msgs) into the venv.
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

# Toolchain for compiling the message package: g++ and cmake. On a bare Debian
# machine (as root) install them from Debian; otherwise say what is missing.
missing=""
command -v g++ >/dev/null 2>&1 || missing="$missing g++"
command -v cmake >/dev/null 2>&1 || missing="$missing cmake"
command -v make >/dev/null 2>&1 || missing="$missing make"
if [ -n "$missing" ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "setup: installing$missing from Debian"
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $missing >/dev/null
  else
    echo "setup: please install$missing (e.g. sudo apt-get install$missing) and run again" >&2
    exit 1
  fi
fi
if ! "$PYTHON" -c 'import sys; sys.exit(sys.version_info < (3, 10))' 2>/dev/null; then
  echo "setup: need Python >= 3.10 as '$PYTHON' (the ROS 2 wheels exist for CPython 3.10-3.14); set PYTHON=..." >&2
  exit 1
fi

if [ ! -x "$VENV/bin/python" ]; then
  echo "setup: creating $VENV with $($PYTHON --version 2>&1)"
  if ! "$PYTHON" -m venv "$VENV"; then
    echo "setup: '$PYTHON -m venv' failed; on Debian install python3-venv (apt-get install python3-venv)" >&2
    rm -rf "$VENV"; exit 1
  fi
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
# Generates and compiles msg_defs/ and mocap4r2_msgs/ unless unchanged (each keeps its own hash stamp).
"$VENV/bin/python" scripts/build_msgs.py
# Rerun's SDK and viewer send usage analytics unless told not to (config in ~/.config/rerun).
if [ ! -f "$STAMPS/rerun-analytics-off-$(id -u)" ] || [ ! -f "${XDG_CONFIG_HOME:-$HOME/.config}/rerun/analytics.json" ]; then
  "$VENV/bin/rerun" analytics disable >/dev/null 2>&1 || "$VENV/bin/python" -m rerun analytics disable >/dev/null 2>&1 || true
  done_ "rerun-analytics-off-$(id -u)"
fi
