# occ_improve: `make demo` and `make test` install what is missing, configure, build and run.
BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
INSTALL_DIR ?= $(CURDIR)/$(BUILD_DIR)/_install
CMAKE_FLAGS ?=
# The Python bindings are built for (and tested with) Debian's interpreter, whose numpy/pytest/matplotlib
# install-deps.sh installs; a `python3` earlier on PATH (pyenv, conda) may lack them.
PYTHON ?= $(shell test -x /usr/bin/python3 && echo /usr/bin/python3 || command -v python3)
# VTK is needed only by occ_improve_live -view (PCL's ImageViewer), which `make test` tests under Xvfb:
# on by default. VIEW=OFF leaves VTK unsearched (a fresh configure takes about half as long) and builds
# occ_improve_live without the window.
VIEW ?= ON
ifeq ($(VIEW),OFF)
VIEW_FLAGS = -DCMAKE_DISABLE_FIND_PACKAGE_VTK=TRUE -DOCC_IMPROVE_WITH_VIEW=OFF
else
# FALSE, not left out: a build folder configured before with VTK hidden keeps that in its cache.
VIEW_FLAGS = -DCMAKE_DISABLE_FIND_PACKAGE_VTK=FALSE -DOCC_IMPROVE_WITH_VIEW=ON
endif
CONFIGURE = cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(VIEW_FLAGS) \
            -DCMAKE_INSTALL_PREFIX=$(INSTALL_DIR) -DPython_EXECUTABLE=$(PYTHON) $(CMAKE_FLAGS)

.PHONY: all deps configure build test demo bench segment-eval map-eval select-eval filter-eval consumer-test install clean \
        python-wheel-test python-bench python-sample fuzz test-sanitize

all: build

deps:
	./scripts/install-deps.sh

configure: deps
	$(CONFIGURE) >/dev/null

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

# The whole suite, the find_package consumer build included (a ctest test); the real-data tests read
# DATA_DIR (below) and skip, saying so, where it is absent.
test: build
	cd $(BUILD_DIR) && OCC_IMPROVE_DATA_DIR=$(DATA_DIR) ctest --output-on-failure -j $(JOBS)

demo: build
	./scripts/demo.sh $(BUILD_DIR)

bench: configure
	cmake --build $(BUILD_DIR) -j $(JOBS) --target benchmarks
	./scripts/bench.sh $(BUILD_DIR)

# The real data: DATA_DIR=..., else the environment's OCC_IMPROVE_DATA_DIR, else ../shared/data beside the
# checkout; the tests, test-sanitize and the evaluations all read it.
DATA_DIR ?= $(or $(OCC_IMPROVE_DATA_DIR),$(CURDIR)/../shared/data)

# Our segmentation and PCL's on the labelled mOSD clouds (docs/SEGMENTATION.md).
segment-eval: build
	$(BUILD_DIR)/pcl_tools/occ_segment_eval $(DATA_DIR)/segmentation/mosd_learn/*.pcd

# The improvement map on real frames, default preset: known against unknown rays, ranking and regions,
# repeated frames, grid end (tests/pcl/test_map_quality.cpp prints the table and checks the targets).
map-eval: build
	OCC_IMPROVE_DATA_DIR=$(DATA_DIR) $(BUILD_DIR)/tests/test_map_quality

# Selective acquisition: strategies (a)-(f) on real frames and the sample (docs/SELECTIVE.md).
SELECT_SCENES = sample $(DATA_DIR)/kinect/pcl_tutorials/pairwise/capture0001.pcd \
  $(DATA_DIR)/kinect/pcl_test/office1.pcd $(DATA_DIR)/kinect/pcl_test/five_people.pcd \
  $(DATA_DIR)/segmentation/mosd_learn/learn0.pcd $(DATA_DIR)/kinect/pcl_test/milk_cartoon_all_small_clorox.pcd \
  $(DATA_DIR)/sequences/7scenes_redkitchen/frames/frame-000150.depth.png
SELECT_OUT ?= out/select
select-eval: build
	$(BUILD_DIR)/pcl_tools/occ_select_eval $(SELECT_SCENES) -o $(SELECT_OUT) -overwrite -frames 3
	$(PYTHON) scripts/plot_select.py $(SELECT_OUT)

# The same question in a PCL pipeline: ImprovementFilter against pcl::RandomSample and pcl::VoxelGrid over
# the posed 7-Scenes sequence, scored against the map from all points (docs/SELECTIVE.md).
FILTER_OUT ?= out/filter
filter-eval: build
	mkdir -p $(dir $(FILTER_OUT))  # the tool creates its own folder, not its parents
	$(BUILD_DIR)/pcl_tools/occ_filter_eval $(DATA_DIR)/sequences/7scenes_redkitchen/frames -o $(FILTER_OUT) -overwrite
	$(PYTHON) scripts/plot_filter.py $(FILTER_OUT)

install: build
	cmake --install $(BUILD_DIR) --prefix $(INSTALL_DIR) >/dev/null

# Only the consumer test: tests/consumer against this build installed in a scratch prefix, asking once
# for the core alone (PCL, OctoMap and libpng made unfindable), once for io and once for every component.
consumer-test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -R Consumer

# pip builds the wheel from this checkout (scikit-build-core, pyproject.toml), installs it in a fresh
# virtual environment and runs the pytest suite against the installed package (docs/PYTHON.md).
python-wheel-test: deps
	./scripts/python-wheel-test.sh $(PYTHON) $(BUILD_DIR)/wheel-test

# A full 640x480 frame through Python against the same calls timed in C++ (docs/PYTHON.md, "Speed").
python-bench: build
	PYTHONPATH=$(BUILD_DIR)/python $(PYTHON) tests/bench/bench_python.py
	PYTHONPATH=$(BUILD_DIR)/python $(PYTHON) tests/bench/bench_python.py --cpu

# The sample: a real 7-Scenes frame's improvement map over its colour image, saved to out/python/.
python-sample: build
	PYTHONPATH=$(BUILD_DIR)/python MPLBACKEND=Agg $(PYTHON) samples/python/improvement_overlay.py --out out/python

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
	cd $(SANITIZE_BUILD_DIR) && OCC_IMPROVE_DATA_DIR=$(DATA_DIR) \
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
