# nbv: the two commands of the README are `make demo` (arrives with the planner) and `make test`.
# Every target installs what is missing first (Debian packages only).

BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)

# Debian packages the project needs to build, test and benchmark. python3-imath only
# because Debian's Imath CMake config (pulled in by FindOpenVDB) names its library.
DEB_PACKAGES := build-essential cmake ccache pkg-config \
  libeigen3-dev libtbb-dev libopenvdb-dev libopenvdb-tools libboost-iostreams-dev \
  liboctomap-dev libcli11-dev libgtest-dev libbenchmark-dev \
  python3-imath

.PHONY: deps configure build test bench clean

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

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

bench: build
	$(BUILD_DIR)/bench/nbv_bench_kernels --benchmark_counters_tabular=true
	$(BUILD_DIR)/bench/nbv_bench_grid --benchmark_counters_tabular=true

clean:
	rm -rf $(BUILD_DIR)
