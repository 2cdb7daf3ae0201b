# flowplan: the two commands of the README are `make demo` and `make test`.
BUILD ?= build
JOBS ?= $(shell nproc)
FLOWPLAN := $(BUILD)/apps/flowplan/flowplan

.PHONY: deps build demo test test-all bench clean

deps:
	./scripts/install_deps.sh

build: deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release
	cmake --build $(BUILD) -j $(JOBS)

# Generate the particle dataset, train, evaluate stitching, export, plot.
demo: build
	FLOWPLAN=$(FLOWPLAN) ./scripts/demo.sh

# Unit, reference and smoke tests (benchmarks excluded).
test: build
	ctest --test-dir $(BUILD) -LE bench --output-on-failure

bench: build
	ctest --test-dir $(BUILD) -L bench --output-on-failure -V

clean:
	rm -rf $(BUILD)
