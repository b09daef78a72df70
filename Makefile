# Quick start: `make demo` builds and runs the headline experiment, `make test` builds
# and runs the whole test suite. Both install the Debian packages they need first.

BUILD_DIR   ?= build
JOBS        ?= $(shell nproc)
DEB_PACKAGES = cmake g++ make pkg-config libeigen3-dev libopenblas-dev liblapacke-dev \
               libcli11-dev nlohmann-json3-dev libgtest-dev libbenchmark-dev \
               libopenmpi-dev openmpi-bin libscalapack-openmpi-dev
# The Python package (built by `make build` and `make test`, not needed by `make demo`).
PYTHON_PACKAGES = pybind11-dev python3-dev python3-numpy
# Only the tests need these: Chromium loads the HTML reports (layout, no script, no request);
# pytest, torch and SciPy run the Python package's tests and examples; venv, pip, setuptools and
# wheel make the offline `pip install .` into a fresh venv (docs/python.md).
TEST_PACKAGES = chromium python3-pytest python3-torch python3-scipy python3-venv python3-pip \
                python3-setuptools python3-wheel

SANITIZE_DIR ?= build-sanitize

# OpenBLAS chooses its kernels from the CPU models it knows; on a newer one (Debian 12's 0.3.21 on
# a Xeon with AVX-512 FP16) it runs its generic SSE3 kernels, several times slower
# (docs/performance.md). Unless set already, the targets here ask for the kernels the CPU's
# AVX-512 or AVX2 can run; programs run outside make print a note instead (blas_core_note()).
ifeq ($(origin OPENBLAS_CORETYPE),undefined)
OPENBLAS_CORETYPE := $(shell grep -qw avx512bw /proc/cpuinfo 2>/dev/null && echo SkylakeX || \
                       { grep -qw avx2 /proc/cpuinfo 2>/dev/null && echo Haswell; })
endif
ifneq ($(OPENBLAS_CORETYPE),)
export OPENBLAS_CORETYPE
endif

RESULTS_DIR ?= docs/results
EXPERIMENTS  = scaled-toy sensitivity comparison hig-toy sin-rotation heat-inverse oscillators \
               quantum-dipole poisson sip-poisson time-reversal

.PHONY: all deps deps-test deps-python configure build demo test test-sanitize bench bench-mpi results clean

all: build

# Installs the Debian packages of $(1) that are missing, so repeated runs cost one dpkg query.
install_missing = @missing=$$(for p in $(1); do \
	    dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; \
	  done); \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:" $$missing; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing; \
	fi

deps:
	$(call install_missing,$(DEB_PACKAGES))

deps-test:
	$(call install_missing,$(TEST_PACKAGES))

deps-python:
	$(call install_missing,$(PYTHON_PACKAGES))

# The Python package is built for Debian's interpreter, which has the Debian numpy and torch.
configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3

# Everything: the libraries, the CLI, the Python package, the tests, benchmarks and examples.
build: deps-python
	$(MAKE) configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

# Builds only the CLI it runs. Each demo run gets a folder of its own
# (runs/hig-toy-<timestamp>); earlier ones are kept.
demo: configure
	cmake --build $(BUILD_DIR) --target physgrad_cli -j $(JOBS)
	$(BUILD_DIR)/physgrad run hig-toy --lambda 0.01

test: build deps-test
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

# Micro-benchmarks of the learning step (about 3 minutes): bench/results.json, then the tables
# of docs/performance.md (between its bench:begin/bench:end marks) and its size-sweep figure.
bench: build
	$(BUILD_DIR)/bench/physgrad_bench --benchmark_out=bench/results.json --benchmark_out_format=json
	$(BUILD_DIR)/bench/bench_report bench/results.json docs/performance.md docs/performance_size_sweep.svg

# Step time of data-parallel training with 1 and 2 ranks (docs/distributed.md).
bench-mpi: build
	bench/distributed_steps.sh $(BUILD_DIR) 2
	bench/distributed_hig.sh $(BUILD_DIR) 2 3

# Every reference experiment with its defaults (the learning ones on their default seeds; the
# 64×64 U-net experiments, heat-inverse and sip-poisson, take the longest): figures, summaries and the
# printed tables in $(RESULTS_DIR), indexed with the reports' captions in $(RESULTS_DIR)/README.md.
results: build
	rm -rf $(RESULTS_DIR) && mkdir -p $(RESULTS_DIR)
	for e in $(EXPERIMENTS); do \
	  $(BUILD_DIR)/physgrad run $$e --out $(RESULTS_DIR)/$$e > $(RESULTS_DIR)/$$e.txt || exit 1; \
	done
	scripts/results_index.sh $(RESULTS_DIR) $(EXPERIMENTS) > $(RESULTS_DIR)/README.md
	rm -f $(RESULTS_DIR)/*/metrics.csv $(RESULTS_DIR)/*/report.html $(RESULTS_DIR)/*/networks.json

# The whole suite under AddressSanitizer + UndefinedBehaviorSanitizer (any report fails it).
test-sanitize: deps deps-test
	cmake -S . -B $(SANITIZE_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPHYSGRAD_SANITIZE=ON
	cmake --build $(SANITIZE_DIR) -j $(JOBS)
	cd $(SANITIZE_DIR) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS)

clean:
	rm -rf $(BUILD_DIR) $(SANITIZE_DIR)
