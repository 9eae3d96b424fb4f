# sarmap: the whole set-up is `make demo` or `make test` on a fresh Debian machine.
# Each target installs missing Debian packages (apt-get, via sudo when not root), configures
# (CMake + Ninja + ccache), builds incrementally, then runs.

BUILD_DIR  ?= build
BUILD_TYPE ?= Release
JOBS       ?= $(shell nproc 2>/dev/null || echo 2)
CTEST_ARGS ?=

# Build tools and libraries (ARCHITECTURE.md), and tools the tests and demo run.
PACKAGES = cmake ninja-build ccache pkg-config g++ python3 \
  liblcm-dev liblcm-bin libeigen3-dev libyaml-cpp-dev libzstd-dev zlib1g-dev \
  libgtest-dev libgmock-dev libbenchmark-dev \
  libopencv-dev libopencv-contrib-dev libpcl-dev libceres-dev libsuitesparse-dev \
  libopenni2-dev libpocketsphinx-dev pocketsphinx-en-us libfftw3-dev libsndfile1-dev \
  libasound2-dev libssl-dev libcpp-httplib-dev nlohmann-json3-dev \
  librosbag-storage-dev libstd-msgs-dev libgeometry-msgs-dev libsensor-msgs-dev libnav-msgs-dev \
  libtf2-msgs-dev libvisualization-msgs-dev libgdal-dev gdal-bin \
  iproute2 iptables util-linux espeak-ng flite sox chromium clang-14 libclang-rt-14-dev
# Java types for lcm-spy: installed when available, never required.
OPTIONAL_PACKAGES = liblcm-java default-jdk-headless

# ccache hits across clones in different directories (CI builds a fresh clone).
export CCACHE_BASEDIR := $(CURDIR)
export CCACHE_NOHASHDIR := 1

SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: all deps configure build test bench bench-missions demo demo-hostile fuzz format docs clean help

all: build

help:
	@echo "make demo    run the stack on the simulated incident site and write a mission report"
	@echo "make demo-hostile  the same mission under attack: a hostile publisher on every channel"
	@echo "             (sarmap-net-fuzz) and 10 % datagram loss, in the demo's network namespace"
	@echo "make test    build and run every test (unit + multi-process) with CTest"
	@echo "make bench   build and run every benchmark (prints figures)"
	@echo "make bench-missions  autonomous missions on generated sites with people detection and the sound chain,"
	@echo "             frontier vs sound_guided (MISSION_SITES=6, MISSION_MODES=frontier,sound_guided)"
	@echo "make fuzz    libFuzzer on the decoding of every message type (FUZZ_SECONDS=300), then the"
	@echo "             network fuzzer against the running stack (NET_FUZZ_SECONDS=60, NET_FUZZ_RATE=2000)"
	@echo "make docs    rewrite the READMEs' configuration tables from the options and config/*.yaml"
	@echo "make build   just build;  make deps  just install packages;  make clean"

# Installs only what is missing, so a second run installs nothing.
deps:
	@missing=""; for p in $(PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "sarmap: installing missing Debian packages:$$missing"; \
	  $(SUDO) apt-get update -q && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -q --no-install-recommends $$missing || exit 1; \
	  optional=""; for p in $(OPTIONAL_PACKAGES); do \
	    dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || optional="$$optional $$p"; \
	  done; \
	  [ -z "$$optional" ] || DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -q --no-install-recommends $$optional \
	    || echo "sarmap: optional packages$$optional not installed (lcm-spy types skipped)"; \
	fi

$(BUILD_DIR)/build.ninja:
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE)

configure: deps $(BUILD_DIR)/build.ninja

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS) $(CTEST_ARGS)

bench: build
	cmake --build $(BUILD_DIR) --target bench

# Autonomous missions in simulated time on generated sites (components/mission/README.md).
MISSION_SITES ?= 6
MISSION_MODES ?= frontier,sound_guided
MISSION_SECONDS ?= 600
bench-missions: build
	$(BUILD_DIR)/bin/sarmap-mission-bench --sites $(MISSION_SITES) --modes $(MISSION_MODES) \
	  --duration $(MISSION_SECONDS) --out out/mission-bench

demo: build
	launch-scripts/demo.sh $(BUILD_DIR)

# The demo attacked (launch-scripts/demo.sh, DEMO_HOSTILE): the report must still find the
# people, and no process may crash.
demo-hostile: build
	DEMO_HOSTILE=1 launch-scripts/demo.sh $(BUILD_DIR)

# Fuzzing (components/common/README.md, "Fuzzing"): libFuzzer with clang in a separate build directory, then the
# network fuzzer's multi-process test with a longer flood.
FUZZ_DIR ?= build-fuzz
FUZZ_SECONDS ?= 300
NET_FUZZ_SECONDS ?= 60
NET_FUZZ_RATE ?= 2000
fuzz: configure
	tests/fuzz/run_libfuzzer.sh $(BUILD_DIR) $(FUZZ_DIR) $(FUZZ_SECONDS)
	cmake --build $(BUILD_DIR) --target net_fuzz_test
	@echo "== the network fuzzer against the running stack: $(NET_FUZZ_RATE) datagrams/s for $(NET_FUZZ_SECONDS) s"
	SARMAP_BIN_DIR=$(abspath $(BUILD_DIR))/bin SARMAP_SOURCE_DIR=$(CURDIR) \
	  tests/harness/sarmap-netns $(BUILD_DIR)/bin/net_fuzz_test \
	  --gtest_filter=NetFuzzTest.EveryNodeSurvivesAHostilePublisherOnEveryChannel \
	  --flood-seconds $(NET_FUZZ_SECONDS) --flood-rate $(NET_FUZZ_RATE)

# The READMEs' configuration tables, from the options' help strings and config/*.yaml.
docs: build
	$(BUILD_DIR)/bin/sarmap-options-doc --root . --write

format:
	find components log-tools tests -name '*.h' -o -name '*.cc' | xargs clang-format -i

clean:
	rm -rf $(BUILD_DIR) $(FUZZ_DIR)
