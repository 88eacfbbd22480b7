# occ_improve: `make demo` and `make test` install what is missing, configure, build and run.
BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
INSTALL_DIR ?= $(CURDIR)/$(BUILD_DIR)/_install
CMAKE_FLAGS ?=
# VTK is not needed by our PCL components; leaving it out halves configure time.
CONFIGURE = cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) -DCMAKE_DISABLE_FIND_PACKAGE_VTK=TRUE \
            -DCMAKE_INSTALL_PREFIX=$(INSTALL_DIR) $(CMAKE_FLAGS)

.PHONY: all deps configure build test demo bench segment-eval consumer-test install clean fuzz test-sanitize

all: build

deps:
	./scripts/install-deps.sh

configure: deps
	$(CONFIGURE) >/dev/null

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)
	$(MAKE) --no-print-directory consumer-test

demo: build
	./scripts/demo.sh $(BUILD_DIR)

bench: configure
	cmake --build $(BUILD_DIR) -j $(JOBS) --target benchmarks
	./scripts/bench.sh $(BUILD_DIR)

# Our segmentation and PCL's on the labelled mOSD clouds (docs/SEGMENTATION.md).
DATA_DIR ?= $(CURDIR)/../shared/data
segment-eval: build
	$(BUILD_DIR)/pcl_tools/occ_segment_eval $(DATA_DIR)/segmentation/mosd_learn/*.pcd

install: build
	cmake --install $(BUILD_DIR) --prefix $(INSTALL_DIR) >/dev/null

# Builds tests/consumer against the installed package (find_package(occ_improve CONFIG)) and runs it.
consumer-test: install
	cmake -S tests/consumer -B $(BUILD_DIR)/consumer -DCMAKE_PREFIX_PATH=$(INSTALL_DIR) \
	      -DCMAKE_DISABLE_FIND_PACKAGE_VTK=TRUE >/dev/null
	cmake --build $(BUILD_DIR)/consumer -j $(JOBS)
	$(BUILD_DIR)/consumer/occ_improve_consumer

# The suite under ASan + UBSan in its own build dir. Third-party reports are suppressed by the files in
# tests/sanitize/ (each entry says why); every report in our code ends the test that raised it.
SANITIZE_BUILD_DIR ?= build-sanitize
SANITIZE_FLAGS = -fsanitize=address,undefined -fno-omit-frame-pointer
# Eigen's inline allocator switches to a hand-made aligned malloc when __SANITIZE_ADDRESS__ is defined;
# the prebuilt PCL's copies do not, and the linker mixes the two (PCL then frees what our copy allocated:
# bad-free, heap-buffer-overflow). Undefining the macro keeps one allocator; ASan still instruments all.
test-sanitize: deps
	cmake -S . -B $(SANITIZE_BUILD_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_DISABLE_FIND_PACKAGE_VTK=TRUE \
	      -DOCC_IMPROVE_BUILD_BENCHMARKS=OFF -DCMAKE_CXX_FLAGS="$(SANITIZE_FLAGS) -U__SANITIZE_ADDRESS__" \
	      -DCMAKE_EXE_LINKER_FLAGS="$(SANITIZE_FLAGS)" -DCMAKE_SHARED_LINKER_FLAGS="$(SANITIZE_FLAGS)" >/dev/null
	cmake --build $(SANITIZE_BUILD_DIR) -j $(JOBS)
	cd $(SANITIZE_BUILD_DIR) && \
	  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/sanitize/lsan.supp:print_suppressions=0 \
	  UBSAN_OPTIONS=suppressions=$(CURDIR)/tests/sanitize/ubsan.supp:halt_on_error=1:print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS)

# One fuzz target per parser, FUZZ_SECONDS each (tests/fuzz/README.md): libFuzzer under clang when
# it can be installed (build dir $(FUZZ_BUILD_DIR)), else the built-in mutation driver in $(BUILD_DIR).
FUZZ_SECONDS ?= 60
FUZZ_BUILD_DIR ?= build-fuzz
fuzz:
	./scripts/install-deps.sh fuzz || echo "fuzz: clang/libFuzzer not installable: using the built-in mutation driver"
	BUILD_DIR=$(BUILD_DIR) FUZZ_BUILD_DIR=$(FUZZ_BUILD_DIR) FUZZ_SECONDS=$(FUZZ_SECONDS) JOBS=$(JOBS) \
	  CONFIGURE="$(CONFIGURE)" ./scripts/fuzz.sh

clean:
	rm -rf $(BUILD_DIR) $(FUZZ_BUILD_DIR) $(SANITIZE_BUILD_DIR)
