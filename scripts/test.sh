#!/usr/bin/env bash
# The whole test suite: formatting, lints, docs, the no_std build for Cortex-M4F, the
# firmware in QEMU and the core's tests on aarch64 (qemu-aarch64) with one snapshot CRC on
# all three architectures, the C API (header drift, C and C++ programs, C firmware in
# QEMU), ROS 2 bags against the Python mcap packages, OctoMap exports read back by
# liboctomap and compared voxel by voxel, every test (unit, property, integration, doc), and
# the Python package (built and installed by pip, tested by pytest against the command line).
# Clippy's lints run inside the builds (scripts/lib/lint.sh). Installs what it needs;
# idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

step "toolchain components and targets"
rustup component add rustfmt clippy >/dev/null 2>&1 || true
ensure_rust_target thumbv7em-none-eabihf

# Every build below lints the crates it compiles, as `cargo clippy -- -D warnings` would
# (scripts/lib/lint.sh): one compilation per crate instead of a check and a build.
lint_in_builds
# Builds here start from nothing on CI: incremental compilation only adds work to those.
export CARGO_INCREMENTAL=0

# Background jobs (below) run in sessions of their own, so that a failing step stops each
# with everything it started; their logs go to $tmp.
bg_pids=()
tmp="$(mktemp -d)"
cleanup() {
    local pid
    for pid in "${bg_pids[@]}"; do kill -- "-$pid" 2>/dev/null || true; done
    rm -rf "$tmp"
}
trap cleanup EXIT
# background NAME COMMAND...: starts COMMAND with its output in $tmp/NAME.log.
background() {
    local name=$1
    shift
    setsid "$@" >"$tmp/$name.log" 2>&1 &
    bg_pids+=("$!")
    printf -v "${name}_pid" %s "$!"
}
# await NAME: waits for the background job NAME, prints its output, fails if it failed.
await() {
    local rc=0 pid_var="${1}_pid"
    wait "${!pid_var}" || rc=$?
    cat "$tmp/$1.log"
    if [ "$rc" -ne 0 ]; then
        echo "error: the background job '$1' failed (exit $rc)" >&2
        exit 1
    fi
}

step "cargo fmt --check"
cargo fmt --all -- --check

# The Python venvs of the ROS 2, OctoMap and Python steps are downloads, not CPU: they fill
# while the workspace compiles.
step "in the background: the Python venvs (target/ros-venv, target/python-venv)"
# shellcheck disable=SC2016 # expanded by the inner shell
background venvs bash -c '. scripts/lib/install.sh && ensure_ros_venv target/ros-venv &&
    ensure_python_venv "${CARGO_TARGET_DIR:-$PWD/target}/python-venv"'

step "build and lint the workspace: tests, binaries, examples, benches (clippy -D warnings)"
cargo test --workspace --no-run
cargo test --workspace --benches --no-run
# The Python package is built (and linted) by pip in its own step, as a Python module.

step "the Python venvs"
await venvs

# The fuzz smoke builds in its own target directory (fuzz/target), so it runs beside the
# next steps, which spend much of their time in one process at a time (QEMU, Python, C++,
# libFuzzer) on the 2 cores. Its C++ compiler is installed first, in the foreground, as
# apt-get takes one install at a time.
step "in the background: fuzzing smoke (fmt, a linted instrumented build, every target)"
ensure_packages c++:g++
background fuzz bash scripts/fuzz.sh --smoke

step "sndt-core builds and lints for thumbv7em-none-eabihf (no_std, no alloc)"
cargo build -p sndt-core --target thumbv7em-none-eabihf --release
cargo build -p sndt-core --target thumbv7em-none-eabihf --release --features defmt

step "Cortex-M4F firmware: fmt, clippy, build, size, run in QEMU, CRC vs host, memory report"
(cd targets/cortex-m4f && cargo fmt --check && cargo clippy --release --locked --features rtt -- -D warnings)
bash scripts/firmware.sh

step "C API: header drift, C99 and C++17 programs (same CRCs), bad calls, C firmware in QEMU"
bash scripts/c.sh

step "ROS 2 bags: a bag written by Python maps like the prepared layout; map bags read back by Python"
bash scripts/ros.sh

step "OctoMap: .bt, .ot and the map bag's message read by liboctomap, every leaf against sndt's map"
bash scripts/octomap.sh

step "OctoMap on the dynamic room: the same world points, its frames to clear and static loss"
bash scripts/dynamics.sh

step "aarch64: sndt-core tests (unit, property, doc) and the CRC check under qemu-aarch64"
bash scripts/aarch64.sh

step "sndt-dispatch built for baseline x86-64: SSE2 by runs, AVX2 and AVX-512 by voxel, the same map"
# The workspace builds for this CPU (.cargo/config.toml); RUSTFLAGS="" builds the baseline
# that crates depending on sndt get, whose as-built level is SSE2.
if [ "$(uname -m)" = x86_64 ]; then
    RUSTFLAGS="" cargo test -p sndt-dispatch --test same_bits --target-dir target/baseline
else
    echo "not an x86-64 machine: skipped"
fi

step "fuzzing smoke: every target over its corpus plus bounded runs (run beside the steps above)"
await fuzz

step "cargo doc without warnings"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --quiet

step "cargo test (workspace: unit, property, integration, doc tests)"
log="$tmp/test.log"
cargo test --workspace 2>&1 | tee "$log"
step "Python package: pip install ./python, pytest against the command line, the example"
bash scripts/python.sh

echo "the test command took $SECONDS s"
# One closing line over all test binaries (cargo prints one summary per binary).
awk '/^test result:/ { p += $4; f += $6 } END { printf "\nsndt: %d passed, %d failed\n", p, f }' "$log"
