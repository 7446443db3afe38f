# shellcheck shell=bash
# Shared by the scripts that run the committed test vector (targets/cortex-m4f/vector/) on
# another architecture or through another API and compare the CRCs it gives (firmware.sh,
# c-firmware.sh, c.sh, aarch64.sh), and by those that run firmware on the Cortex-M4F board
# in QEMU (firmware.sh, c-firmware.sh, firmware-profile.sh). Source it
# (`. scripts/lib/vector.sh`) from the repository root.

VECTOR_DIR=targets/cortex-m4f/vector

# committed_crc FILE: the CRC committed in $VECTOR_DIR/FILE (expected_crc.txt, ...) as
# 0x........ in lower case, as the programs print theirs; fails when the file holds anything
# else, so that a damaged file reads as such and not as a CRC mismatch.
committed_crc() {
    local crc
    crc=$(tr -d '[:space:]' <"$VECTOR_DIR/$1")
    if ! [[ $crc =~ ^0x[0-9a-fA-F]{8}$ ]]; then
        echo "error: $VECTOR_DIR/$1 is not 0x........" >&2
        return 1
    fi
    printf '%s\n' "${crc,,}"
}

# last_hex FILE PATTERN: the 0x........ after PATTERN (an extended regular expression) on the
# last line of FILE (- for standard input) that has one; empty when no line has.
last_hex() { grep -oE "$2 0x[0-9a-f]{8}" "$1" | awk '{ print $NF }' | tail -n 1 || true; }

# last_number FILE PATTERN: the same for a decimal number after PATTERN.
last_number() { grep -oE "$2 [0-9]+" "$1" | awk '{ print $NF }' | tail -n 1 || true; }

# run_mps2_an386 SECONDS ELF SERIAL [QEMU OPTION...]: runs the firmware ELF on QEMU's
# mps2-an386 board (Cortex-M4F) for at most SECONDS, UART0 to SERIAL (QEMU's -serial: none,
# file:PATH, ...). The status is the firmware's semihosting exit code, or timeout's 124.
# -icount shift=0: one instruction per virtual nanosecond, so the firmware's SysTick (25 MHz)
# counts exactly one tick per 40 instructions.
run_mps2_an386() {
    local seconds=$1 elf=$2 serial=$3
    shift 3
    timeout "$seconds" qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
        -monitor none -serial "$serial" -semihosting-config enable=on,target=native \
        -icount shift=0 -kernel "$elf" "$@"
}
