#!/bin/sh
# Checks of the unsafe code that need a nightly toolchain or valgrind (not part of .ci/run, which
# runs stable only). DESIGN.md "How the unsafe code is checked" says what each covers; BENCHMARKS.md
# "Memory checks" what they found and how long they took.
#
#   tools/memcheck.sh miri          Miri on the library's unit tests of the modules with unsafe code
#   tools/memcheck.sh asan          AddressSanitizer on the library's unit and integration tests
#   tools/memcheck.sh valgrind-c    valgrind memcheck on every C/C++ program of bindings/c/tests
#   tools/memcheck.sh valgrind-cli  valgrind memcheck on a few CLI commands
#
# Each mode uses its own target directory under $MEMCHECK_TARGET (default target/memcheck), so it
# does not invalidate the normal build. Exit status: non-zero on any finding.
set -eu
cd "$(dirname "$0")/.."
T=${MEMCHECK_TARGET:-$PWD/target/memcheck}
VG="valgrind -q --error-exitcode=99 --leak-check=full --show-leak-kinds=definite --errors-for-leak-kinds=definite"

case "${1:-}" in
miri)
    # Tree Borrows: rayon's crossbeam-epoch breaks Stacked Borrows' rules (crossbeam#545; it
    # runs its own Miri tests under Tree Borrows). Leaks ignored: the library's thread pool is
    # leaked by design (src/par.rs). Isolation off: store::name looks at the file system.
    # Not under Miri: anything that compresses (zstd is C), maps files (memmap2), or runs
    # inline assembly (the DAZ test is #[cfg_attr(miri, ignore)]); fastmath's libm comparisons
    # (Miri perturbs libm's results by design) — those run under ASan instead.
    MIRIFLAGS="-Zmiri-tree-borrows -Zmiri-ignore-leaks -Zmiri-disable-isolation" \
        CARGO_TARGET_DIR="$T/miri" cargo +nightly miri test -p brdftab --lib -- \
        simd:: par:: store::name fastmath::tests::the_documented \
        fastmath::tests::floor
    ;;
asan)
    # The explicit --target keeps build scripts and proc-macros uninstrumented. A failed
    # allocation returns null rather than aborting: tests/store.rs asks for more than memory
    # on purpose (the library's try_reserve must see the failure).
    ASAN_OPTIONS=allocator_may_return_null=1 \
        RUSTFLAGS="-Zsanitizer=address" RUSTDOCFLAGS="-Zsanitizer=address" \
        CARGO_TARGET_DIR="$T/asan" cargo +nightly test --release \
        --target x86_64-unknown-linux-gnu -p brdftab --lib --test table --test store \
        --test store_memory --test concurrency --test codec_compat --test sample_domain \
        --test library_api --test crash
    ;;
valgrind-c)
    # The programs' own stderr is read by some tests: valgrind logs to files, checked after.
    # The tests' verdict is printed but not the mode's: under valgrind's ~30x slowdown the
    # monitor test's latency check (a stopped .bsdf conversion returns within 3 s) fails.
    log=$(mktemp -d)
    BRDFTAB_C_TEST_WRAPPER="$VG --log-file=$log/%p.log" CARGO_TARGET_DIR="$T/release" \
        cargo test --release -p brdftab-c --test c_programs || echo "(tests failed: see above)"
    echo "valgrind logs in $log: $(ls "$log" | wc -l) programs"
    ! grep -l . "$log"/*.log
    ;;
valgrind-cli)
    CARGO_TARGET_DIR="$T/release" cargo build --release -p brdftab-tools --bin brdftab
    b="$T/release/release/brdftab"
    d=$(mktemp -d)
    pairs="0 0 1 0 0 1
0.3 0.1 0.948683 -0.2 0.3 0.932738
0 0 -1 0 0 1"
    $VG "$b" bake '{"model":"ggx","alpha":0.3}' --preset small -o "$d/g.btdb" >/dev/null
    for cmd in "info $d/g.btdb" "eval $d/g.btdb" "pdf $d/g.btdb" "albedo $d/g.btdb" \
        "check $d/g.btdb" "sample --wo 0.3,0,0.953939 $d/g.btdb" \
        "convert $d/g.btdb $d/g.binary" "eval $d/g.binary" \
        "eval data/rgl/paper_white_rgb.bsdf" "convert $d/g.btdb $d/h.btdb --codec f16" \
        "db add --name t --preset small $d/d.btdb {\"model\":\"lambert\",\"kd\":0.5}" \
        "db list $d/d.btdb" "db verify $d/d.btdb" "eval $d/d.btdb#t"; do
        # shellcheck disable=SC2086
        echo "$pairs" | $VG "$b" $cmd >/dev/null
    done
    echo "valgrind-cli: no errors, no definite leaks"
    ;;
*)
    sed -n '2,13p' "$0"
    exit 2
    ;;
esac
