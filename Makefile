# flowplan: the two commands of the README are `make demo` and `make test`.
BUILD ?= build
JOBS ?= $(shell nproc)
FLOWPLAN := $(BUILD)/apps/flowplan/flowplan

.PHONY: deps configure build demo test test-long bench fuzz sanitize sanitize-thread clean

deps:
	./scripts/install_deps.sh

configure: deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j $(JOBS)

# Generate the particle datasets, train, evaluate stitching, export, plot.
demo: configure
	cmake --build $(BUILD) -j $(JOBS) --target flowplan
	FLOWPLAN=$(FLOWPLAN) ./scripts/demo.sh

# Unit, reference and smoke tests (benchmarks and long tests excluded), one per
# core: each test works in its own scratch folder.
test: build
	ctest --test-dir $(BUILD) -LE 'bench|long' --output-on-failure -j $(JOBS)

# The end-to-end tests too long for the default run (label `long`).
test-long: build
	ctest --test-dir $(BUILD) -L long --output-on-failure -j $(JOBS)

# The fuzz targets (fuzz/) under libFuzzer with ASan and UBSan, each for
# FUZZ_SECONDS, in their own Clang build folder.
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 600
fuzz:
	./scripts/install_deps.sh --fuzz
	cmake -S . -B $(FUZZ_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
	  -DCMAKE_CXX_COMPILER=clang++ -DFLOWPLAN_FUZZ=ON -DFLOWPLAN_FUZZ_SECONDS=$(FUZZ_SECONDS)
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target flowplan_fuzz_targets
	ctest --test-dir $(FUZZ_BUILD) -L fuzz --output-on-failure -j $(JOBS)

# The default test suite built with AddressSanitizer, LeakSanitizer and
# UndefinedBehaviorSanitizer; the threaded parts' tests with ThreadSanitizer.
ASAN_BUILD ?= build-asan
TSAN_BUILD ?= build-tsan
sanitize: deps
	cmake -S . -B $(ASAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFLOWPLAN_SANITIZE=address
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	./scripts/sanitize.sh address $(ASAN_BUILD) -j $(JOBS)

sanitize-thread: deps
	cmake -S . -B $(TSAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFLOWPLAN_SANITIZE=thread
	cmake --build $(TSAN_BUILD) -j $(JOBS)
	./scripts/sanitize.sh thread $(TSAN_BUILD) -j $(JOBS)

bench: build
	ctest --test-dir $(BUILD) -L bench --output-on-failure -V

clean:
	rm -rf $(BUILD)
