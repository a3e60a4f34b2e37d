#!/usr/bin/env bash
# Install what tmc needs and the machine lacks: Debian's gmsh (library and headers) for
# meshing, python3-meshio to read results, python3-gmsh and python3-dolfinx (FEniCSx 0.5.2)
# for the validation against FEniCSx. Idempotent: installs only missing packages.
set -euo pipefail
need=()
for pkg in gmsh libgmsh-dev pkg-config python3-meshio python3-gmsh python3-dolfinx; do
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
