# The README's two commands. Both install missing Debian packages first (tools/ops/setup.sh).
#   make demo  - build and run the main job: a simulated 3D scan and map (out/)
#   make test  - build and run every test through CTest
BUILD ?= build
JOBS ?= 2
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

.PHONY: all setup build demo test bench clean

all: build

setup:
	@bash tools/ops/setup.sh

$(BUILD)/Makefile: CMakeLists.txt
	cmake -S . -B $(BUILD) $(CMAKE_FLAGS)

build: setup $(BUILD)/Makefile
	cmake --build $(BUILD) -j$(JOBS)

demo: build
	$(BUILD)/bin/sweepmap demo --out out

test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) --timeout 900

bench: build
	$(BUILD)/bin/sweepmap bench --work $(BUILD)/bench

clean:
	rm -rf $(BUILD) out
