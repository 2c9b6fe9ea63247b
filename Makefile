# Thin wrapper over CMake, CTest, the harness and the analysis (python3 -m analysis TOOL).
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
# Build and test with every core this machine has.
JOBS    ?= $(shell nproc)

.PHONY: all help deps build tools ceilings test test-faults fuzz fuzz-build test-sanitize sweep sweep-slurm test-slurm plots scoreboard grade grade-slurm gradescope noise compare accuracy bench targets million animate regress regress-baseline test-v3 stability device-kit clean

all: build

# The targets with their one-line descriptions (the text after ## on each target's line).
help: ## the targets, a line each
	@awk -F ':.*## ' '/^[a-z][a-z0-9 -]*:.*## / { printf "  make %-18s %s\n", $$1, $$2 }' $(MAKEFILE_LIST)

deps: ## install the Debian packages the lab needs (only those missing)
	@scripts/bootstrap.sh

# OPT=-O1 (with BUILD=other-dir) configures a build at another optimisation level; AVX512=0 one
# without AVX-512 (as make regress's own build-regress, which valgrind can run); CUDA=OFF|ON|AUTO
# the GPU engine (AUTO: where nvcc is found and a GPU is present); MPI=OFF|ON|AUTO the mpi engine
# (AUTO: where MPI is found); MARCH=x86-64-v3 another instruction set than the host's (make
# regress's); PLANTED=ON the test-only planted slowdown that make regress must catch
# (docs/regress.md); the folder keeps them all.
# Quiet unless something fails (scripts/build.sh: the output in BUILD/build.log).
CMAKE_OPTIONS = $(if $(OPT),-DPARTICLE_OPT=$(OPT)) $(if $(AVX512),-DPARTICLE_AVX512=$(AVX512)) \
	$(if $(MARCH),-DPARTICLE_MARCH=$(MARCH)) $(if $(CUDA),-DPARTICLE_CUDA=$(CUDA)) \
	$(if $(MPI),-DPARTICLE_MPI=$(MPI)) \
	$(if $(PLANTED),-DPARTICLE_PLANTED_SLOWDOWN=$(PLANTED))
build: deps ## build psim, psweep, the benchmarks and the tests [BUILD=DIR OPT=-O1 AVX512=0 CUDA=ON MPI=OFF]
	@JOBS=$(JOBS) scripts/build.sh $(BUILD) -- $(CMAKE_OPTIONS)

# What a sweep and the analysis's tools run, without the tests and benchmarks make test builds.
tools: deps ## build psim, psweep and ceilings alone (what make sweep needs)
	@JOBS=$(JOBS) scripts/build.sh $(BUILD) tools -- $(CMAKE_OPTIONS)

# This machine's ceilings (docs/performance.md, "The machine's ceilings"), measured afresh: the
# pair kernel's peak, memory bandwidth, the caches, process and OpenMP start-up, each with its
# spread. psweep records the same figures in every meta.json (measured once per machine and build,
# or the last make ceilings's: it refreshes psweep's cache).
ceilings: tools ## this machine's ceilings: results/ceilings/ceilings.json and a table (a few seconds)
	@mkdir -p results/ceilings
	$(BUILD)/ceilings --out results/ceilings/ceilings.json

# The browser test of report.html (tests/python/test_report_page.py) needs a headless Chromium.
test: build ## every C++ and Python test, then the quick accuracy check
	@scripts/bootstrap.sh chromium chromium-driver python3-selenium
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)
	$(PY) -m pytest -q tests/python
	$(MAKE) --no-print-directory accuracy QUICK=1 ACCURACY_OUT=$(BUILD)/accuracy-quick

# The fault suite alone (tests/python/test_faults.py, docs/faults.md) with more kill -9 points
# than the short run make test makes.
FAULT_KILLS ?= 12
test-faults: build ## the fault suite alone, with more kill -9 points (FAULT_KILLS=12)
	FAULT_KILLS=$(FAULT_KILLS) $(PY) -m pytest -q tests/python/test_faults.py

sweep: tools ## a sweep from configs/ (CONFIG=quick.json OUT= RESUME=1), then its plots
	$(BUILD)/psweep $(CONFIG_PATH) --out $(OUT) $(if $(RESUME),--resume)
	$(MAKE) --no-print-directory plots RESULTS=$(OUT)

# A sweep as a Slurm job array of SHARDS shards plus a dependent merge job that also draws the plots;
# submits and returns. EXCLUSIVE=1 asks for whole nodes.
SHARDS  ?= 4
sweep-slurm: tools ## submit a sweep to Slurm as SHARDS shards plus a merge job
	scripts/slurm/submit.sh $(CONFIG_PATH) $(OUT) $(SHARDS) $(BUILD)

# End to end on a private 3-node Slurm cluster on this machine (root or sudo; installs slurm-wlm):
# it runs psweep and psim alone, so the tools suffice.
test-slurm: tools ## Slurm sweeps on a private 3-node cluster here, one losing a node, and mpi ranks across nodes (root)
	BUILD=$(BUILD) tests/slurm/test_slurm.sh

plots: deps ## speedup.csv, plots/, report.md and report.html of a results folder (RESULTS=DIR)
	$(PY) -m analysis plots $(RESULTS)

# External programs beside the engines (docs/programs.md): verdict first, then speed.
scoreboard: deps ## programs and engines judged and timed: scoreboard.csv of a results folder (RESULTS=DIR)
	$(PY) -m analysis scoreboard $(RESULTS)

# A folder of submissions (docs/programs.md, "Grading many submissions"): each judged on the
# judging scenes of GRADE_CONFIG and timed beside brute and auto. Exit 0 when the grading ran,
# whatever the submissions did; 2 on bad input.
PROGRAMS     ?=
GRADE_OUT    := $(if $(filter command line,$(origin OUT)),$(OUT),results/grade)
GRADE_CONFIG ?= configs/grade.json
grade: tools ## judge and time every submission of a folder, each confined: scoreboard and reports (PROGRAMS=DIR OUT=results/grade UNCONFINED=1)
	@test -n "$(PROGRAMS)" || { echo "usage: make grade PROGRAMS=DIR [OUT=results/grade]" >&2; exit 2; }
	$(PY) -m analysis grade $(PROGRAMS) --out $(GRADE_OUT) --config $(GRADE_CONFIG) --psweep $(BUILD)/psweep $(if $(UNCONFINED),--unconfined)

# A class over a Slurm cluster (docs/programs.md, "A class on a Slurm cluster"): SHARDS array
# tasks, each grading its group beside the references timed on its node, and a merge job writing
# the OUT make grade writes. Submits and returns; DRY_RUN=1 says the node-hours, submits nothing.
grade-slurm: tools ## a class graded as SHARDS Slurm array tasks plus a merge job (PROGRAMS=DIR SHARDS=4 OUT=results/grade EXCLUSIVE=1 DRY_RUN=1)
	@test -n "$(PROGRAMS)" || { echo "usage: make grade-slurm PROGRAMS=DIR SHARDS=n [OUT=results/grade] [EXCLUSIVE=1] [DRY_RUN=1]" >&2; exit 2; }
	$(if $(UNCONFINED),UNCONFINED=1) scripts/slurm/grade.sh $(PROGRAMS) $(GRADE_OUT) $(SHARDS) $(GRADE_CONFIG) $(BUILD)

# Gradescope's autograder: this lab with setup.sh and run_autograder (scripts/gradescope/), which
# grade one submission confined, as make grade does (docs/programs.md, "Grades for Gradescope").
GRADESCOPE_ZIP ?= results/gradescope-autograder.zip
gradescope: ## the Gradescope autograder zip of this commit: results/gradescope-autograder.zip (GRADESCOPE_ZIP=)
	$(PY) scripts/gradescope/zip.py $(GRADESCOPE_ZIP)

# Quiet against one busy neighbour, T = 1..8 (configs/noise.json): noise.csv and plots/noise.png.
noise: tools ## brute and auto quiet and beside a busy neighbour: results/noise/
	$(BUILD)/psweep configs/noise.json --out results/noise $(if $(RESUME),--resume)
	$(PY) -m analysis noise results/noise

# A = the reference sweep, B = the one compared against it; COMPARE_OUT overrides where it goes.
compare: deps ## how two sweeps differ (A=DIR B=DIR)
	@test -n "$(A)" -a -n "$(B)" || { echo "usage: make compare A=results/x B=results/y" >&2; exit 2; }
	$(PY) -m analysis compare $(A) $(B) $(if $(COMPARE_OUT),--out $(COMPARE_OUT))

# Error against run time (README "Accuracy"): auto at K = 1..256 and event, then the other exact
# engines at small K, on three scenes; QUICK=1 is the short version make test runs.
ACCURACY_OUT ?= results/accuracy
accuracy: tools ## error against run time of every engine and K (QUICK=1: the short one)
ifdef QUICK
	$(BUILD)/psweep configs/accuracy_quick.json --out $(ACCURACY_OUT)/quick
	$(PY) -m analysis accuracy $(ACCURACY_OUT)/quick --out $(ACCURACY_OUT) --psim $(BUILD)/psim \
		--trajectory-ks 1,4,16 --horizon-k 16 --horizon-steps 20
else
	$(BUILD)/psweep configs/accuracy.json --out $(ACCURACY_OUT)/auto $(if $(RESUME),--resume)
	$(BUILD)/psweep configs/accuracy_engines.json --out $(ACCURACY_OUT)/engines $(if $(RESUME),--resume)
	$(PY) -m analysis accuracy $(ACCURACY_OUT)/auto $(ACCURACY_OUT)/engines --out $(ACCURACY_OUT) \
		--psim $(BUILD)/psim
endif

bench: build ## Google Benchmark micro-benchmarks, minimum of 5 repetitions
	$(BUILD)/bench_engine --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

# The speed targets (README "Performance") through psweep, every configuration interleaved, then
# `python3 -m analysis targets`: per scene the minimum wall_s, ns per particle-step, peak RSS, the speed-up
# against the scene's reference run and its target, state hashes against brute. `targets`: the
# default scene, section 8 and the slow crowd (configs/targets.json); `million`: the
# million-particle loop (configs/million.json). Exit 1 when a state hash differs.
targets million: tools ## the speed targets end to end (configs/targets.json, configs/million.json)
	$(BUILD)/psweep configs/$@.json --out results/$@ $(if $(RESUME),--resume)
	$(PY) -m analysis targets results/$@

# Stiff and extreme scenes through every engine: results/stability/{stability.csv,report.md};
# exit 1 on any failure. `make test` runs the quick subset (tests/python/test_stability.py).
stability: tools ## extreme scenes through every engine: results/stability/
	$(PY) -m analysis stability --psim $(BUILD)/psim --out results/stability

animate: tools ## a GIF of a scene (SCENE=scenes/cradle.in K=1)
	$(PY) -m analysis animate $(SCENE) --slow-factor $(K) --psim $(BUILD)/psim

# make regress measures its own build, REGRESS_BUILD (build-regress: psim and psweep for
# x86-64-v3, tuned generically: no AVX-512, which valgrind 3.19 cannot decode, and counts that
# compare across CPUs; no GPU engine; the mpi engine as configured by default, psim-mpi beside
# psim, so that MPI's libraries linked into psim again would count in every run, the
# one-particle group's above all), made or brought up to date first. BUILD=dir takes that build as it was
# configured instead (its own flags: make build BUILD=build-O1 OPT=-O1 AVX512=0). ONLY=instructions
# runs only the valgrind part (what CI runs), ONLY=wall only the timed one; REQUIRE_GATE=1 fails
# when the instruction counts could not be gated (CI: a gate that never bites guards nothing).
REGRESS_BUILD := $(if $(filter command line,$(origin BUILD)),$(BUILD),build-regress)
define regress_build
	@if [ "$(origin BUILD)" = "command line" ]; then \
	  test -f $(BUILD)/CMakeCache.txt || { echo "make regress: $(BUILD) is not a CMake build (make one: make build BUILD=$(BUILD) AVX512=0 [OPT=-O1])" >&2; exit 2; }; \
	  cmake --build $(BUILD) -j $(JOBS) --target tools >/dev/null; \
	else JOBS=$(JOBS) scripts/build.sh $(REGRESS_BUILD) tools -- -DPARTICLE_MARCH=x86-64-v3 \
	  -DPARTICLE_AVX512=OFF -DPARTICLE_CUDA=OFF -DPARTICLE_MPI=AUTO; fi
endef

# BASE=REF: compare with that commit instead of the committed baseline, both measured here,
# interleaved (its build in build-base/, scripts/regress-base.sh), so the wall-time gate bites on
# any machine.
regress: deps ## the regression check against results/baselines/regress/ (ONLY=instructions|wall REQUIRE_GATE=1 BASE=REF)
	$(regress_build)
	$(if $(BASE),@JOBS=$(JOBS) scripts/regress-base.sh $(BASE) build-base)
	$(PY) -m analysis regress run --build $(REGRESS_BUILD) $(if $(ONLY),--only $(ONLY)) \
		$(if $(REQUIRE_GATE),--require-gate) $(if $(BASE),--base-build build-base/build)

# The engine tests of make regress's own build (x86-64-v3: AVX2 and FMA, no AVX-512). On an
# AVX-512 machine the suite's build takes the AVX-512 paths and leaves the AVX2 ones untested;
# .ci/run runs this there.
test-v3: deps ## the engine tests of build-regress (x86-64-v3), the AVX2 paths
	$(regress_build)
	cmake --build $(REGRESS_BUILD) -j $(JOBS) --target engine_tests >/dev/null
	$(REGRESS_BUILD)/tests/engine_tests --gtest_brief=1

# GROUP=NAME records that group alone into the committed baseline, the other rows kept (a new
# group, or one changed on purpose; refused where the baseline's environment differs).
regress-baseline: deps ## record a new regression baseline (GROUP=NAME: that group alone)
	$(regress_build)
	$(PY) -m analysis regress baseline --build $(REGRESS_BUILD) $(if $(GROUP),--group $(GROUP))

# libFuzzer targets of tests/fuzz (README "Fuzzing and sanitizers"), built with Debian's clang in
# their own folder; SECONDS per target, or RUNS inputs each (SECONDS then a cap). CI runs a fixed
# number of inputs from a fixed seed, on a build for a fixed instruction set (x86-64-v3, as make
# regress's), so that the code, its coverage and so the inputs tried are the same on every
# machine for a checkout at the same path (docs/testing.md, "Fuzzing": another path still differs).
# Neither this build nor make test-sanitize's has the MPI engine: MPI's one-time set-up would be a
# leak of the first input that ran it, and its leaks at exit lie in components it has unloaded by
# then, which no suppression can name (docs/testing.md, "Sanitizers").
FUZZ_BUILD ?= build-fuzz
SECONDS    ?= 300
RUNS       ?= 0
fuzz-build:
	@scripts/bootstrap.sh clang-14 libclang-rt-14-dev libomp-14-dev
	@cmake -S . -B $(FUZZ_BUILD) -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 -DPARTICLE_CUDA=OFF \
		-DPARTICLE_MPI=OFF -DPARTICLE_FUZZ=ON -DPARTICLE_OPT=-O1 -DPARTICLE_MARCH=x86-64-v3 -DPARTICLE_AVX512=OFF >/dev/null
	@cmake --build $(FUZZ_BUILD) -j $(JOBS) --target fuzz_scene fuzz_config

fuzz: fuzz-build ## the libFuzzer targets of the two parsers (SECONDS=300 each; RUNS=n: n inputs)
	scripts/fuzz.sh $(FUZZ_BUILD) $(SECONDS) $(RUNS)

# The whole suite (ctest, then the pytest suites that take their build from PARTICLE_LAB_BUILD)
# against a gcc build with AddressSanitizer (LeakSanitizer included) and UndefinedBehaviorSanitizer
# in its own folder; any report fails the test that triggered it. tests/sanitize.supp: see there.
SANITIZE_BUILD ?= build-sanitize
SANITIZE_ENV := ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
	LSAN_OPTIONS=suppressions=$(CURDIR)/tests/sanitize.supp:print_suppressions=0 \
	UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
test-sanitize: deps ## the whole suite against an ASan + UBSan build
	@cmake -S . -B $(SANITIZE_BUILD) -DCMAKE_BUILD_TYPE=Release -DPARTICLE_OPT="-O1 -g" -DPARTICLE_CUDA=OFF \
		-DPARTICLE_MPI=OFF \
		-DCMAKE_CXX_FLAGS="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer" \
		-DCMAKE_C_FLAGS="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer" >/dev/null
	$(SANITIZE_ENV) cmake --build $(SANITIZE_BUILD) -j $(JOBS)
	cd $(SANITIZE_BUILD) && $(SANITIZE_ENV) ctest --output-on-failure -j $(JOBS)
	$(SANITIZE_ENV) PARTICLE_LAB_BUILD=$(SANITIZE_BUILD) $(PY) -m pytest -q tests/python

# The device machine (docs/testing.md, "On the device machine"): build here with CUDA, pack the
# binaries and the libraries they load into device-kit/, carry it there, run scripts/device-check.sh.
# Its own build, build-device/, for x86-64-v3 rather than this host: the device's CPU is unknown
# (an EPYC Milan has no AVX-512), and a kit of -march=native would die there before main. tools:
# psim-mpi too where the build has MPI, so the kit never carries a stale one.
device-kit: deps ## pack psim, psim-mpi, psweep and the GPU tests for the device machine (device-kit/)
	@JOBS=$(JOBS) scripts/build.sh build-device tools gpu_tests -- -DPARTICLE_CUDA=ON \
		-DPARTICLE_MARCH=x86-64-v3
	scripts/device-kit.sh build-device device-kit

clean: ## remove the build folders (build/, build-regress/, build-device/, build-base/) and device-kit/
	rm -rf $(BUILD) build-regress build-device device-kit build-base
	git worktree prune
