# yarf: every entry point. Each target installs what is missing on a
# fresh Debian 12 (apt packages, a Python venv in .venv), then builds.
#   make render   build, start a local server, render the Cornell box
#   make test     build and run every test (C++ through ctest, then pytest)
#   make bench    the benchmarks

SHELL := /bin/bash
BUILD := build
VENV := .venv
PY := $(VENV)/bin/python
STAMPS := .stamps
SPP ?= 256
# yarfd refuses to run as root unless told to; a build machine or container
# where root is the only user says so for the servers tests and benchmarks start.
ifeq ($(shell id -u),0)
export YARF_ALLOW_ROOT ?= 1
endif

APT_PACKAGES := g++ cmake ninja-build pkg-config python3 python3-venv \
  libembree-dev libtbb-dev libopenimageio-dev openimageio-tools \
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc \
  libgtest-dev libtinyobjloader-dev libpugixml-dev zlib1g-dev clang-14 libclang-rt-14-dev \
  curl ca-certificates libnanoflann-dev libsqlite3-dev libssl-dev openssl nats-server chromium \
  libopenvdb-dev libboost-dev libxsimd-dev libosd-dev
# Mitsuba's LLVM variant and perf (bench/profile.py), for the benchmarks only.
BENCH_APT_PACKAGES := libllvm19 linux-perf

.PHONY: all deps venv profile build stubs lint render test fuzz bench clean

all: build

# Installs only the packages that are missing; quick when all are there.
define apt_install
	@missing=$$(for p in $(1); do dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "installing:" $$missing; \
	  SUDO=$$( [ $$(id -u) -eq 0 ] || echo sudo ); \
	  $$SUDO apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq --no-install-recommends \
	    -o DPkg::Lock::Timeout=600 $$missing; \
	fi
endef

deps:
	$(call apt_install,$(APT_PACKAGES))

$(STAMPS)/venv: requirements-dev.txt clients/python/pyproject.toml components/python/pyproject.toml | deps
	@mkdir -p $(STAMPS)
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q --disable-pip-version-check -r requirements-dev.txt
	$(PY) -m pip install -q --disable-pip-version-check -e clients/python
	$(PY) -m pip install -q --disable-pip-version-check -e components/python
	@touch $@

venv: $(STAMPS)/venv

# Python stubs from the IDL, generated at build time, never committed.
stubs: venv
	$(PY) -m grpc_tools.protoc -I proto --python_out=clients/python \
	  --grpc_python_out=clients/python --pyi_out=clients/python proto/yarf/v1/*.proto

# Profile-guided optimisation: yarfd and the plugins the training renders
# load (tools/profile_training.py --plugins), built once instrumented in
# $(BUILD)/profiling, render the training scenes, and the build proper is
# optimised for the branches and calls those renders took. Made with a
# build folder's first build; `make profile` makes a new one and has the
# next build recompile everything with it (until then a file changed since
# compiles without its stale profile).
PROFILE := $(abspath $(BUILD))/profile
profile: deps stubs
	@date -u +'%T profile'
	rm -rf $(PROFILE) $(BUILD)/profiling
	cmake -S . -B $(BUILD)/profiling -G Ninja -DCMAKE_BUILD_TYPE=Release \
	  -DYARF_PROFILE=generate -DYARF_PROFILE_DIR=$(PROFILE)
	cmake --build $(BUILD)/profiling -j2 --target yarfd $$($(PY) tools/profile_training.py --plugins)
	$(PY) tools/profile_training.py $(BUILD)/profiling/bin/yarfd
	rm -rf $(BUILD)/profiling
	@if [ -f $(BUILD)/build.ninja ]; then ninja -C $(BUILD) -t clean >/dev/null; fi
	touch $(PROFILE)/trained

build: deps stubs
	@test -f $(PROFILE)/trained || $(MAKE) --no-print-directory profile
	@date -u +'%T build'
	@grep -qs '^YARF_PROFILE:STRING=use' $(BUILD)/CMakeCache.txt || cmake -S . -B $(BUILD) -G Ninja \
	  -DCMAKE_BUILD_TYPE=Release -DYARF_PROFILE=use -DYARF_PROFILE_DIR=$(PROFILE)
	cmake --build $(BUILD) -j2
	components/go/build.sh

render: build
	@mkdir -p out
	$(VENV)/bin/yarf render scenes/cornell-box/scene.json -o out/cornell-box.exr --spp $(SPP)

# Python style: formatted and lint-clean (ruff).
lint: venv
	$(VENV)/bin/ruff format --check bench tests clients/python components/python deploy fuzz tools
	$(VENV)/bin/ruff check bench tests clients/python components/python deploy fuzz tools

# Each stage prints when it starts, so a slow or stalled run shows where.
test: build lint
	@date -u +'%T ctest'
	cd $(BUILD) && ctest --output-on-failure -j2
	@date -u +'%T go tests'
	components/go/test.sh
	@date -u +'%T pytest'
	$(PY) -m pytest -q --durations=15
	@date -u +'%T fuzz'
	$(MAKE) --no-print-directory fuzz
	@date -u +'%T done'

# The parsers of untrusted bytes under libFuzzer (clang, apart from the
# main build): FUZZ_RUNS inputs each, seeded with the test scenes (see
# fuzz/run.sh for runs of hours). Then Submit, mutated over its proto
# descriptors: SUBMIT_MUTANTS checked by yarfd's own checks, SUBMIT_RENDERS
# of the accepted ones rendered by a real yarfd.
# The defaults keep the stage's runs under a minute on two cores and still
# prove something: each harness gets 10 000 inputs (texture 500) past its
# seeds, which on a fresh clone covers the seeds' parsers and a few
# thousand mutations of each; 3000 Submit mutants (about a third accepted)
# all go through the checks and 20 accepted ones, of every seed scene, are
# rendered. For longer runs: make fuzz FUZZ_RUNS=200000 SUBMIT_MUTANTS=30000
# SUBMIT_RENDERS=400, or fuzz/run.sh with libFuzzer's own limits.
FUZZ_RUNS ?= 10000
SUBMIT_MUTANTS ?= 3000
SUBMIT_RENDERS ?= 20
fuzz: build
	@test -f $(BUILD)/fuzz/build.ninja || cmake -S fuzz -B $(BUILD)/fuzz -G Ninja \
	  -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_BUILD_TYPE=RelWithDebInfo
	cmake --build $(BUILD)/fuzz -j2
	fuzz/run.sh $(BUILD)/fuzz $(FUZZ_RUNS)
	$(PY) fuzz/submit_fuzz.py --mutants $(SUBMIT_MUTANTS) --renders $(SUBMIT_RENDERS) --seed 1

bench: build
	$(call apt_install,$(BENCH_APT_PACKAGES))
	$(PY) bench/cornell_box.py
	$(PY) bench/path_lengths.py
	$(PY) bench/scene_ratios.py
	$(PY) bench/aggregates.py
	$(PY) bench/profile.py
	$(BUILD)/bin/integrator_throughput
	$(BUILD)/bin/texture_lookups
	$(PY) bench/integrators.py
	$(PY) bench/render_integrators.py
	$(PY) bench/light_transport.py
	$(PY) bench/prepare_threads.py
	$(PY) bench/lights.py
	$(PY) bench/media.py
	$(PY) bench/denoise.py
	$(PY) bench/remote_components.py
	$(PY) bench/farm.py
	$(PY) bench/soak.py
	$(PY) bench/kill_loop.py

clean:
	rm -rf $(BUILD) $(STAMPS) out
