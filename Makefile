# tmc — two commands for a newcomer: `make demo` and `make test`.
CARGO ?= cargo
TMC := target/release/tmc

.PHONY: deps build demo test bench validate clean

deps:
	@scripts/install-deps.sh

build: deps
	$(CARGO) build --release

# Mesh and solve the default scene, then say where the results are.
demo: build
	$(TMC) solve cases/block.toml --verbose
	@echo "results in results/block/: open block.pvd in ParaView"

# Every test: unit, analytical, patch, tangent, end-to-end, bad input.
test: deps
	$(CARGO) test --release

# Benchmarks print tables (tests never assert wall time).
bench: deps
	$(CARGO) bench --bench strategies
	$(CARGO) bench --bench table2

# tmc against FEniCSx on four scenes (T1, Q1, tet4, H1); writes validation/fenicsx/RESULTS.md.
validate: build
	/usr/bin/python3 validation/fenicsx/run.py $(CURDIR)/$(TMC) $(CURDIR)/target/validate

clean:
	$(CARGO) clean
	rm -rf results
