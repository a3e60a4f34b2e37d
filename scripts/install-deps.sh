#!/usr/bin/env bash
# Install what tmc needs and the machine lacks: Debian's gmsh (library and headers) for
# meshing, a font for the plots (DejaVu Sans, read by plotters), python3-meshio and
# python3-matplotlib to read and render results, python3-gmsh and python3-dolfinx (FEniCSx 0.5.2)
# for the validation against FEniCSx. Idempotent: installs only missing packages.
# `install-deps.sh demo` installs only what building and running tmc needs (no Python, no
# FEniCSx, about 1 GB less); without an argument, also what the tests and validation need,
# with the distributed engine: PETSc (petsc-dev, with MUMPS and hypre), Open MPI (its headers
# and mpirun) and libclang (which the mpi crate's build reads MPI's header with).
set -euo pipefail
packages=(gmsh libgmsh-dev pkg-config fonts-dejavu-core)
if [ "${1:-all}" != "demo" ]; then
  packages+=(python3-meshio python3-matplotlib python3-gmsh python3-dolfinx)
  packages+=(petsc-dev libopenmpi-dev openmpi-bin libclang-dev)
  # the PETSc layer's memory check (scripts/memcheck.sh)
  packages+=(valgrind)
fi
need=()
for pkg in "${packages[@]}"; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need+=("$pkg")
done
if [ ${#need[@]} -gt 0 ]; then
  echo "installing: ${need[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${need[@]}" >/dev/null
fi
command -v cargo >/dev/null || { echo "cargo not found: install Rust (https://rustup.rs)" >&2; exit 1; }
