# nbv: the two commands of the README are `make demo` and `make test`.
# Every target installs what is missing first (Debian packages only).

BUILD_DIR ?= build
# ccache hits across clones and build folders (paths below the checkout are made relative;
# the working directory is not hashed, even in -g builds).
export CCACHE_BASEDIR := $(CURDIR)
export CCACHE_NOHASHDIR := 1
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)

# Debian packages the project needs to build, test and benchmark. python3-imath only
# because Debian's Imath CMake config (pulled in by FindOpenVDB) names its library;
# python3-matplotlib draws the plots of `make demo`; pybind11-dev, python3-dev, python3-numpy
# and python3-pytest build and test the Python package; clang and its runtime build the fuzzers.
DEB_PACKAGES := build-essential cmake ccache pkg-config \
  libeigen3-dev libtbb-dev libopenvdb-dev libopenvdb-tools libboost-iostreams-dev \
  liboctomap-dev libcli11-dev libgtest-dev libbenchmark-dev libembree-dev libassimp-dev libpng-dev \
  libnanoflann-dev python3-imath python3-matplotlib pybind11-dev python3-dev python3-numpy python3-pytest python3-venv python3-wheel \
  clang libclang-rt-14-dev nlohmann-json3-dev libjs-three chromium

# `make install` puts the command, libraries, headers, CMake package and Python package here.
PREFIX ?= /usr/local

.PHONY: deps configure build test bench models demo install clean asan tsan fuzz emulate-avx512 float-roundtrips ab-kernels \
  slurm-test

# $(call install-missing,PACKAGES): apt-get install those of PACKAGES that are not installed.
define install-missing
	@missing=""; for p in $(1); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  SUDO=""; [ "$$(id -u)" -ne 0 ] && SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing; \
	else echo "all Debian packages present"; fi
endef

deps:
	$(call install-missing,$(DEB_PACKAGES))

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE)

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

test: build models
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

# The 11 meshes of the experiments (as many as the paper used), from the data archive of
# Debian's libcgal-demo (downloaded, not installed), into the user's data folder
# ($$XDG_DATA_HOME/nbv/models, or NBV_MODELS_DIR): `nbv models fetch`, which keeps what is there.
models: build
	@$(BUILD_DIR)/apps/nbv models fetch

# The build installed under PREFIX: bin/nbv, the libraries, headers, the CMake package and the
# Python package (nbv.plots included), with no path into this clone.
install: build
	cmake --install $(BUILD_DIR) --prefix $(PREFIX)
	@site=$$(cmake -L -N $(BUILD_DIR) | sed -n 's/^NBV_PYTHON_INSTALL_DIR:PATH=//p'); \
	  echo "nbv: $(PREFIX)/bin/nbv (put $(PREFIX)/bin on PATH); Python package: $(PREFIX)/$$site/nbv"; \
	  $(PYTHON) -c "import sys, os; sys.exit(os.path.abspath('$(PREFIX)/'+'$$site') not in map(os.path.abspath, sys.path))" || \
	  echo "      $(PYTHON) does not look there: export PYTHONPATH=$(PREFIX)/$$site, or pip install . (README, Python)"
# The README's first command: reconstruct the bunny with Proximity Count for 20 views, print
# the per-iteration table, and write the run's JSON and a coverage plot to $(DEMO_DIR).
DEMO_DIR ?= demo-output
# Debian's interpreter, which has python3-matplotlib (not whatever `python3` is first on PATH).
PYTHON ?= /usr/bin/python3
demo: build models
	@mkdir -p $(DEMO_DIR)
	$(BUILD_DIR)/apps/nbv reconstruct --model bunny --metric pc --iterations 20 --seed 0 \
	  --json $(DEMO_DIR)/bunny_pc.json --html $(DEMO_DIR)/bunny_pc.html
	PYTHONPATH=$(BUILD_DIR)/python $(PYTHON) -m nbv.plots runs $(DEMO_DIR)/bunny_pc.json --out $(DEMO_DIR)/bunny_pc.png
	@echo "demo: the run is in $(DEMO_DIR)/bunny_pc.json, its coverage and entropy plot in $(DEMO_DIR)/bunny_pc.png,"
	@echo "      and a page to look at it in 3D in $(DEMO_DIR)/bunny_pc.html (open it in a browser)"

bench: build models
	$(BUILD_DIR)/bench/nbv_bench_sensor --benchmark_counters_tabular=true
	$(BUILD_DIR)/bench/nbv_bench_kernels --benchmark_counters_tabular=true
	$(BUILD_DIR)/bench/nbv_bench_grid --benchmark_counters_tabular=true
	$(BUILD_DIR)/bench/nbv_bench_ig --benchmark_counters_tabular=true

# Sanitizer and fuzzing stages; .ci/run runs them after `make test`. Debug builds at -O1 with
# line tables keep the asserts and readable stacks, and compile in reasonable time.
SANITIZER_FLAGS := -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" -DNBV_BUILD_BENCHMARKS=OFF \
  -DNBV_BUILD_PYTHON=OFF
SANITIZER_ENV := ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 \
  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/sanitizers/lsan.supp:print_suppressions=0 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  TSAN_OPTIONS=halt_on_error=1:suppressions=$(CURDIR)/tests/sanitizers/tsan.supp
# The parallel code: integration, IG evaluation, anytime decisions, depth rendering, the
# planner's loop (ctest regular expressions over the GoogleTest names: those to run, and those
# left out of them).
# The real-scale workloads' walks against the reference (a minute each under AddressSanitizer):
# their maps' code (workloads, OctoMap tiles) is run by the other tests.
ASAN_EXCLUDE := RealScaleWorkloads
TSAN_TESTS := Parallel|Threads|ThreadCount|Serial|^InformationGain\.|^DepthCamera\.|^Reconstruction|^Experiment\.|^VisibleVoxels\.
TSAN_EXCLUDE := ^InformationGain\.Bunny3

# The whole suite (unit and command-line tests) under AddressSanitizer + UBSan (GCC's; clang's
# UBSan also flags the sentinel pointers of TBB's concurrent_hash_map, in OpenVDB's headers).
asan: deps models
	cmake -S . -B build-asan $(SANITIZER_FLAGS) -DNBV_SANITIZE=address,undefined
	cmake --build build-asan -j $(JOBS)
	cd build-asan && $(SANITIZER_ENV) ctest --output-on-failure -j $(JOBS) -E '$(ASAN_EXCLUDE)'

# The parallel tests under ThreadSanitizer, JOBS at a time.
tsan: deps models
	cmake -S . -B build-tsan $(SANITIZER_FLAGS) -DNBV_SANITIZE=thread -DNBV_BUILD_APPS=OFF
	cmake --build build-tsan -j $(JOBS) --target nbv_tests
	cd build-tsan && $(SANITIZER_ENV) ctest --output-on-failure -j $(JOBS) -R '$(TSAN_TESTS)' -E '$(TSAN_EXCLUDE)'

# The suite with the AVX-512 walks over plain C++ lanes (NBV_EMULATE_AVX512: 8 lanes, bit
# masks, the instructions' rules; kernels/src/simd_emulated.hpp) on any CPU with AVX2, so that a
# machine without AVX-512 still checks them. The intrinsics themselves are checked against the
# same lanes by the LaneOps tests where the CPU has AVX-512. Left out: the tests of bad files,
# sweeps' processes, pages and installs, which no walk changes (half of the stage's test time).
EMULATE_EXCLUDE := ^cli\.(bad_inputs|sweep|report|export)$$|^package\.|BadMapFiles
emulate-avx512: deps models
	cmake -S . -B build-emulate-avx512 -DCMAKE_BUILD_TYPE=Release -DNBV_EMULATE_AVX512=ON \
	  -DNBV_BUILD_BENCHMARKS=OFF -DNBV_BUILD_PYTHON=OFF
	cmake --build build-emulate-avx512 -j $(JOBS)
	cd build-emulate-avx512 && ctest --output-on-failure -j $(JOBS) -E '$(EMULATE_EXCLUDE)'

# Every source of the build compiled again with GCC's vectorizer dumps, listing any place where a
# vector rounded to float is widened back to double: GCC 12.2 folds that pair away and loses the
# rounding (scripts/find_float_roundtrips.py; cmake/NbvCompilerChecks.cmake).
float-roundtrips: build
	$(PYTHON) scripts/find_float_roundtrips.py $(BUILD_DIR) --jobs $(JOBS)

# The ray walks of commit BEFORE against this tree's, side by side in one process, on the widest
# instruction set of this CPU unless AB_ISA names one (scripts/ab_kernels.sh; BEFORE's library is
# built in a worktree under build-ab/): make ab-kernels BEFORE=079d7d5 [AB_ISA=avx2] [AB_ROUNDS=20]
AB_ROUNDS ?= 10
ab-kernels:
	@[ -n "$(BEFORE)" ] || { echo "make ab-kernels: give BEFORE=<commit>" >&2; exit 2; }
	$(MAKE) build models
	bash scripts/ab_kernels.sh $(BUILD_DIR) $(BEFORE) "$(AB_ISA)" $(AB_ROUNDS)

# Every libFuzzer target (clang, with AddressSanitizer) for FUZZ_SECONDS from its committed
# seeds (tests/fuzz/corpus), JOBS targets at a time (tests/fuzz/fuzz_one.sh); new inputs go to
# build-fuzz/corpus, crashes to build-fuzz/crashes.
FUZZ_SECONDS ?= 60
FUZZ_TARGETS := fuzz_ply_cloud fuzz_mesh fuzz_views fuzz_map fuzz_integrate_evaluate fuzz_ig_rays fuzz_results_csv
fuzz: deps
	CXX=clang++ cmake -S . -B build-fuzz $(SANITIZER_FLAGS) -DNBV_SANITIZE=address,fuzzer-no-link \
	  -DNBV_BUILD_FUZZERS=ON -DNBV_BUILD_TESTS=OFF -DNBV_BUILD_APPS=OFF
	cmake --build build-fuzz -j $(JOBS) --target $(FUZZ_TARGETS)
	@printf '%s\n' $(FUZZ_TARGETS) | $(SANITIZER_ENV) xargs -P $(JOBS) -I{} bash tests/fuzz/fuzz_one.sh build-fuzz $(FUZZ_SECONDS) {}

# The shipped Slurm sweep on a real one-node cluster of Debian's Slurm, started and stopped by
# scripts/slurm/local_cluster.sh (as root: it runs munged, slurmctld and slurmd) with its state
# in a fresh folder under /tmp (munge's socket path must stay short).
SLURM_PACKAGES := munge slurmctld slurmd slurm-client
slurm-test: build models
	$(call install-missing,$(SLURM_PACKAGES))
	@state=$$(mktemp -d /tmp/nbv-slurm-XXXXXX) && trap 'rm -rf "$$state"' EXIT && \
	  bash scripts/slurm/local_cluster.sh "$$state" bash tests/slurm_test.sh $(BUILD_DIR)/apps/nbv

clean:
	rm -rf $(BUILD_DIR) build-asan build-tsan build-fuzz build-emulate-avx512 build-ab build-pip
	git worktree prune 2>/dev/null || true
