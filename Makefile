# The README's commands. Each installs missing Debian packages first (tools/ops/setup.sh).
#   make demo           - build and run the main job: a simulated 3D scan and map (out/)
#   make test           - build and run every test through CTest (labels unit and e2e), then
#                         test-sanitize: what CI runs (.ci/run)
#   make test-unit      - build only the unit tests and run them (ctest -L unit)
#   make test-sanitize  - the unit tests under AddressSanitizer (with LeakSanitizer) and
#                         UndefinedBehaviorSanitizer, in their own build tree: any report fails
#   make fuzz           - each protocol decoder under libFuzzer (clang, ASan+UBSan) for
#                         FUZZ_RUNS inputs (default 10 M) in build-fuzz/; new inputs that
#                         reach new code are added to build-fuzz/corpus/
#   make pi             - cross-build the on-board tree (sweepmap-motor, -lidar, -odometry, no
#                         PCL/Ceres/OctoMap) for arm64 in build-pi/ and run its unit tests under
#                         qemu-aarch64-static (setup.sh --pi installs the cross toolchain)
#   make package        - Debian packages with CPack: sweepmap (amd64, everything) in build/,
#                         sweepmap-onboard (arm64, on-board processes + systemd units) in build-pi/
#   make format         - clang-format every C++ file in place (.clang-format)
#   make format-check   - fail, listing them, when files are not formatted (part of make test)
#   make docs           - regenerate docs/reference/{cli,config,channels}.md from the built
#                         commands and the code (the test docs_reference_is_current checks them)
BUILD ?= build
SANITIZE_BUILD ?= build-sanitize
FUZZ_BUILD ?= build-fuzz
PI_BUILD ?= build-pi
FUZZ_RUNS ?= 10000000
FUZZ_PROTOCOLS = scip x4 rplidar hi219 wheelboard lcm_datagram lcm_message
JOBS ?= 2
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release
# The on-board tree cross-compiled for arm64, through ccache (the cross compiler's entries
# are its own: a first build is a cold one).
PI_CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release -DSWEEPMAP_ONBOARD=ON \
                  --toolchain cmake/toolchain-aarch64-linux-gnu.cmake \
                  -DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache
# -O1: sanitizer checks cost less than at -O0, and the stack traces stay readable. -g1: the
# line tables only, which is all a sanitizer's stack trace needs (file:line, inlined frames);
# measured on two of the heaviest files, it compiles in 0.6-0.7 of -g's time into objects a
# third to a quarter of the size.
SANITIZE_CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Debug "-DCMAKE_CXX_FLAGS_DEBUG=-g1 -O1" \
                        -DSWEEPMAP_SANITIZE=ON -DSWEEPMAP_BUILD_TESTS=ON
CTEST = ctest --output-on-failure -j$(JOBS) --timeout 900
# Reports are fatal already (-fno-sanitize-recover=all, ASan's default); these add the
# stack trace of an undefined-behaviour report and keep leak checking on.
SANITIZE_ENV = ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

# Every tracked C++ source; generated lcm-gen headers live in the build tree, not here.
FORMAT_FILES = $(shell git ls-files '*.cpp' '*.hpp' 2>/dev/null)

.PHONY: all setup setup-pi build demo test test-costs test-unit test-sanitize fuzz pi pi-build package \
        format format-check bench bench-view docs clean bench-calib-seeds

all: build

setup:
	@bash tools/ops/setup.sh

setup-pi:
	@bash tools/ops/setup.sh --pi

$(BUILD)/Makefile: CMakeLists.txt
	cmake -S . -B $(BUILD) $(CMAKE_FLAGS)

$(PI_BUILD)/Makefile: CMakeLists.txt
	cmake -S . -B $(PI_BUILD) $(PI_CMAKE_FLAGS)

$(SANITIZE_BUILD)/Makefile: CMakeLists.txt
	cmake -S . -B $(SANITIZE_BUILD) $(SANITIZE_CMAKE_FLAGS)

build: setup $(BUILD)/Makefile
	cmake --build $(BUILD) -j$(JOBS)

demo: build
	$(BUILD)/bin/sweepmap demo --out out

test: build format-check
	cd $(BUILD) && $(CTEST)
	@$(MAKE) --no-print-directory test-sanitize

# The tests' costs ctest measured in build/ and build-sanitize/ (1 s or more) become the
# starting order of a fresh build folder's run (tests/CMakeLists.txt): run after `make test`.
test-costs:
	@for b in release:$(BUILD) sanitize:$(SANITIZE_BUILD); do \
	  f=$${b#*:}/Testing/Temporary/CTestCostData.txt; out=tests/ctest_costs/$${b%%:*}.txt; \
	  awk 'NF == 3 && $$3 >= 1.0 { printf "%s 1 %.1f\n", $$1, $$3 }' $$f | sort -k3 -rn > $$out; \
	  echo "---" >> $$out; echo "test-costs: $$(($$(wc -l < $$out) - 1)) tests in $$out"; \
	done

test-unit: setup $(BUILD)/Makefile
	cmake --build $(BUILD) -j$(JOBS) --target unit_tests
	cd $(BUILD) && $(CTEST) -L unit

# Only the unit tests' targets: neither the executables nor the e2e tests are built here.
test-sanitize: setup $(SANITIZE_BUILD)/Makefile
	cmake --build $(SANITIZE_BUILD) -j$(JOBS) --target unit_tests
	cd $(SANITIZE_BUILD) && $(SANITIZE_ENV) $(CTEST) -L unit

# libFuzzer: -max_len 2048 covers several packets of every protocol and a whole SCIP reply of a
# few hundred steps (15k inputs/s for SCIP under ASan+UBSan here); rss and per-input time
# limits turn unbounded memory or a hang into a failure. Each run prints its final stats.
fuzz: setup
	cmake -S . -B $(FUZZ_BUILD) -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
	      -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSWEEPMAP_FUZZ=ON -DSWEEPMAP_BUILD_TESTS=OFF
	cmake --build $(FUZZ_BUILD) -j$(JOBS) --target fuzz_targets
	@for p in $(FUZZ_PROTOCOLS); do \
	  mkdir -p $(FUZZ_BUILD)/corpus/$$p; \
	  echo "fuzz: $$p, $(FUZZ_RUNS) runs (log: $(FUZZ_BUILD)/fuzz_$$p.log)"; \
	  start=$$(date +%s); \
	  $(FUZZ_BUILD)/fuzz/fuzz_$$p -runs=$(FUZZ_RUNS) -max_len=2048 -rss_limit_mb=1024 \
	    -timeout=5 -print_final_stats=1 $(FUZZ_BUILD)/corpus/$$p fuzz/corpus/$$p \
	    > $(FUZZ_BUILD)/fuzz_$$p.log 2>&1; rc=$$?; \
	  grep -E "^(stat::number_of_executed_units|stat::peak_rss_mb|Done)" $(FUZZ_BUILD)/fuzz_$$p.log; \
	  echo "fuzz: $$p took $$(( $$(date +%s) - start )) s, exit $$rc"; \
	  if [ $$rc -ne 0 ]; then tail -40 $(FUZZ_BUILD)/fuzz_$$p.log; exit $$rc; fi; \
	done

# The unit tests run under qemu-aarch64-static (CMAKE_CROSSCOMPILING_EMULATOR in the toolchain
# file), GTest's test discovery too.
pi: pi-build
	cd $(PI_BUILD) && $(CTEST) -L unit

pi-build: setup-pi $(PI_BUILD)/Makefile
	cmake --build $(PI_BUILD) -j$(JOBS)

package: build pi-build
	cd $(BUILD) && cpack -G DEB
	cd $(PI_BUILD) && cpack -G DEB
	@ls -l $(BUILD)/*.deb $(PI_BUILD)/*.deb

format:
	clang-format -i $(FORMAT_FILES)

format-check: setup
	@bad=$$(for f in $(FORMAT_FILES); do clang-format --dry-run --Werror "$$f" >/dev/null 2>&1 || echo "$$f"; done); \
	if [ -n "$$bad" ]; then echo "format-check: not clang-formatted (run make format):"; echo "$$bad"; exit 1; fi; \
	echo "format-check: $(words $(FORMAT_FILES)) files formatted"

# The generated reference pages need only the commands, not the tests.
DOC_TARGETS = sweepmap sweepmap-motor sweepmap-lidar sweepmap-odometry sweepmap-assembler \
              sweepmap-mapper sweepmap-profiler
docs: setup $(BUILD)/Makefile
	cmake --build $(BUILD) -j$(JOBS) --target $(DOC_TARGETS)
	python3 tools/docs/generate_reference.py $(BUILD)/bin

bench: build
	$(BUILD)/bin/sweepmap bench --work $(BUILD)/bench
	$(BUILD)/bin/bench_net

# The view's figures in headless chromium beside a live rig-A run of 3 mode-7 sweeps (2 M
# points on screen): frame rate, latency from a sweep's end to its drawing, server CPU per
# client (tools/bench/bench_view.sh; 4-6 minutes, root).
bench-view: build
	bash tools/bench/bench_view.sh $(BUILD)/bin $(BUILD)/bench/view

# calib rig and the single-parameter commands on the same simulated logs of calib plan's
# recording, per seed and rig kind: errors, |error|/sigma, targets met, plots; rig B also
# evaluated on a lap of the loop with its calibrated rig file (tools/bench/calib_seeds.py;
# about 20 minutes for the three kinds and five seeds).
SEEDS ?= 1,2,3,4,5
bench-calib-seeds: build
	python3 tools/bench/calib_seeds.py $(BUILD)/bin $(BUILD)/bench/calib_seeds --seeds $(SEEDS)

clean:
	rm -rf $(BUILD) $(SANITIZE_BUILD) $(PI_BUILD) out
