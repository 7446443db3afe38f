#!/usr/bin/env bash
# Builds the bare-metal C firmware (targets/c/firmware: C99 over the sndt C API, linked with
# libsndt_c.a built for thumbv7em-none-eabihf, picolibc with semihosting stdio), prints its
# flash and static RAM, and runs it under QEMU (mps2-an386, Cortex-M4F). The firmware
# integrates the committed test vector (targets/cortex-m4f/vector/frames.bin), renders a
# 64x48 view and prints the snapshot CRC and the view's CRC; this script checks both against
# expected_crc.txt / expected_render_crc.txt, that QEMU exits 0 (the firmware's own
# verdict, semihosting) and that no panic call site comes from sndt-core. Installs what it needs when missing (idempotent; fast when present).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

C_DIR=targets/c
FW_SRC="$C_DIR/firmware"
TARGET=thumbv7em-none-eabihf
LIB="$C_DIR/target/$TARGET/release/libsndt_c.a"
BUILD="$C_DIR/target/firmware" # gitignored (target/)
ELF="$BUILD/sndt-c-firmware.elf"


step "C firmware toolchain"
ensure_rust_target "$TARGET"
ensure_packages arm-none-eabi-gcc:gcc-arm-none-eabi picolibc-arm-none-eabi \
    qemu-system-arm:qemu-system-arm

step "build libsndt_c.a (release, $TARGET)"
# Its own workspace and lockfile; its own target dir whatever CARGO_TARGET_DIR says, so $LIB
# is the fresh build.
(cd "$C_DIR" && CARGO_TARGET_DIR="$PWD/target" cargo build --release --locked --target "$TARGET")

step "build C firmware"
# The expected CRCs, compiled in: the firmware's exit status is its own verdict.
expected_crc=$(committed_crc expected_crc.txt)
expected_render_crc=$(committed_crc expected_render_crc.txt)
mkdir -p "$BUILD"
# Cortex-M4F, hard float (the ABI of libsndt_c.a); picolibc with semihosting as the OS layer,
# crt0-semihost (reports HardFaults and exits instead of hanging).
ARCH=(-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16)
PICOLIBC=(--specs=picolibc.specs --oslib=semihost --crt0=semihost)
arm-none-eabi-gcc "${ARCH[@]}" "${PICOLIBC[@]}" -O2 -g -std=c99 -Wall -Wextra -Werror -pedantic \
    -ffunction-sections -fdata-sections -I"$C_DIR/include" \
    -DEXPECTED_CRC="$expected_crc" -DEXPECTED_RENDER_CRC="$expected_render_crc" \
    -c "$FW_SRC/main.c" -o "$BUILD/main.o"
# vector.S .incbin's frames.bin from the assembler's include path.
arm-none-eabi-gcc "${ARCH[@]}" "${PICOLIBC[@]}" -Wa,-I,"$VECTOR_DIR" \
    -c "$FW_SRC/vector.S" -o "$BUILD/vector.o"
# mps2-an386.ld sets the memory budget and includes picolibc.ld. Integer-only printf (no
# floats printed). -z noexecstack: some picolibc objects lack a .note.GNU-stack section.
arm-none-eabi-gcc "${ARCH[@]}" "${PICOLIBC[@]}" -DPICOLIBC_INTEGER_PRINTF_SCANF \
    -T "$FW_SRC/mps2-an386.ld" -Wl,-z,noexecstack -Wl,-Map="$BUILD/sndt-c-firmware.map" \
    -o "$ELF" "$BUILD/main.o" "$BUILD/vector.o" "$LIB"

step "panic call sites: none may come from sndt-core (the C API's Rust code is listed)"
bash scripts/panic-sites.sh "$ELF"

step "C firmware size"
# size -A: section sizes in bytes. Flash = what is loaded from flash (.init: vector table and
# reset code, .text with .rodata, initial .data/.tdata); static RAM = .data + .tdata + TLS
# .bss + .bss (.tbss is a TLS view of .tbss_space, not counted twice).
size_report=$(arm-none-eabi-size -A "$ELF")
printf '%s\n' "$size_report" | awk '$1 ~ /^\.(init|text|rodata|data|tdata|tbss_space|bss|stack)$/'
read -r flash ram stack < <(printf '%s\n' "$size_report" | awk '
    $1 == ".init" || $1 == ".text" || $1 == ".rodata" { flash += $2 }
    $1 == ".data" || $1 == ".tdata" { flash += $2; ram += $2 }
    $1 == ".tbss_space" || $1 == ".bss" { ram += $2 }
    $1 == ".stack" { stack += $2 }
    END { print flash + 0, ram + 0, stack + 0 }')
vector_bytes=$(stat -c %s "$VECTOR_DIR/frames.bin")
printf 'flash:      %8d bytes (%d KiB of 1024 KiB; %d of it the test vector)\n' \
    "$flash" $(((flash + 1023) / 1024)) "$vector_bytes"
printf 'static RAM: %8d bytes (%d KiB of 512 KiB; .bss %d bytes, the map 485,520 of it), stack region %d bytes\n' \
    "$ram" $(((ram + 1023) / 1024)) "$(printf '%s\n' "$size_report" | awk '$1 == ".bss" { print $2 }')" "$stack"
if ((flash > 1024 * 1024 || ram + stack > 512 * 1024)); then
    echo "error: the C firmware exceeds its memory budget" >&2
    exit 1
fi

step "run C firmware under QEMU (mps2-an386, Cortex-M4F)"
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
status=0
run_mps2_an386 60 "$ELF" none >"$log" 2>&1 || status=$?
cat "$log"

step "check"
snapshot=$(last_hex "$log" '^snapshot crc')
render=$(last_hex "$log" '^render crc')
printf 'snapshot crc: C firmware %s, expected_crc.txt %s\n' "${snapshot:-none}" "$expected_crc"
printf 'render crc:   C firmware %s, expected_render_crc.txt %s\n' "${render:-none}" "$expected_render_crc"
peak=$(last_number "$log" 'peak stack')
ticks=$(last_number "$log" 'systick per frame')
if [ -n "$peak" ]; then
    printf 'peak stack: %d bytes (measured, painted); static RAM + peak stack %d bytes of 512 KiB\n' \
        "$peak" $((ram + peak))
fi
if [ -n "$ticks" ]; then
    printf 'per frame:  %d instructions (QEMU -icount: %d SysTick ticks x 40; 19,200 points of 160x120)\n' \
        $((ticks * 40)) "$ticks"
fi
if [ "$status" -ne 0 ]; then
    echo "error: QEMU exited with status $status (124: timeout)" >&2
    exit 1
fi
if [ "$snapshot" != "$expected_crc" ] || [ "$render" != "$expected_render_crc" ]; then
    echo "error: the C firmware's CRCs differ from the expected ones" >&2
    exit 1
fi
echo "c firmware: ok"
