# pelage: one command runs the demo, one runs every test (see README.md).
# Each installs the Debian packages it needs when they are missing: the demo
# only what configuring and building the demo takes, the tests the rest.

BUILD ?= build
JOBS ?= 2
FUZZ_SECONDS ?= 60

# What each entry point installs (Debian packages, then rustup targets).
# The demo configures CMake with the tests off, so it needs no test package.
DEPS_demo := cmake g++ binutils libembree-dev libtbb-dev libpng-dev libtinyobjloader-dev
DEPS_farm := $(DEPS_demo) slurm-wlm munge
DEPS_test := $(DEPS_farm) pkg-config libopenvdb-dev libboost-dev valgrind python3-venv \
  libx11-6 libxrender1 libxxf86vm1 libxfixes3 libxi6 libxkbcommon0 libsm6 libgl1 libegl1 \
  libegl-mesa0 libgl1-mesa-dri
RUST_TARGETS_test := thumbv7em-none-eabihf
EMBEDDED_TARGET := thumbv7em-none-eabihf

.PHONY: demo farm-demo test deps deps-demo deps-farm deps-test docs-check rust-test rust-lint \
        rust-miri rust-fuzz cmake-test header-check bench perf python-venv python-test \
        blender-venv blender-test blender-extension

# A build tree that is already configured keeps its settings (after `make
# test` it has the tests on, and their packages are installed); a new one is
# configured with the tests off, so the demo needs none of their packages.
DEMO_CONFIGURE = cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release \
  $(if $(wildcard $(BUILD)/CMakeCache.txt),,-DPELAGE_BUILD_TESTS=OFF)

demo: deps-demo
	$(DEMO_CONFIGURE)
	cmake --build $(BUILD) -j$(JOBS) --target demo
	cd $(BUILD) && ./cpp_examples/demo

# A short shot through Slurm: a one-node cluster on this machine (farm/cluster.sh),
# the simulation, the shot pass and a job array of render tasks (farm/shot.sh);
# the frames land in $(BUILD)/farm_demo/frame_NNNN.png. The cluster is stopped
# afterwards unless it was already up, or FARM_KEEP=1 is given.
FARM_FRAMES ?= 8
FARM_HAIRS ?= 200000
FARM_CHUNK ?= 2
FARM_KEEP ?= 0
farm-demo: deps-farm
	$(DEMO_CONFIGURE)
	cmake --build $(BUILD) -j$(JOBS) --target shot
	@was_up=0; if farm/cluster.sh status; then was_up=1; fi; \
	farm/cluster.sh && farm/shot.sh $(BUILD)/cpp_examples/shot $(BUILD)/assets/creature.obj \
	  $(BUILD)/farm_demo $(FARM_FRAMES) $(FARM_HAIRS) $(FARM_CHUNK); rc=$$?; \
	if [ $$was_up = 1 ] || [ "$(FARM_KEEP)" = 1 ]; then \
	  echo "farm-demo: the cluster stays up (munged, slurmctld, slurmd); stop it with: farm/cluster.sh stop"; \
	else farm/cluster.sh stop && echo "farm-demo: cluster stopped"; fi; \
	exit $$rc

test: deps-test docs-check rust-lint rust-test rust-miri rust-fuzz cmake-test python-test blender-test \
  header-check

# Installs the Debian packages and rustup targets of DEPS_<name> and
# RUST_TARGETS_<name> that are missing (the one recipe for every list).
deps-demo deps-farm deps-test: deps-%:
	@missing=""; for p in $(DEPS_$*); do \
	  dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing; \
	fi
	@for t in $(RUST_TARGETS_$*); do \
	  rustup target list --installed | grep -qx $$t || rustup target add $$t; done

deps: deps-test

rust-lint:
	python3 tests/import_circles.py core/src capi/src
	@long=$$(find core/src capi/src -name '*.rs' ! -name tests.rs -exec wc -l {} + | \
	  awk '$$2 != "total" && $$1 > 1000'); [ -z "$$long" ] || \
	  { echo "production files over 1000 lines (move tests to a tests.rs):"; echo "$$long"; exit 1; }
	cargo fmt --all -- --check
	cargo clippy --locked --workspace --all-targets --release -- -D warnings
	cargo check --locked -p pelage-core --target $(EMBEDDED_TARGET)
	RUSTDOCFLAGS="-D warnings" cargo doc --locked --workspace --no-deps

rust-test:
	cargo test --locked --workspace --release
	cargo bench --locked --workspace --no-run

# Miri on the fast core tests (the arena, strided reads, maps, mesh, RNG, the
# trim lengths and their file).
rust-miri:
	@rustup +nightly component list --installed | grep -q '^miri' || rustup component add --toolchain nightly miri rust-src
	cargo +nightly miri test --locked -p pelage-core --lib --no-default-features -- arena strided rng map:: mesh:: trim::length trim_file

# The file decoders under libFuzzer (cargo-fuzz, nightly), a while each.
rust-fuzz:
	fuzz/run.sh $(FUZZ_SECONDS)

cmake-test:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DPELAGE_BUILD_TESTS=ON
	cmake --build $(BUILD) -j$(JOBS)
	ctest --test-dir $(BUILD) --output-on-failure -j$(JOBS)

# The README stays one or two screens, and its C snippet is cpp_examples/minimal.c's
# own lines (each line of the snippet but "/* ... */" must appear there).
README_MAX_LINES := 300
docs-check:
	@n=$$(wc -l < README.md); [ $$n -le $(README_MAX_LINES) ] || \
	  { echo "README.md: $$n lines, more than $(README_MAX_LINES)"; exit 1; }
	@awk '/^```c$$/ { c = 1; next } /^```/ { c = 0 } c && !/\/\* \.\.\. \*\// && NF' README.md | \
	  sed 's/^[[:space:]]*//' | while IFS= read -r line; do \
	    grep -qF -- "$$line" cpp_examples/minimal.c || \
	      { echo "README.md's C snippet has a line cpp_examples/minimal.c does not: $$line"; exit 1; }; \
	  done

# The Python package (python/): a virtual environment in the build tree with
# the pinned test requirements (pip's downloads cached beside it, so a second
# run installs from the cache), the package installed from the working tree
# as a user would (`pip install ./python`, which builds the library with
# cargo; without build isolation, so setuptools comes from the venv), then
# its pytest suite.
PY_DIR := $(BUILD)/python
PY_VENV := $(PY_DIR)/venv
PY_PIP = $(PY_VENV)/bin/pip --disable-pip-version-check --cache-dir $(abspath $(PY_DIR))/pip-cache
python-venv: deps-test
	@test -x $(PY_VENV)/bin/python || python3 -m venv $(PY_VENV)
	@$(PY_PIP) install -q -r python/requirements-test.txt
python-test: python-venv
	$(PY_PIP) install -q --no-build-isolation --force-reinstall --no-deps ./python
	$(PY_VENV)/bin/pytest -q -p no:cacheprovider python/tests

# The Blender add-on (blender/): bpy from PyPI in a virtual environment of
# its own (bpy wants CPython 3.11 and numpy < 2, so not python-test's). The
# pinned wheels, bpy's ~374 MB among them, are downloaded once into the
# build tree (or BL_WHEELS: a directory outside it keeps them across
# clones) and installed from there on later runs, offline; then the
# package from the working tree, as python-test installs it, and the
# add-on's headless suite.
BL_DIR := $(BUILD)/blender
BL_VENV := $(BL_DIR)/venv
BL_WHEELS ?= $(BL_DIR)/wheels
BL_PYTHON ?= python3.11
BL_PIP = $(BL_VENV)/bin/pip --disable-pip-version-check --cache-dir $(abspath $(BL_DIR))/pip-cache
blender-venv: deps-test
	@test -x $(BL_VENV)/bin/python || $(BL_PYTHON) -m venv $(BL_VENV)
	@$(BL_PIP) install -q --no-index --find-links $(BL_WHEELS) -r blender/requirements-test.txt 2>/dev/null || \
	  { $(BL_PIP) download -q -d $(BL_WHEELS) -r blender/requirements-test.txt && \
	    $(BL_PIP) install -q --no-index --find-links $(BL_WHEELS) -r blender/requirements-test.txt; }
blender-test: blender-venv blender-extension
	$(BL_PIP) install -q --no-build-isolation --force-reinstall --no-deps ./python
	$(BL_VENV)/bin/pytest -q -p no:cacheprovider blender/tests

# The add-on packed as a Blender 4.2+ extension, build/blender/pelage_fur.zip:
# its files and the wheels its manifest lists (the package built from the
# working tree, cffi and pycparser), then installed with Blender's own
# installer into an empty user directory and used once there.
BL_EXT := $(BL_DIR)/extension/pelage_fur
blender-extension: blender-venv
	rm -rf $(BL_EXT) $(BL_DIR)/pelage_fur.zip $(BL_DIR)/extension-user
	mkdir -p $(BL_EXT)/wheels
	cp blender/pelage_fur/*.py blender/pelage_fur/blender_manifest.toml $(BL_EXT)/
	$(BL_PIP) wheel -q --no-build-isolation --no-deps -w $(BL_EXT)/wheels ./python
	cp $(BL_WHEELS)/cffi-*.whl $(BL_WHEELS)/pycparser-*.whl $(BL_EXT)/wheels/
	cd $(BL_EXT) && $(abspath $(BL_VENV))/bin/python -m zipfile -c $(abspath $(BL_DIR))/pelage_fur.zip \
	  blender_manifest.toml $$(ls *.py) wheels
	BLENDER_USER_RESOURCES=$(abspath $(BL_DIR))/extension-user \
	  $(BL_VENV)/bin/python blender/tests/install_extension.py $(BL_DIR)/pelage_fur.zip

# The committed header, and its declarations for cffi, must be exactly what
# the build generates.
header-check:
	git diff --exit-code -- include/pelage.h python/pelage/_cdef.h

# Every benchmark's tables, printed to the terminal.
bench:
	cargo bench --locked -p pelage-tests

# Every benchmark run, its tables written to docs/PERFORMANCE.md with the
# machine and the date (BENCHES="stamp cache" runs only those).
BENCHES ?=
perf:
	tests/perf/report.sh $(BENCHES)
