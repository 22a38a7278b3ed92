# nbv: the two commands of the README are `make demo` and `make test`.
# Every target installs what is missing first (Debian packages only).

BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)

# Debian packages the project needs to build, test and benchmark. python3-imath only
# because Debian's Imath CMake config (pulled in by FindOpenVDB) names its library;
# python3-matplotlib draws the plots of `make demo`.
DEB_PACKAGES := build-essential cmake ccache pkg-config \
  libeigen3-dev libtbb-dev libopenvdb-dev libopenvdb-tools libboost-iostreams-dev \
  liboctomap-dev libcli11-dev libgtest-dev libbenchmark-dev libembree-dev libassimp-dev libpng-dev \
  libnanoflann-dev python3-imath python3-matplotlib

MODELS_DIR := data/models
# The meshes of issue 3, from the data archive of Debian's libcgal-demo (downloaded, not installed).
MODEL_FILES := bunny00.off armadillo.off ChineseDragon-10kv.off dino.off head.off

.PHONY: deps configure build test bench models demo clean

deps:
	@missing=""; for p in $(DEB_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  SUDO=""; [ "$$(id -u)" -ne 0 ] && SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing; \
	else echo "all Debian packages present"; fi

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE)

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

test: build models
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

models: $(MODELS_DIR)/.complete

$(MODELS_DIR)/.complete:
	@mkdir -p $(MODELS_DIR)
	@tmp=$$(mktemp -d) && trap 'rm -rf "$$tmp"' EXIT && chmod 777 "$$tmp" && \
	  echo "fetching libcgal-demo (apt-get download) for its meshes" && \
	  (cd "$$tmp" && { apt-get download -qq libcgal-demo 2>/dev/null || \
	     { [ "$$(id -u)" -eq 0 ] && apt-get update -qq && apt-get download -qq libcgal-demo; }; }) && \
	  dpkg-deb --fsys-tarfile "$$tmp"/libcgal-demo_*.deb | \
	    tar -xO ./usr/share/doc/libcgal-dev/data.tar.gz > "$$tmp/data.tar.gz" && \
	  tar -xzf "$$tmp/data.tar.gz" -C "$$tmp" $(addprefix data/meshes/,$(MODEL_FILES)) && \
	  cp $(addprefix "$$tmp"/data/meshes/,$(MODEL_FILES)) $(MODELS_DIR)/ && \
	  touch $@ && echo "models in $(MODELS_DIR): $(MODEL_FILES)"

# The README's first command: reconstruct the bunny with Proximity Count for 20 views, print
# the per-iteration table, and write the run's JSON and a coverage plot to $(DEMO_DIR).
DEMO_DIR ?= demo-output
# Debian's interpreter, which has python3-matplotlib (not whatever `python3` is first on PATH).
PYTHON ?= /usr/bin/python3
demo: build models
	@mkdir -p $(DEMO_DIR)
	$(BUILD_DIR)/apps/nbv reconstruct --model bunny --metric pc --iterations 20 --seed 0 \
	  --json $(DEMO_DIR)/bunny_pc.json
	$(PYTHON) scripts/plot_reconstruction.py $(DEMO_DIR)/bunny_pc.json --out $(DEMO_DIR)/bunny_pc.png
	@echo "demo: the run is in $(DEMO_DIR)/bunny_pc.json, its coverage and entropy plot in $(DEMO_DIR)/bunny_pc.png"

bench: build models
	$(BUILD_DIR)/bench/nbv_bench_sensor --benchmark_counters_tabular=true
	$(BUILD_DIR)/bench/nbv_bench_kernels --benchmark_counters_tabular=true
	$(BUILD_DIR)/bench/nbv_bench_grid --benchmark_counters_tabular=true
	$(BUILD_DIR)/bench/nbv_bench_ig --benchmark_counters_tabular=true

clean:
	rm -rf $(BUILD_DIR)
