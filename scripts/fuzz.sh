#!/usr/bin/env bash
# Coverage-guided fuzzing of the map, its record stream and the dataset readers
# (docs/FUZZING.md).
#
#   bash scripts/fuzz.sh --smoke             fmt of fuzz/, a quick build that lints it, then
#                                            every target over its corpus and a bounded
#                                            number of new runs (CI)
#   bash scripts/fuzz.sh TARGET [SECONDS]    one target for SECONDS (default 600); inputs it
#                                            finds go to fuzz/target/found/TARGET
#   bash scripts/fuzz.sh --repro TARGET FILE run one input (a crash artifact) again
#   bash scripts/fuzz.sh --merge TARGET      add found inputs that cover more to the corpus
#   bash scripts/fuzz.sh --seeds             add the seed writer's inputs to fuzz/corpus/
#
# Engine: libFuzzer (the libfuzzer-sys crate) built on stable Rust with the
# sanitizer-coverage flags below, which are the ones cargo-fuzz passes; no nightly and no
# extra cargo tool. libfuzzer-sys compiles libFuzzer from C++ source, so a C++ compiler is
# the one thing installed here. Prints per target: runs, crashes, coverage (cov, ft);
# exits non-zero on any crash, printing the artifact's path.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

TARGETS=(snapshot integrate record_stream png json npy hdf5 mcap)
# Smoke: new runs per target after the corpus, and a time cap per target (seconds) so a
# slow machine still finishes the eight targets in about a minute.
SMOKE_RUNS=${SMOKE_RUNS:-20000}
SMOKE_SECONDS=${SMOKE_SECONDS:-7}
TRIPLE=$(rustc -vV | sed -n 's/^host: //p')
TARGET_DIR="$PWD/fuzz/target"
# Long runs use the release profile (fuzz/Cargo.toml: optimised, with debug assertions and
# overflow checks). The smoke uses the `smoke` profile, which optimises only the map's code
# and builds in less than half the time; it fuzzes about a third as fast, which a bounded
# smoke run can spare.
PROFILE=release
BIN="$TARGET_DIR/$TRIPLE/$PROFILE"
# Coverage instrumentation (edges, 8-bit counters, PC table for libFuzzer's feature
# tracking, comparison operands so it can solve magic numbers and CRC-free checks, stack
# depth) and the `fuzzing` cfg. `--target` keeps them off build scripts and proc macros.
FUZZ_RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares -Cllvm-args=-sanitizer-coverage-stack-depth \
--cfg fuzzing"

build() {
    # libfuzzer-sys compiles libFuzzer, which is C++.
    ensure_packages c++:g++
    step "building the fuzz targets ($PROFILE profile, debug assertions, sanitizer coverage)"
    (cd fuzz && RUSTFLAGS="$FUZZ_RUSTFLAGS" cargo build --profile "$PROFILE" --locked \
        --target "$TRIPLE" --target-dir "$TARGET_DIR" --bins)
}

# run TARGET [libFuzzer options...]: fuzzes with the committed corpus (read only; new
# inputs go to fuzz/target/found/TARGET), prints one summary line, returns 1 on a crash.
run() {
    local target=$1
    shift
    local found="$TARGET_DIR/found/$target" artifacts="$TARGET_DIR/artifacts/$target"
    local log
    log="$TARGET_DIR/logs/$target-$(date +%Y%m%d-%H%M%S)-$$.log"
    mkdir -p "$found" "$artifacts" "$(dirname "$log")" "fuzz/corpus/$target"
    local start=$SECONDS rc=0
    "$BIN/$target" -artifact_prefix="$artifacts/" -print_final_stats=1 -timeout=25 \
        "$@" "$found" "fuzz/corpus/$target" >"$log" 2>&1 || rc=$?
    summarize "$target" "$log" $((SECONDS - start)) "$rc"
}

# summarize TARGET LOG SECONDS EXIT: runs, crashes and the last coverage line of a log.
summarize() {
    local target=$1 log=$2 secs=$3 rc=$4
    local runs cov ft artifact
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    # From libFuzzer's status lines ("#N NEW cov: 1234 ft: 5678 corp: ..."), the last one.
    cov=$(grep -E '^#[0-9]+' "$log" | grep -oE ' cov: [0-9]+' | tail -1 | tr -dc '0-9')
    ft=$(grep -E '^#[0-9]+' "$log" | grep -oE ' ft: [0-9]+' | tail -1 | tr -dc '0-9')
    artifact=$(sed -n 's/.*Test unit written to //p' "$log" | tail -1)
    local crashes=0
    if [ "$rc" -ne 0 ] || [ -n "$artifact" ]; then crashes=1; fi
    printf 'fuzz %-13s runs %-9s crashes %s  cov %-6s ft %-6s %ss\n' \
        "$target" "${runs:-?}" "$crashes" "${cov:-?}" "${ft:-?}" "$secs"
    if [ "$crashes" -ne 0 ]; then
        echo "  crash in $target (exit $rc); log: $log"
        grep -m 20 -E 'panicked|ERROR|SUMMARY|deadly signal|timeout|out-of-memory' "$log" | sed 's/^/  /'
        echo "  artifact: ${artifact:-none written}"
        echo "  reproduce: bash scripts/fuzz.sh --repro $target ${artifact:-<file>}"
        return 1
    fi
}

# The smoke's build lints the fuzz crate as it compiles it (scripts/lib/lint.sh). The seed
# writer (fuzz/seeds) is a crate of the main workspace, linted with the rest of it.
smoke() {
    step "fuzz crate: cargo fmt --check"
    (cd fuzz && cargo fmt --all -- --check)
    lint_in_builds
    PROFILE=smoke
    BIN="$TARGET_DIR/$TRIPLE/$PROFILE"
    build
    step "smoke: each target over its corpus, then $SMOKE_RUNS runs (at most ${SMOKE_SECONDS}s)"
    # Two targets at a time (one per core; each libFuzzer process is single-threaded), their
    # lines printed in the targets' order.
    local failed=0 i t pid out pids=()
    out=$(mktemp -d)
    for ((i = 0; i < ${#TARGETS[@]}; i += 2)); do
        pids=()
        for t in "${TARGETS[@]:i:2}"; do
            run "$t" -runs="$SMOKE_RUNS" -max_total_time="$SMOKE_SECONDS" >"$out/$t" 2>&1 &
            pids+=($!)
        done
        for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
        for t in "${TARGETS[@]:i:2}"; do cat "$out/$t"; done
    done
    rm -rf "$out"
    return $failed
}

# Seeds: the writer (an ordinary, uninstrumented build) writes raw inputs; libFuzzer's
# -merge=1 adds to the corpus only those that cover something it does not. Files already
# there stay (crash inputs that tests read among them).
seeds() {
    build
    local tmp raw
    tmp=$(mktemp -d)
    raw="$tmp/raw"
    step "writing raw seeds"
    cargo run --release --locked -q -p sndt-fuzz-seeds -- "$raw"
    for t in "${TARGETS[@]}"; do
        mkdir -p "fuzz/corpus/$t" "$raw/$t"
        "$BIN/$t" -merge=1 "fuzz/corpus/$t" "$raw/$t" >"$tmp/$t.log" 2>&1
        echo "corpus $t: $(find "fuzz/corpus/$t" -type f | wc -l) files, $(du -sk "fuzz/corpus/$t" | cut -f1) KiB"
    done
    rm -rf "$tmp"
}

known() {
    local t
    for t in "${TARGETS[@]}"; do [ "$t" = "$1" ] && return 0; done
    echo "unknown target '$1' (targets: ${TARGETS[*]})" >&2
    exit 2
}

case "${1:-}" in
--smoke) smoke ;;
--seeds) seeds ;;
--repro)
    known "${2:?--repro TARGET FILE}"
    build
    "$BIN/$2" "${3:?--repro TARGET FILE}"
    ;;
--merge)
    known "${2:?--merge TARGET}"
    build
    "$BIN/$2" -merge=1 "fuzz/corpus/$2" "$TARGET_DIR/found/$2"
    ;;
"" | -h | --help) sed -n '2,18p' "$0" ;;
*)
    known "$1"
    build
    step "fuzzing $1 for ${2:-600}s"
    run "$1" -max_total_time="${2:-600}"
    ;;
esac
