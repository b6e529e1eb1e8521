# galerkin — two commands:
#   make demo   install what is missing, build, run every demo (writes out/*.png)
#   make test   install what is missing, run every test on Mesa lavapipe with validation on
# make test-mpi: the trainings over MPI ranks (installs OpenMPI, builds with --features mpi).
# make test-shaderc: derived fields (--expr) compiled at run time (installs the system's
#   shaderc and glslang, builds with --features runtime-shaderc).
# Also: make bench (the device's ceilings), make bench-all (every benchmark in one run, its
# tables also written to out/benchmarks.md, or spliced into OUT=BENCHMARKS.md between its
# markers; QUICK=1 for the quick sizes), make lint,
# make fuzz (every loader's fuzz target, FUZZ_SECONDS each; nightly + cargo-fuzz; not in CI).

CARGO ?= cargo
LAVAPIPE_ICD ?= /usr/share/vulkan/icd.d/lvp_icd.json

.PHONY: deps build demo test test-mpi test-shaderc bench bench-all lint fuzz

deps:
	@scripts/install-deps.sh

build: deps
	$(CARGO) build --release

demo: build
	$(CARGO) run --release --quiet -- demo

# Tests run on lavapipe (selected by VK_DRIVER_FILES) with the Khronos validation layer on;
# the viewer test starts its own Xvfb.
test: deps
	VK_DRIVER_FILES=$(LAVAPIPE_ICD) VK_ICD_FILENAMES=$(LAVAPIPE_ICD) GALERKIN_VALIDATION=1 \
		$(CARGO) test --release --features fault-injection

# The trainings under mpirun (1, 2, 4 ranks, oversubscribed) against one process: needs the
# `mpi` feature and OpenMPI (installed by install-deps.sh --mpi).
test-mpi:
	@scripts/install-deps.sh --mpi
	OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
		$(CARGO) test --release --features mpi --test mpi

# Derived fields per pixel: the expression shaders compiled at run time through the shaderc
# crate, linked against the system's shaderc and glslang (install-deps.sh --shaderc).
test-shaderc:
	@scripts/install-deps.sh --shaderc
	VK_DRIVER_FILES=$(LAVAPIPE_ICD) VK_ICD_FILENAMES=$(LAVAPIPE_ICD) GALERKIN_VALIDATION=1 \
		$(CARGO) test --release --features runtime-shaderc --test spectral_expression

fuzz: deps
	@scripts/fuzz.sh

bench: deps
	$(CARGO) run --release --quiet -- bench gpu

bench-all: deps
	@mkdir -p out
	$(CARGO) run --release --quiet -- bench all $(if $(QUICK),--quick,) --out $(or $(OUT),out/benchmarks.md)

lint:
	$(CARGO) fmt --check
	$(CARGO) clippy --release --all-targets -- -D warnings
