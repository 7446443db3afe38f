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

C_DIR=targets/c
FW_SRC="$C_DIR/firmware"
VECTOR_DIR=targets/cortex-m4f/vector
TARGET=thumbv7em-none-eabihf
LIB="$C_DIR/target/$TARGET/release/libsndt_c.a"
BUILD="$C_DIR/target/firmware" # gitignored (target/)
ELF="$BUILD/sndt-c-firmware.elf"

step() { printf '\n==> %s\n' "$*"; }

step "C firmware toolchain"
if ! rustup target list --installed | grep -qx "$TARGET"; then
    rustup target add "$TARGET"
fi
# picolibc.specs is found through the compiler's search path (-print-file-name prints the
# bare name when it is missing).
have_picolibc() {
    command -v arm-none-eabi-gcc >/dev/null 2>&1 &&
        [ -f "$(arm-none-eabi-gcc -print-file-name=picolibc.specs)" ]
}
if ! have_picolibc; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends gcc-arm-none-eabi picolibc-arm-none-eabi
fi
if ! command -v qemu-system-arm >/dev/null 2>&1; then
    # As scripts/firmware.sh: the image ships qemu-utils from backports, which conflicts with
    # bookworm's qemu-system-arm; installing the bookworm qemu-utils alongside keeps qemu-img.
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends --allow-downgrades \
        qemu-system-arm qemu-utils/bookworm
fi

step "build libsndt_c.a (release, $TARGET)"
# Its own workspace and lockfile; its own target dir whatever CARGO_TARGET_DIR says, so $LIB
# is the fresh build.
(cd "$C_DIR" && CARGO_TARGET_DIR="$PWD/target" cargo build --release --locked --target "$TARGET")

step "build C firmware"
# The expected CRCs, compiled in: the firmware's exit status is its own verdict.
crc_of() {
    local v
    v=$(tr -d '[:space:]' <"$VECTOR_DIR/$1")
    if ! [[ $v =~ ^0x[0-9a-fA-F]{8}$ ]]; then
        echo "error: $VECTOR_DIR/$1 is not 0x........" >&2
        return 1
    fi
    printf '%s\n' "${v,,}"
}
expected_crc=$(crc_of expected_crc.txt)
expected_render_crc=$(crc_of expected_render_crc.txt)
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
printf 'static RAM: %8d bytes (%d KiB of 512 KiB; .bss %d bytes, the map 485,512 of it), stack region %d bytes\n' \
    "$ram" $(((ram + 1023) / 1024)) "$(printf '%s\n' "$size_report" | awk '$1 == ".bss" { print $2 }')" "$stack"
if ((flash > 1024 * 1024 || ram + stack > 512 * 1024)); then
    echo "error: the C firmware exceeds its memory budget" >&2
    exit 1
fi

step "run C firmware under QEMU (mps2-an386, Cortex-M4F)"
# -icount shift=0: one instruction per virtual nanosecond, so SysTick (25 MHz) counts one
# tick per 40 instructions. The exit status is the firmware's (semihosting) or timeout's 124.
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
status=0
timeout 60 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic -monitor none \
    -serial none -semihosting-config enable=on,target=native -icount shift=0 \
    -kernel "$ELF" >"$log" 2>&1 || status=$?
cat "$log"

step "check"
# The last "NAME 0x........" line of the firmware's output.
crc_line() { grep -oE "^$1 0x[0-9a-f]{8}" "$log" | awk '{ print $NF }' | tail -n 1 || true; }
snapshot=$(crc_line 'snapshot crc')
render=$(crc_line 'render crc')
printf 'snapshot crc: C firmware %s, expected_crc.txt %s\n' "${snapshot:-none}" "$expected_crc"
printf 'render crc:   C firmware %s, expected_render_crc.txt %s\n' "${render:-none}" "$expected_render_crc"
peak=$(grep -oE 'peak stack [0-9]+' "$log" | awk '{ print $3 }' | tail -n 1 || true)
ticks=$(grep -oE 'systick per frame [0-9]+' "$log" | awk '{ print $4 }' | tail -n 1 || true)
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
