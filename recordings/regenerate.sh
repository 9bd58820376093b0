#!/bin/sh
# Regenerate the bundled simulated recordings (and their .truth.json files).
# Usage: recordings/regenerate.sh [PYTHON]   (default: .venv/bin/python of the repo)
# Deterministic: fixed seeds; takes about 2 minutes on one core.
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
PY=${1:-"$HERE/../.venv/bin/python"}
sim() { "$PY" -m hop_impedance.cli simulate "$@"; }
# Seed 000's Table 1 trials: the seed-like hopper (scenarios.seed_like_hopper_options) on the force plate (rigid)
# with its shoe pad in series. The names keep "hard" (the contact under the shoe is rigid: see README.md).
sim --hopper seed-like --freq 1.53 --surface rigid --hops 10 --seed 11 --out "$HERE/sim_1p53hz_hard.mcap"
sim --hopper seed-like --freq 1.87 --surface rigid --hops 10 --seed 12 --out "$HERE/sim_1p87hz_hard.mcap"
sim --hopper seed-like --freq 2.20 --surface rigid --hops 10 --seed 13 --out "$HERE/sim_2p20hz_hard.mcap"
# Seed 001's pair stays on the default hopper: the seed-like hopper finds no periodic 2.2 Hz hop on seed 001's soft
# law (session 33's preset: closest 419 ms stance, 41 ms flight; test/simulation/test_sim_seed001_prepared.py) and its
# bell excludes the time-based activation below (README.md).
sim --freq 2.20 --surface soft --hops 10 --seed 14 --out "$HERE/sim_2p20hz_soft.mcap"
# Seed 001's unexpected surface: time-based activation tuned on soft; hops 4 and 7 land on hard.
sim --freq 2.20 --surface soft --activation --unexpected hard --unexpected-hops 4,7 --hops 10 --seed 15 \
    --out "$HERE/sim_2p20hz_soft_unexpected_hard.mcap"
