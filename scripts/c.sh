#!/usr/bin/env bash
# The C API (targets/c): Rust fmt, clippy (inside its builds) and unit tests of sndt-c;
# the committed header include/sndt.h against a fresh cbindgen generation (drift check);
# the C99 and C++17 host programs built with CMake (-Wall -Wextra -Werror -pedantic) and
# run by ctest: the test vector's snapshot and render CRCs from C, the snapshot CRC from
# C++, and the bad calls from C; then the bare C firmware on Cortex-M4F in QEMU
# (scripts/c-firmware.sh). Installs what it needs when missing (cmake via apt-get,
# cbindgen via cargo install); idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

C_DIR=targets/c
CBINDGEN_VERSION=0.29.4
BUILD="$C_DIR/target/cmake"

# Every build of sndt-c lints it (clippy -D warnings, scripts/lib/lint.sh): the unit tests'
# build on the host, and the thumbv7em-none-eabihf build of scripts/c-firmware.sh.
lint_in_builds

step "C toolchain: cmake, a C and C++ compiler, cbindgen $CBINDGEN_VERSION"
ensure_packages cmake:cmake make:make cc:gcc g++:g++
ensure_rust_target thumbv7em-none-eabihf
ensure_cargo_tool cbindgen "$CBINDGEN_VERSION"

step "sndt-c: fmt, unit tests (built and linted)"
(cd "$C_DIR" && cargo fmt --check && cargo test --locked --quiet)

step "header drift: include/sndt.h against a fresh cbindgen"
fresh="$(mktemp)"
trap 'rm -f "$fresh"' EXIT
(cd "$C_DIR" && cbindgen --quiet --config cbindgen.toml --output "$fresh")
if ! diff -u "$C_DIR/include/sndt.h" "$fresh"; then
    echo "error: targets/c/include/sndt.h is stale: regenerate it with" >&2
    echo "  (cd targets/c && cbindgen --config cbindgen.toml --output include/sndt.h)" >&2
    exit 1
fi
echo "include/sndt.h: up to date"

step "C99 and C++17 host programs (CMake, -Wall -Wextra -Werror -pedantic), ctest"
cmake -S "$C_DIR" -B "$BUILD" -DSNDT_EXAMPLES=ON -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD" -j 2
(cd "$BUILD" && ctest --output-on-failure)

step "the C program of docs/C_API.md compiles (C99, -Wall -Wextra -Werror -pedantic)"
awk '/^## A first program/ { s = 1 } s && /^```c$/ { c = 1; next } c && /^```$/ { exit } c' \
    docs/C_API.md >"$BUILD/first_program.c"
test -s "$BUILD/first_program.c"
cc -std=c99 -Wall -Wextra -Werror -pedantic -I"$C_DIR/include" -c "$BUILD/first_program.c" \
    -o "$BUILD/first_program.o"
echo "docs/C_API.md example: compiles"

step "CRCs from C and C++ against the Rust test vector's"
want=$(committed_crc expected_crc.txt)
want_render=$(committed_crc expected_render_crc.txt)
c_out=$("$BUILD/vector_crc" "$VECTOR_DIR/frames.bin")
cpp_out=$("$BUILD/vector_crc_cpp" "$VECTOR_DIR/frames.bin")
c_crc=$(last_hex - '^snapshot crc' <<<"$c_out")
c_render=$(last_hex - '^render crc' <<<"$c_out")
cpp_crc=$(last_hex - '^snapshot crc' <<<"$cpp_out")
printf 'snapshot CRC: C %s, C++ %s, expected_crc.txt %s\n' "${c_crc:-none}" "${cpp_crc:-none}" "$want"
printf 'render CRC:   C %s, expected_render_crc.txt %s\n' "${c_render:-none}" "$want_render"
if [ "$c_crc" != "$want" ] || [ "$cpp_crc" != "$want" ] || [ "$c_render" != "$want_render" ]; then
    echo "error: the C API gives other CRCs than the Rust test vector" >&2
    exit 1
fi

step "C firmware on Cortex-M4F in QEMU"
bash scripts/c-firmware.sh
echo "c api: ok"
