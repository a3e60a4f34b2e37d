#!/usr/bin/env bash
# The PETSc layer under valgrind's memory checker: a solve that converges on PETSc, and its
# error paths (a factorisation package PETSc lacks, a misspelt option, a factorisation that
# meets a zero pivot, a Krylov solver that does not converge, a bad option under mpirun on
# two ranks, a rank that fails alone). Each must end as tmc says it ends (converged, or its
# error) with no invalid read, write or free, no use of an uninitialised value and no double
# destruction; leaks at exit are PETSc's and MPI's and not counted. Open MPI's own suppressions, and
# scripts/valgrind.supp for PMIx's.
#
#   scripts/memcheck.sh [BINARY]     (default target/release/tmc, built with --features petsc)
set -uo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "${1:-target/release/tmc}")
command -v valgrind >/dev/null || { echo "memcheck: valgrind is not installed" >&2; exit 2; }
[ -x "$bin" ] || { echo "memcheck: no binary at $bin" >&2; exit 2; }
out=target/memcheck
rm -rf "$out" && mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
supp=(--suppressions=scripts/valgrind.supp)
[ -f /usr/share/openmpi/openmpi-valgrind.supp ] &&
    supp+=(--suppressions=/usr/share/openmpi/openmpi-valgrind.supp)
vg=(valgrind -q --error-exitcode=99 "${supp[@]}")
case=cases/bar3d-stretch.toml
"$bin" mesh geo/bar3d.geo -o "$out/bar.msh" >/dev/null || { echo "memcheck: meshing failed" >&2; exit 1; }
mesh="mesh=\"$(realpath "$out/bar.msh")\""

# name, the words its output must hold, then tmc's arguments after the case
run() {
    local name=$1 expect=$2 launch=()
    shift 2
    [ "${name#mpirun}" != "$name" ] && launch=(mpirun -n 2)
    timeout 600 "${launch[@]}" "${vg[@]}" "$bin" solve "$case" --set "$mesh" "$@" \
        -o "$out/$name" >"$out/$name.log" 2>&1
    local rc=$?
    if [ $rc -eq 99 ] || grep -q "^==[0-9]*== [A-Z]" "$out/$name.log"; then
        echo "memcheck: $name: valgrind found errors (exit $rc), see $out/$name.log"
        return 1
    fi
    if ! grep -q -- "$expect" "$out/$name.log"; then
        echo "memcheck: $name: ended without \"$expect\" (exit $rc), see $out/$name.log"
        return 1
    fi
    echo "memcheck: $name: clean (exit $rc)"
}

petsc() { echo "solver.petsc.options=\"$1\""; }
pids=()
run converges "results in" --set 'solver.engine="petsc"' \
    --set "$(petsc "-pc_type lu -pc_factor_mat_solver_type superlu_dist")" & pids+=($!)
run package "Could not locate solver type pastix" --set 'solver.engine="petsc"' \
    --set "$(petsc "-pc_type lu -pc_factor_mat_solver_type pastix")" & pids+=($!)
run misspelt "Unable to find requested PC type nonsense" --set 'solver.engine="petsc"' \
    --set "$(petsc "-pc_type nonsense")" & pids+=($!)
run zero-pivot "DIVERGED_PC_FAILED" --set 'solver.engine="petsc"' \
    --set "$(petsc "-ksp_type preonly -pc_type lu -pc_factor_zeropivot 1e300")" & pids+=($!)
run diverged "DIVERGED_ITS" --set 'solver.engine="petsc"' \
    --set "$(petsc "-ksp_type cg -pc_type none -ksp_max_it 2")" & pids+=($!)
failed=0
for p in "${pids[@]}"; do wait "$p" || failed=1; done
run mpirun "Unable to find requested PC type nonsense" --set "$(petsc "-pc_type nonsense")" || failed=1
# a rank that fails alone: a folder in the way of the second rank's part of step 1, which
# that rank cannot write; the first rank hears of it, and both end on it
mkdir -p "$out/mpirun-alone/step_0001_1.vtu"
run mpirun-alone "cannot write .*step_0001_1.vtu: Is a directory" || failed=1
exit $failed
