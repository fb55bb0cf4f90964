# pelage: one command runs the demo, one runs every test (see README.md).
# Both install the Debian packages they need when they are missing.

BUILD ?= build
JOBS ?= 2
APT_PACKAGES := cmake g++ pkg-config libembree-dev libtbb-dev libpng-dev libtinyobjloader-dev libopenvdb-dev libboost-dev valgrind binutils python3-venv slurm-wlm munge
EMBEDDED_TARGET := thumbv7em-none-eabihf

FUZZ_SECONDS ?= 60

.PHONY: demo farm-demo test deps rust-test rust-lint rust-miri rust-fuzz cmake-test header-check bench

demo: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release
	cmake --build $(BUILD) -j$(JOBS) --target demo
	cd $(BUILD) && ./cpp_examples/demo

# A short shot through Slurm: a one-node cluster on this machine (farm/cluster.sh),
# the simulation, the shot pass and a job array of render tasks (farm/shot.sh);
# the frames land in $(BUILD)/farm_demo/frame_NNNN.png.
FARM_FRAMES ?= 8
FARM_HAIRS ?= 200000
FARM_CHUNK ?= 2
farm-demo: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release
	cmake --build $(BUILD) -j$(JOBS) --target shot
	farm/cluster.sh
	farm/shot.sh $(BUILD)/cpp_examples/shot $(BUILD)/assets/creature.obj $(BUILD)/farm_demo \
	  $(FARM_FRAMES) $(FARM_HAIRS) $(FARM_CHUNK)

test: deps rust-lint rust-test rust-miri rust-fuzz cmake-test header-check

deps:
	@missing=""; for p in $(APT_PACKAGES); do \
	  dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing; \
	fi
	@rustup target list --installed | grep -qx $(EMBEDDED_TARGET) || rustup target add $(EMBEDDED_TARGET)

rust-lint:
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
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release
	cmake --build $(BUILD) -j$(JOBS)
	ctest --test-dir $(BUILD) --output-on-failure -j$(JOBS)

# The committed header must be exactly what the build generates.
header-check:
	git diff --exit-code -- include/pelage.h

bench:
	cargo bench --locked -p pelage-tests
