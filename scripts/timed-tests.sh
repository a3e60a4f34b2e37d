#!/usr/bin/env bash
# Run a `cargo test` command line with each test's time reported, keep the whole output in
# target/test-times.log (or $TESTS_LOG), and end with the ten slowest tests. The exit status is
# the tests'. A command still running after $TESTS_DEADLINE seconds (default 1800; a fresh
# clone builds and runs the integration binary in about 10 minutes on 2 CPUs) is ended with
# everything it started, and the tests it was still waiting on are named: a test that hangs
# fails `make test` there, instead of holding CI until CI's own limit ends it without a word.
#
#   scripts/timed-tests.sh cargo test --release --features petsc
#
# libtest reports a test's time only with an unstable option; RUSTC_BOOTSTRAP lets the stable
# test harness take it (it changes nothing else in the build or the tests).
set -uo pipefail
cd "$(dirname "$0")/.."
mkdir -p target
# One test thread more than CPUs: many tests wait on a child (mpirun starting its ranks, a run
# polled for its step files before Ctrl-C), and the extra thread keeps the CPUs busy meanwhile
# (the integration binary on 2 CPUs: 313 s with 2 test threads, 260–280 s with 3, 307 s with 4).
# Not more: the `distributed::` tests come one after another, and two `mpirun` jobs at once put
# four ranks on two CPUs, each polling while it waits for the others (the 24 slowest tests:
# 161 s with 3 test threads, over 6 minutes with 4; docs/notes/2026-12-05-the-suite-s-time-and-
# a-mesher-that-is-not-the-same-twice.md).
export RUST_TEST_THREADS=${RUST_TEST_THREADS:-$(($(nproc) + 1))}
# More tests at once than CPUs: a solve's pool threads sleep between its parallel parts
# instead of spinning, which would take the CPU another test's solve is waiting for (tmc solve
# and the tests' own runs read it; the idle threads' own tests set what they test).
export TMC_IDLE_THREADS=${TMC_IDLE_THREADS:-sleep}
log=${TESTS_LOG:-target/test-times.log}
deadline=${TESTS_DEADLINE:-1800}
expired=target/.tests-deadline-$$
rm -f "$expired"
# The process `$1` and everything under it, deepest first.
tree() {
    local child
    for child in $(ps -o pid= --ppid "$1"); do
        tree "$child"
    done
    echo "$1"
}
# The watch: at the deadline, end what this script started (the tests stay in the foreground,
# so a Ctrl-C reaches them as it always did).
me=$$
(
    sleep "$deadline"
    kill -0 "$me" 2>/dev/null || exit 0
    touch "$expired"
    for signal in TERM KILL; do
        for child in $(ps -o pid= --ppid "$me"); do
            [ "$child" -ne "$BASHPID" ] && kill -s "$signal" $(tree "$child") 2>/dev/null
        done
        sleep 10
    done
) &
watch=$!
trap 'kill $(tree "$watch") 2>/dev/null; rm -f "$expired"' EXIT
RUSTC_BOOTSTRAP=1 "$@" -- -Z unstable-options --report-time 2>&1 | tee "$log"
status=${PIPESTATUS[0]}
if [ -e "$expired" ]; then
    status=124
    echo
    echo "the tests did not end within $deadline s (TESTS_DEADLINE) and were ended; still running:"
    # libtest names a test running for over 60 s; those it never said were done were running
    sed -n 's/^test \(.*\) has been running for over 60 seconds$/\1/p' "$log" | sort -u |
        while read -r name; do
            grep -q "^test $name \.\.\. " "$log" || echo "  $name"
        done
fi
echo
echo "the ten slowest tests (of $(grep -c '^test .* <[0-9.]*s>$' "$log") timed; $log has them all):"
sed -n 's/^test \(.*\) \.\.\. [a-zA-Z]* <\([0-9.]*\)s>$/\2 \1/p' "$log" | sort -rn | head -10 |
    awk '{ printf "  %8.1f s  %s\n", $1, $2 }'
exit "$status"
