# GlassFusion: the two set-up commands are `make demo` and `make test`.
# Both install the Debian packages the build needs (only those missing), then build.

BUILD_DIR ?= build
DEMO_OUT  ?= demo-out
JOBS      ?= $(shell nproc)
CMAKE_FLAGS ?=

# Every Debian (bookworm) package the build, the tests and the measuring scripts need (the ROS 1
# bag library and message headers: RealSense .bag input; libavformat: Azure Kinect .mkv input;
# nodejs: bundling the reports' 3D view from npm packages, and testing it; chromium:
# the test that renders the demo report in a headless browser; slurm-wlm and munge: the test that
# runs `batch --slurm` on a one-node cluster on loopback).
DEB_PACKAGES := cmake make g++ pkg-config \
  libopencv-dev libeigen3-dev libceres-dev libpcl-dev \
  libopenni2-dev libfreenect-dev \
  librosbag-storage-dev libroscpp-core-dev libsensor-msgs-dev libgeometry-msgs-dev \
  libstd-msgs-dev libavformat-dev \
  libcli11-dev nlohmann-json3-dev libspdlog-dev \
  libgtest-dev libgmock-dev libbenchmark-dev \
  python3-numpy python3-opencv python3-open3d \
  colmap chromium slurm-wlm munge nodejs

SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

SANITIZE_DIR ?= build-asan
TSAN_DIR ?= build-tsan

.PHONY: all deps configure build test sanitize tsan demo clean format

all: build

deps:
	@missing=""; \
	for p in $(DEB_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "deps: installing$$missing"; \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get update -q && \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends $$missing; \
	else \
	  echo "deps: all $(words $(DEB_PACKAGES)) Debian packages present"; \
	fi && \
	if ! command -v npm >/dev/null; then \
	  echo "deps: installing npm (Debian's nodejs comes without it)"; \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends npm; \
	fi

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release -DGF_BUILD_TESTS=ON -DGF_BUILD_BENCHMARKS=ON $(CMAKE_FLAGS)

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS) --repeat after-timeout:2

# The sanitizer builds: -O1 with line tables only (-g1), which is what the sanitizers' reports
# need (function, file and line) and compiles in half the time of RelWithDebInfo's -O2 -g.
SANITIZER_BUILD := -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG"

# The unit tests (not the end-to-end tests, label "tests", which it does not build) built with
# AddressSanitizer and UndefinedBehaviorSanitizer; CI runs it after `make test`. Left out: the
# loop-closure suite and the reproducibility test, whole synthetic captures replayed (many times
# over), which ASan runs 5-8x slower and `make test` and `make tsan` run; the pipeline's other
# whole-run tests stay.
sanitize: deps
	cmake -S . -B $(SANITIZE_DIR) $(SANITIZER_BUILD) -DGF_SANITIZE=ON \
	  -DGF_BUILD_TESTS=ON -DGF_BUILD_BENCHMARKS=OFF $(CMAKE_FLAGS)
	cmake --build $(SANITIZE_DIR) -j $(JOBS) --target gf_unit_tests
	cd $(SANITIZE_DIR) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp \
	  ctest --output-on-failure -j $(JOBS) -LE '^tests$$' --repeat after-timeout:2 \
	  -E '^pipeline/loop_closure[.]|HoweverFastEachStageRuns'

# The pipeline's tests (whole reconstructions in-process, every stage in its own thread) built with
# ThreadSanitizer; CI runs it after `make sanitize`. Tests that run the same threads as their
# neighbours (a contained fill failure, a loop without drift, the keyframes' completion from the
# map, which runs on the caller's thread after the stages have joined, and the reproducibility
# tests, which run whole captures twice with one stage held back) are left out: TSan runs them
# 25-45x slower. The stages' hand-overs they use (fills and corrections at fixed points) run in
# the tests that stay. OpenCV's parallel loops run on the calling
# thread there (tests/tsan_serial_opencv.cc): its TBB pool is not instrumented.
tsan: deps
	cmake -S . -B $(TSAN_DIR) $(SANITIZER_BUILD) -DGF_TSAN=ON \
	  -DGF_BUILD_TESTS=ON -DGF_BUILD_BENCHMARKS=OFF \
	  -DCMAKE_GTEST_DISCOVER_TESTS_DISCOVERY_MODE=PRE_TEST $(CMAKE_FLAGS)
	cmake --build $(TSAN_DIR) -j $(JOBS) --target pipeline_reconstruction pipeline_loop_closure \
	  pipeline_fill_stage pipeline_settings pipeline_run_sink
	cd $(TSAN_DIR) && TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$(CURDIR)/tests/tsan.supp" \
	  ctest --output-on-failure -j $(JOBS) -R '^pipeline/' --repeat after-timeout:2 \
	  -E 'AFillFailureIsContained|CostsNothingWithoutDrift|TheMapCompletesEachKeyframeFromItsFills|HoweverFastEachStageRuns|AtFixedPointsOfTheSequence|TheReportIsWrittenLast|StopDuringTheMapCompletion'

# Builds the command alone (not the tests and benchmarks), then runs the demo.
demo: configure
	cmake --build $(BUILD_DIR) -j $(JOBS) --target glassfusion
	$(BUILD_DIR)/apps/glassfusion demo --out $(DEMO_OUT)

format:
	find acquisition registration fill surfels pipeline apps datasets eval report runs batch tests -name '*.h' -o -name '*.cc' | xargs clang-format -i

clean:
	rm -rf $(BUILD_DIR) $(SANITIZE_DIR) $(TSAN_DIR) $(DEMO_OUT)
