# hop_impedance: two commands for people.
#   make demo   set up (first time only) and run the main job on the bundled recording
#   make test   set up (first time only) and run the tests
# Every process that may start rclpy keeps DDS discovery on this machine.
export ROS_AUTOMATIC_DISCOVERY_RANGE := LOCALHOST

VENV ?= .venv
PY := $(VENV)/bin/python
DEMO_RECORDING ?= recordings/sim_2p20hz_hard.mcap
DEMO_OUT ?= demo_out

.PHONY: setup demo test bench screenshot recordings clean help

help:
	@echo "make demo   - set up and run the main job on $(DEMO_RECORDING)"
	@echo "make test   - set up and run the tests"
	@echo "make bench  - run the benchmarks in bench/"
	@echo "make screenshot - render docs/rerun_screenshot.png headless"
	@echo "make clean  - remove build products (keeps .venv)"

setup:
	@bash scripts/setup_env.sh

demo: setup
	@$(PY) -m hop_impedance.cli demo $(DEMO_RECORDING) --out $(DEMO_OUT)

test: setup
	@$(PY) -m pytest -q

bench: setup
	@for f in bench/bench_*.py; do echo "== $$f"; $(PY) $$f || exit 1; done

# A picture of the Rerun viewer with the default blueprint, rendered without a GPU
# (installs Debian's mesa-vulkan-drivers if missing): docs/rerun_screenshot.png
screenshot: setup
	@bash scripts/screenshot.sh

clean:
	rm -rf build $(DEMO_OUT) demo.rrd
