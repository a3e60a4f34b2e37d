# tmc — two commands for a newcomer: `make demo` and `make test`.
CARGO ?= cargo
TMC := target/release/tmc

.PHONY: deps deps-demo build demo test memcheck bench validate figures studies clean

# Everything the tests and the validation need (FEniCSx included).
deps:
	@scripts/install-deps.sh

# Only what building and running tmc needs.
deps-demo:
	@scripts/install-deps.sh demo

# With the distributed engine (PETSc over MPI): `mpirun -n N target/release/tmc solve CASE`.
build: deps
	$(CARGO) build --release --features petsc

# Mesh and solve the default scene, then say where the results are (installs only what tmc
# itself needs).
demo: deps-demo
	$(CARGO) build --release
	$(TMC) solve cases/block.toml --verbose
	@echo "results in results/block/: open block.pvd in ParaView"

# Every test. First, optimised with the PETSc engine: analytical, patch, tangent, end to end,
# bad input, and the engine on one and two ranks; ends with the ten slowest tests
# (target/test-times.log has every test's time). Then, in a build without the PETSc engine, in
# its own folder so as not to replace the engine's build, and unoptimised without debug
# information (it is built once and its tests are light: 2 min 17 s to build on a fresh
# clone against 285 s optimised): the unit tests (29 s; the kernels' fixed-size arrays want
# more than a test thread's 2 MB of stack unoptimised) and what that build says when asked
# for the engine; beside them the PETSc layer under valgrind (`make memcheck`, 43 s alone).
# The unit tests are not built a second time optimised: that build took 265 s of the 480 s
# the optimised build of a fresh clone took. Tests still running 30 minutes into the first
# part, or 15 into the unit tests, are ended and named, and `make test` fails there. Every
# build here has RUSTC_BOOTSTRAP=1 (timed-tests.sh sets it): cargo counts it in a build's
# fingerprint, and a build without it would build everything again.
SERIAL := CARGO_TARGET_DIR=target/serial CARGO_PROFILE_DEV_DEBUG=0 CARGO_INCREMENTAL=0
# The tests keep the meshes they make in a cache of their own, emptied first, not in the
# user's (docs/CASE.md, `[mesh_options]`): each `make test` meshes as a fresh clone does.
test: export TMC_MESH_CACHE = $(CURDIR)/target/test-mesh-cache
test: deps
	rm -rf target/test-mesh-cache
	scripts/timed-tests.sh $(CARGO) test --release --features petsc --test it
	scripts/memcheck.sh >target/memcheck.log 2>&1 & m=$$!; \
	TESTS_LOG=target/unit-test-times.log TESTS_DEADLINE=900 RUST_TEST_THREADS=$$(nproc) \
	  scripts/timed-tests.sh env RUST_MIN_STACK=67108864 $(SERIAL) $(CARGO) test --lib && \
	RUSTC_BOOTSTRAP=1 $(SERIAL) $(CARGO) test --test it cli::without_petsc; s=$$?; \
	wait $$m; c=$$?; cat target/memcheck.log; [ $$s -eq 0 ] && [ $$c -eq 0 ]

# The PETSc layer under valgrind: a converging solve and its error paths, on one rank and two.
memcheck: build
	scripts/memcheck.sh

# Benchmarks print tables (tests never assert wall time).
bench: deps
	$(CARGO) bench --bench strategies
	$(CARGO) bench --bench table2
	$(CARGO) bench --bench stability
	$(CARGO) bench --bench friction
	$(CARGO) bench --bench kernel
	$(CARGO) bench --bench assembly
	$(CARGO) bench --bench output
	$(CARGO) bench --bench sliding
	$(CARGO) bench --features petsc --bench distributed
	$(CARGO) bench --features petsc --bench start
	$(CARGO) build --release
	scripts/threads-table.sh -b $(TMC) -n 16

# tmc against FEniCSx on eight scenes (T1, T2, Q1, tet4, H1, H2; H1 in Mooney-Rivlin, T1 radiating);
# writes validation/fenicsx/RESULTS.md.
validate: build
	/usr/bin/python3 validation/fenicsx/run.py $(CURDIR)/$(TMC) $(CURDIR)/target/validate

# The README's renders: solve the curved scenes (sphere-block takes about 8 minutes), then draw.
R = /usr/bin/python3 validation/render/render.py
figures: build
	$(TMC) solve cases/discs-ellipse.toml -q
	$(TMC) solve cases/micro-contact.toml -q
	$(TMC) solve cases/sphere-block.toml -q
	$(R) results/discs-ellipse docs/img/discs-ellipse.png --title "discs-ellipse: θ, ū = 0.9"
	for l in 0.25 0.5 1; do $(R) results/micro-contact docs/img/micro-contact-$$l.png \
	  --at-lambda $$l --window 0,4,1.2,3.4 --title "micro-contact: θ at λ = $$l"; done
	/usr/bin/python3 validation/render/curve.py results/micro-contact \
	  docs/img/micro-contact-conductance.png Q_top --scale-x 1.3333333333 \
	  --xlabel "top displacement v̄" --mark 0.25,0.5,1
	$(R) results/sphere-block docs/img/sphere-block.png --title "sphere-block: θ, ū = 0.2"

# The accuracy-against-time studies: tables and plots into validation/studies/NAME/
# (one command each: tmc study validation/studies/NAME.toml -o validation/studies/NAME).
STUDIES = block-refinement block-gamma block-plate-layers h1-vs-h2
studies: build
	@failed=""; for s in $(STUDIES); do \
	  $(TMC) study validation/studies/$$s.toml -o validation/studies/$$s || failed="$$failed $$s"; \
	done; [ -z "$$failed" ] || echo "some variants failed in:$$failed (named in their study.md)"

clean:
	$(CARGO) clean
	rm -rf results
