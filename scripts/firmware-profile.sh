#!/usr/bin/env bash
# Where the Cortex-M4F firmware spends its instructions (opt-in; not part of the test
# command). Runs the firmware built by scripts/firmware.sh under QEMU with its execution log
# (-d in_asm,exec,nochain) streamed through a FIFO into scripts/profile/tb_profile.py, which
# counts the instructions executed per address and attributes them to functions, inlined
# sndt-core functions and lines (llvm-addr2line -i), and software floating point calls to
# their callers. The whole firmware run is profiled: setup, the 4 frames, probes, CRC and
# the 64x48 view. Takes about a minute.
#
# Usage: bash scripts/firmware-profile.sh [--frames | ELF]
#   --frames  builds the firmware with its `frames-only` feature (own target dir) and
#             profiles the 4 frames alone: setup and frames, no probes, CRC or view.
# PROFILE_ADDRESSES=FILE also writes the executions of every instruction address to FILE.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

ELF="${1:-targets/cortex-m4f/target/thumbv7em-none-eabihf/release/sndt-cortex-m4f}"
if [[ "$ELF" == --frames ]]; then
    (cd targets/cortex-m4f && CARGO_TARGET_DIR="$PWD/target-frames" \
        cargo build --release --locked --quiet --features frames-only)
    ELF=targets/cortex-m4f/target-frames/thumbv7em-none-eabihf/release/sndt-cortex-m4f
fi
if [[ ! -f "$ELF" ]]; then
    echo "error: $ELF not found; build it with bash scripts/firmware.sh" >&2
    exit 1
fi
ensure_packages qemu-system-arm:qemu-system-arm llvm-addr2line:llvm python3:python3

dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
mkfifo "$dir/log"
python3 scripts/profile/tb_profile.py "$dir/log" "$ELF" &
reader=$!
run_mps2_an386 600 "$ELF" none -d in_asm,exec,nochain -D "$dir/log" >/dev/null
wait "$reader"
