#!/bin/sh
# Regenerate the bundled simulated recordings (and their .truth.json files).
# Usage: recordings/regenerate.sh [PYTHON]   (default: .venv/bin/python of the repo)
# Deterministic: fixed seeds; takes about 2 minutes on one core.
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
PY=${1:-"$HERE/../.venv/bin/python"}
sim() { "$PY" -m hop_impedance.cli simulate "$@"; }
sim --freq 1.53 --surface hard --hops 10 --seed 11 --out "$HERE/sim_1p53hz_hard.mcap"
sim --freq 1.87 --surface hard --hops 10 --seed 12 --out "$HERE/sim_1p87hz_hard.mcap"
sim --freq 2.20 --surface hard --hops 10 --seed 13 --out "$HERE/sim_2p20hz_hard.mcap"
sim --freq 2.20 --surface soft --hops 10 --seed 14 --out "$HERE/sim_2p20hz_soft.mcap"
# Seed 001's unexpected surface: time-based activation tuned on soft; hops 4 and 7 land on hard.
sim --freq 2.20 --surface soft --activation --unexpected hard --unexpected-hops 4,7 --hops 10 --seed 15 \
    --out "$HERE/sim_2p20hz_soft_unexpected_hard.mcap"
