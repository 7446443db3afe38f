#!/usr/bin/env bash
# Builds the Cortex-M4F firmware (targets/cortex-m4f), prints its flash and static RAM, and
# runs it under QEMU (mps2-an386) with defmt output decoded by defmt-print. Exits non-zero
# if anything fails, including the firmware's own checks. Installs what it needs when
# missing (idempotent; fast when everything is present).
set -euo pipefail
cd "$(dirname "$0")/.."

FW_DIR=targets/cortex-m4f
ELF="$FW_DIR/target/thumbv7em-none-eabihf/release/sndt-cortex-m4f"
FLASH_BUDGET=$((1024 * 1024))
RAM_BUDGET=$((512 * 1024))

step() { printf '\n==> %s\n' "$*"; }

step "firmware toolchain"
if ! rustup target list --installed | grep -qx thumbv7em-none-eabihf; then
    rustup target add thumbv7em-none-eabihf
fi
if ! command -v qemu-system-arm >/dev/null 2>&1; then
    # The image ships qemu-utils from backports, which conflicts with bookworm's
    # qemu-system-arm: installing the bookworm qemu-utils in the same command keeps qemu-img.
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends --allow-downgrades \
        qemu-system-arm qemu-utils/bookworm
fi
if ! command -v defmt-print >/dev/null 2>&1; then
    cargo install defmt-print --locked
fi
if ! command -v size >/dev/null 2>&1; then
    echo "error: 'size' (binutils) not found" >&2
    exit 1
fi

step "build firmware (release, thumbv7em-none-eabihf)"
# Its own workspace and .cargo/config.toml (target, runner, DEFMT_LOG): build from its dir.
(cd "$FW_DIR" && cargo build --release --locked)

step "firmware size"
# size -A: section sizes in bytes. Flash = everything loaded from flash (vector table, text,
# rodata, initial .data); static RAM = .data + .bss + .uninit.
read -r flash ram < <(size -A "$ELF" | awk '
    $1 == ".vector_table" || $1 == ".text" || $1 == ".rodata" { flash += $2 }
    $1 == ".data" { flash += $2; ram += $2 }
    $1 == ".bss" || $1 == ".uninit" { ram += $2 }
    END { print flash + 0, ram + 0 }')
printf 'flash: %d bytes (%d KiB of %d KiB)\n' "$flash" $(((flash + 1023) / 1024)) $((FLASH_BUDGET / 1024))
printf 'static RAM: %d bytes (%d KiB of %d KiB; the rest is stack)\n' "$ram" $(((ram + 1023) / 1024)) $((RAM_BUDGET / 1024))
if ((flash > FLASH_BUDGET || ram > RAM_BUDGET)); then
    echo "error: firmware exceeds its memory budget" >&2
    exit 1
fi

step "run firmware under QEMU (mps2-an386, Cortex-M4F)"
# pipefail: the status is QEMU's, i.e. the firmware's semihosting exit code (or timeout's 124).
timeout 60 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic -monitor none \
    -serial none -semihosting-config enable=on,target=native -kernel "$ELF" |
    defmt-print -e "$ELF"
echo "firmware: ok"
