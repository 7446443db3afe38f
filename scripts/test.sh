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

# Each step's banner says when it started (seconds since the start), so a slow step shows.
step() { printf '\n==> %s (at %d s)\n' "$*" "$SECONDS"; }

step "toolchain components and targets"
rustup component add rustfmt clippy >/dev/null 2>&1 || true
if ! rustup target list --installed | grep -qx thumbv7em-none-eabihf; then
    rustup target add thumbv7em-none-eabihf
fi

# Every build below lints the crates it compiles, as `cargo clippy -- -D warnings` would
# (scripts/lib/lint.sh): one compilation per crate instead of a check and a build.
. scripts/lib/lint.sh
lint_in_builds
# Builds here start from nothing on CI: incremental compilation only adds work to those.
export CARGO_INCREMENTAL=0

step "cargo fmt --check"
cargo fmt --all -- --check

step "build and lint the workspace, every target (clippy -D warnings while it compiles)"
cargo test --workspace --all-targets --no-run

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

step "aarch64: sndt-core tests (unit, property, doc) and the CRC check under qemu-aarch64"
bash scripts/aarch64.sh

step "fuzzing smoke: fmt and clippy of fuzz/, every target over its corpus plus bounded runs"
bash scripts/fuzz.sh --smoke

step "cargo doc without warnings"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --quiet

step "cargo test (workspace: unit, property, integration, doc tests)"
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
cargo test --workspace 2>&1 | tee "$log"
step "Python package: pip install ./python, pytest against the command line, the example"
bash scripts/python.sh

echo "the test command took $SECONDS s"
# One closing line over all test binaries (cargo prints one summary per binary).
awk '/^test result:/ { p += $4; f += $6 } END { printf "\nsndt: %d passed, %d failed\n", p, f }' "$log"
