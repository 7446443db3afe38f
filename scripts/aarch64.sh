#!/usr/bin/env bash
# Runs sndt-core's tests (unit, property, doc) for aarch64-unknown-linux-gnu under
# qemu-aarch64, and checks that the aarch64 snapshot CRC of the test vector and the CRC of the
# view rendered from its map equal the committed ones (targets/cortex-m4f/vector/
# expected_crc.txt and expected_render_crc.txt), as on x86-64 and the Cortex-M4F firmware.
# The CRCs come from the C API's vector_crc program (targets/c/examples/vector_crc.c),
# cross-compiled against libsndt_c.a for aarch64: it integrates the vector through the same
# core code as the Rust test, and needs only sndt-core built for aarch64, not sndt-host.
# The spill run's CRC (expected_spill_crc.txt: the firmware's evicted records merged into a
# larger map) is checked by the core's own test tests/spill_vector.rs, which must pass here.
# Installs what it needs when missing (idempotent; fast when everything is present).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

TARGET=aarch64-unknown-linux-gnu
start=$SECONDS

step "aarch64 toolchain (rustup target, cross gcc, qemu-user)"
ensure_rust_target "$TARGET"
ensure_packages aarch64-linux-gnu-gcc:gcc-aarch64-linux-gnu libc6-dev-arm64-cross \
    qemu-aarch64:qemu-user

# Cross linker and the emulator as the test runner (-L: where the aarch64 loader and libc are).
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER="qemu-aarch64 -L /usr/aarch64-linux-gnu"
# Emulated debug code is 30-100x slower than native: optimise the test builds (the test
# profile keeps debug assertions and overflow checks on, as in the x86-64 `cargo test`).
export CARGO_PROFILE_TEST_OPT_LEVEL=2
# The core's doctests are merged into one program (edition 2024); under the emulator they
# run as threads of one process, not one process each, and the crate example's map (a
# 485 KB `Map` on the stack) overflows a test thread's default 2 MiB stack there.
export RUST_MIN_STACK=16777216

log="$(mktemp)"
trap 'rm -f "$log"' EXIT

step "cargo test -p sndt-core --target $TARGET (unit, property, doc tests under qemu-aarch64)"
cargo test -p sndt-core --target "$TARGET" 2>&1 | tee "$log"
doctests=$(awk '/Doc-tests/ { d = 1 } d && /^test result:/ { print $4; exit }' "$log")
if [ -z "$doctests" ] || [ "$doctests" -eq 0 ]; then
    echo "error: no doc tests ran for $TARGET" >&2
    exit 1
fi

expected_spill=$(committed_crc expected_spill_crc.txt)
if ! grep -q '^test spill_run_matches_the_committed_crc \.\.\. ok$' "$log"; then
    echo "error: the spill run's test (core/tests/spill_vector.rs) did not pass on $TARGET" >&2
    exit 1
fi

step "cross-architecture CRCs on $TARGET: the C API's vector_crc under qemu-aarch64"
# libsndt_c.a for aarch64 (release, as a C project links it), then the C program against it.
C_DIR=targets/c
(cd "$C_DIR" && cargo build --release --locked --quiet --target "$TARGET")
prog="$C_DIR/target/$TARGET/vector_crc"
aarch64-linux-gnu-gcc -std=c99 -O2 -Wall -Wextra -Werror -pedantic -I"$C_DIR/include" \
    "$C_DIR/examples/vector_crc.c" "$C_DIR/target/$TARGET/release/libsndt_c.a" -lm -o "$prog"
qemu-aarch64 -L /usr/aarch64-linux-gnu "$prog" "$VECTOR_DIR/frames.bin" | tee -a "$log"
# checked_crc NAME FILE: the last "NAME crc 0x........" vector_crc printed, which must be the
# CRC committed in FILE.
checked_crc() {
    local crc expected
    crc=$(last_hex "$log" "^$1 crc")
    expected=$(committed_crc "$2")
    if [ "$crc" != "$expected" ]; then
        echo "error: aarch64 $1 CRC '${crc:-none}' differs from $2 ($expected)" >&2
        return 1
    fi
    printf '%s\n' "$crc"
}
crc=$(checked_crc snapshot expected_crc.txt)
render=$(checked_crc render expected_render_crc.txt)
awk '/^test result:/ { p += $4; f += $6 } END { printf "\naarch64: %d passed, %d failed\n", p, f }' "$log"
echo "aarch64 (qemu-aarch64): snapshot CRC $crc = expected_crc.txt, render CRC $render = expected_render_crc.txt, spill CRC = expected_spill_crc.txt ($expected_spill, tests/spill_vector.rs); took $((SECONDS - start)) s"
