# hop_impedance: two commands for people.
#   make demo   set up (first time only) and run the main job on the bundled recording
#   make test   set up (first time only) and run the tests
# Every process that may start rclpy keeps DDS discovery on this machine.
export ROS_AUTOMATIC_DISCOVERY_RANGE := LOCALHOST

VENV ?= .venv
PY := $(VENV)/bin/python
DEMO_RECORDING ?= recordings/sim_2p20hz_hard.mcap
DEMO_OUT ?= demo_out

.PHONY: setup demo test lint lint-strict bench screenshot recordings clean help

help:
	@echo "make demo   - set up and run the main job on $(DEMO_RECORDING)"
	@echo "make test   - set up, lint (ruff, mypy) and run the tests"
	@echo "make lint   - ruff (package, bench, tests, scripts), mypy, pylint duplicate-code and function length on the package"
	@echo "make bench  - run the benchmarks in bench/"
	@echo "make screenshot - render docs/rerun_screenshot.png headless"
	@echo "make clean  - remove build products (keeps .venv)"

setup:
	@bash scripts/setup_env.sh

demo: setup
	@$(PY) -m hop_impedance.cli demo $(DEMO_RECORDING) --out $(DEMO_OUT)

test: setup lint
	@$(PY) -m pytest -q

# ruff (style, imports, bugbear, pyupgrade) on the package, bench/, test/ and scripts/ (one set of conventions;
# bench/ and test/ had drifted while only the package was checked) and mypy (the package, lenient) as pyproject.toml configures them;
# pylint's duplicate-code check alone (6 lines or more, comments, docstrings, imports and signatures ignored);
# at most 3 functions over 60 lines, each with its reason above it (issue 20); lint-strict below.
lint: setup lint-strict
	@$(VENV)/bin/ruff check hop_impedance bench test scripts
	@$(VENV)/bin/mypy
	@$(VENV)/bin/pylint --disable=all --enable=duplicate-code --min-similarity-lines=6 --score=n hop_impedance
	@$(PY) scripts/check_function_length.py hop_impedance

# Part of `make lint` (so of `make test`): mypy --strict itself on all of biomech/ and impedance/ (clean since
# 2026-11-24, 76 errors in 17 of 28 files that morning); pyproject.toml also gives these modules strict's checks.
lint-strict: setup
	@$(VENV)/bin/mypy --config-file= --strict --ignore-missing-imports --python-version 3.10 --follow-imports=silent \
		hop_impedance/biomech hop_impedance/impedance

bench: setup
	@for f in bench/bench_*.py; do echo "== $$f"; $(PY) $$f || exit 1; done

# A picture of the Rerun viewer with the default blueprint, rendered without a GPU
# (installs Debian's mesa-vulkan-drivers if missing): docs/rerun_screenshot.png
screenshot: setup
	@bash scripts/screenshot.sh

clean:
	rm -rf build $(DEMO_OUT) demo.rrd
