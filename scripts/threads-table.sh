#!/usr/bin/env bash
# The threads table: Table 2's H1 rows (block-plate-3d-tm1, one medium layer) solved by one
# built binary at 1, 2, 4, 8, ... threads, up to the CPUs this process may use, the runs of
# each thread count interleaved; a markdown table of the median wall, solver, assembly and
# output seconds, each against the fewest threads run, and the counts that must not change
# with the threads. Beside it, what the factor's elimination tree bounds the speed-ups at (`tmc
# check`), and each part of the run projected to 4, 16 and 64 threads from its 1- and
# 2-thread seconds (Amdahl's law: the part that did not halve stays, the rest divides).
#
#   scripts/threads-table.sh [-b BINARY] [-n "16 32"] [-t "1 2 4 8 16"] [-r REPEATS] [-k] [-M]
#
# Defaults: target/release/tmc, the 16×16 row (20.5k unknowns; add 32 for the 147k row, which
# takes minutes per run), one run per thread count. Runs go to target/threads-table/; each
# row is meshed once, to target/threads-table/h1-N.msh (again where the .geo is newer); -k
# keeps the meshes there as they are, so that a machine without gmsh runs the table from
# meshes written elsewhere (-M only writes them: copy target/threads-table/ and the binary
# over, then run with -k). A line per run is printed as it ends, so a table cut short still
# says what it measured.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/tmc
rows="16"
repeats=1
keep=0
mesh_only=0
cpus=$(nproc)
threads=""
while getopts "b:n:t:r:kM" o; do
    case $o in
    b) bin=$OPTARG ;;
    n) rows=$OPTARG ;;
    t) threads=$OPTARG ;;
    r) repeats=$OPTARG ;;
    k) keep=1 ;;
    M) mesh_only=1 ;;
    *) sed -n '2,18p' "$0"; exit 2 ;;
    esac
done
if [ -z "$threads" ]; then
    t=1
    while [ "$t" -le "$cpus" ]; do threads="$threads $t"; t=$((t * 2)); done
    [ $((t / 2)) -lt "$cpus" ] && threads="$threads $cpus"
fi
[ -x "$bin" ] || { echo "no binary at $bin (cargo build --release, or -b BINARY)" >&2; exit 2; }
out=target/threads-table
mkdir -p "$out"
geo=$(pwd)/geo/block-plate-3d.geo
echo "binary $bin, $cpus CPUs usable, threads:$threads, $repeats run(s) each"
for n in $rows; do
    nb=$((n * 10 / 16)); nq=$((n * 6 / 16))
    case=$out/h1-$n.toml
    msh=$(pwd)/$out/h1-$n.msh
    { [ -s "$msh" ] && { [ $keep = 1 ] || [ "$msh" -nt "$geo" ]; }; } || "$bin" mesh "$geo" -o "$msh" --set n=$n --set nb=$nb --set nm=1 --set nq=$nq >/dev/null
    sed -e "s#^mesh = .*#mesh = \"$msh\"#" -e "/^params = /d" -e "/^\[mesh_options\]/d" \
        cases/block-plate-3d-tm1.toml >"$case"
    [ $mesh_only = 1 ] && { echo "$n×$n: $msh"; continue; }
    "$bin" check "$case" 2>&1 | grep -E "^(factorisation|solves):" >"$out/h1-$n-check.txt" || true
    for r in $(seq "$repeats"); do
        for t in $threads; do
            dir=$out/h1-$n-t$t-r$r
            if RAYON_NUM_THREADS=$t "$bin" solve "$case" -o "$dir" >"$dir.log" 2>&1; then
                python3 -c 'import json, sys
s = json.load(open(sys.argv[1]))
w, so, a, nw, kr = (s[k] for k in ("wall_seconds", "solver_seconds", "assembly_seconds", "newton_iterations", "krylov_iterations"))
g, f = s["probes"].get("gap", float("nan")), s.get("factorisations", "?")
fs, ap = s.get("factorisation_seconds") or float("nan"), s.get("factor_solve_seconds") or float("nan")
print(f"  {sys.argv[2]} threads, run {sys.argv[3]}: wall {w:.2f} s, solver {so:.2f} s (factorising {fs:.2f}, applying the factors {ap:.2f}), assembly {a:.2f} s, Newton {nw}, Krylov {kr}, factorisations {f}, gap {g:.12e}", flush=True)' \
                    "$dir/summary.json" "$n×$n at $t" "$r"
            else
                echo "  $n×$n at $t threads, run $r: failed (see $dir.log)"
            fi
        done
    done
    python3 - "$out" "$n" "$repeats" $threads <<'PY'
import json, statistics, sys
out, n, repeats, threads = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4:]
rows = {}
for t in sorted(threads, key=int):
    runs = []
    for r in range(1, repeats + 1):
        try:
            runs.append(json.load(open(f"{out}/h1-{n}-t{t}-r{r}/summary.json")))
        except OSError:
            pass
    if runs:
        rows[t] = runs
if not rows:
    sys.exit(f"{n}×{n}: no run finished")
med = lambda runs, k: statistics.median(s[k] for s in runs)
# the ratios against the fewest threads that finished (one, where it did)
fewest = next(iter(rows))
base = rows[fewest]
per = f"{fewest} thread" + ("s" if fewest != "1" else "")
print(f"\n{n}×{n}, {base[0]['dofs']['free']} free unknowns")
print(f"| threads | wall s | solver s | factorising s | applying the factors s | rest of GMRES s | assembly s | output s | wall / {per} | solver / {per} | Newton its | Krylov its | factorisations | gap |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for t, runs in rows.items():
    w, s, a = med(runs, "wall_seconds"), med(runs, "solver_seconds"), med(runs, "assembly_seconds")
    o = med(runs, "output_seconds") if all("output_seconds" in x for x in runs) else float("nan")
    split = all(x.get("factorisation_seconds") is not None for x in runs)
    fs = med(runs, "factorisation_seconds") if split else float("nan")
    ap = med(runs, "factor_solve_seconds") if split else float("nan")
    rw = f"{w / med(base, 'wall_seconds'):.2f}"
    rs = f"{s / med(base, 'solver_seconds'):.2f}"
    its = sorted({x["newton_iterations"] for x in runs})
    kry = sorted({x["krylov_iterations"] for x in runs})
    fac = sorted({x.get("factorisations", -1) for x in runs})
    gaps = sorted({f"{x['probes'].get('gap', float('nan')):.12e}" for x in runs})
    print(f"| {t} | {w:.2f} | {s:.2f} | {fs:.2f} | {ap:.2f} | {s - fs - ap:.2f} | {a:.2f} | {o:.2f} | {rw} | {rs} | {'/'.join(map(str, its))} | {'/'.join(map(str, kry))} | {'/'.join(map(str, fac))} | {' '.join(gaps)} |")
try:
    print("\nthe elimination tree's bounds (tmc check):")
    print(open(f"{out}/h1-{n}-check.txt").read().rstrip())
except OSError:
    pass
base, two = rows.get("1"), rows.get("2")
if base and two and all("output_seconds" in x for x in base + two):
    # each part's seconds at p threads by Amdahl's law, its serial share read from 1 and 2
    parts = {"solver": "solver_seconds", "assembly": "assembly_seconds", "output": "output_seconds"}
    t1 = {k: med(base, v) for k, v in parts.items()}
    t2 = {k: med(two, v) for k, v in parts.items()}
    t1["rest"] = med(base, "wall_seconds") - sum(t1.values())
    t2["rest"] = med(two, "wall_seconds") - sum(t2.values())
    def at(k, p):
        serial = min(max(2 * t2[k] / t1[k] - 1, 0), 1) if t1[k] > 0 else 1
        return t1[k] * (serial + (1 - serial) / p)
    print("\nprojected from 1 and 2 threads (Amdahl: what did not halve stays):")
    print("| threads | wall s | solver s | assembly s (share) | output s (share) | wall / 1 thread |")
    print("|---|---|---|---|---|---|")
    for p in (4, 16, 64):
        v = {k: at(k, p) for k in t1}
        w = sum(v.values())
        print(f"| {p} | {w:.2f} | {v['solver']:.2f} | {v['assembly']:.2f} ({v['assembly'] / w:.1%}) | {v['output']:.2f} ({v['output'] / w:.1%}) | {w / med(base, 'wall_seconds'):.2f} |")
PY
done
