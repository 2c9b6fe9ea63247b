# Thin wrapper over CMake, CTest, the harness and the analysis scripts.
# Every target that builds first runs scripts/bootstrap.sh, so a fresh Debian machine needs nothing else.

BUILD   ?= build
PY      := /usr/bin/python3
CONFIG  ?= quick.json
# A bare name is looked up in configs/; anything else is a path.
CONFIG_PATH := $(if $(wildcard configs/$(CONFIG)),configs/$(CONFIG),$(CONFIG))
OUT     ?= results/$(basename $(notdir $(CONFIG_PATH)))
RESULTS ?= $(OUT)
SCENE   ?= scenes/cradle.in
K       ?= 1

.PHONY: all deps build test sweep plots compare bench animate clean

all: build

deps:
	@scripts/bootstrap.sh

build: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release >/dev/null
	@cmake --build $(BUILD) -j 2

test: build
	cd $(BUILD) && ctest --output-on-failure -j 2
	$(PY) -m pytest -q tests/python

sweep: build
	$(BUILD)/psweep $(CONFIG_PATH) --out $(OUT) $(if $(RESUME),--resume)
	$(MAKE) --no-print-directory plots RESULTS=$(OUT)

plots: deps
	$(PY) analysis/plots.py $(RESULTS)

# A = the reference sweep, B = the one compared against it; COMPARE_OUT overrides where it goes.
compare: deps
	@test -n "$(A)" -a -n "$(B)" || { echo "usage: make compare A=results/x B=results/y" >&2; exit 2; }
	$(PY) analysis/compare.py $(A) $(B) $(if $(COMPARE_OUT),--out $(COMPARE_OUT))

bench: build
	$(BUILD)/bench_engine --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

animate: build
	$(PY) analysis/animate.py $(SCENE) --slow-factor $(K) --psim $(BUILD)/psim

clean:
	rm -rf $(BUILD)
