#!/usr/bin/env bash
# Builds the Cortex-M4F firmware (targets/cortex-m4f), prints its flash and static RAM, and
# runs it under QEMU (mps2-an386) with defmt output decoded by defmt-print. The firmware
# integrates the committed test vector (targets/cortex-m4f/vector/), renders a 64x48 view of
# the map and prints the snapshot CRC, the view's CRC and the peak stack; this script checks
# both CRCs against the host's (`sndt testvector --check`, x86-64) and expected_crc.txt /
# expected_render_crc.txt, and that static RAM + peak stack fit the RAM of memory.x.
# The firmware then runs the spill run: the same frames into the same static map at 9 cm
# cells, which overflows it, every evicted voxel and block sent over UART0 as the core's
# record stream (QEMU writes it to a file, -serial file:...). The host checks that stream
# whole and merges it into a larger map (`sndt testvector --merge-stream`); its CRC must
# equal the host's own spill run (`sndt testvector --spill`) and expected_spill_crc.txt, the
# stream must be the bytes the host's run writes, and the device map's CRC the host's.
# Exits non-zero if anything fails, including the firmware's own checks and a panic call
# site of sndt-core in the ELF (scripts/panic-sites.sh). Installs what it needs when
# missing (idempotent; fast when everything is present).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib/common.sh

FW_DIR=targets/cortex-m4f
ELF="$FW_DIR/target/thumbv7em-none-eabihf/release/sndt-cortex-m4f"
# The budgets are memory.x's FLASH and RAM lengths (in K).
kib_of() { awk -v r="$1" '$1 == r { for (i = 1; i <= NF; i++) if ($i == "LENGTH") { v = $(i + 2); sub(/[Kk],?$/, "", v); print v } }' "$FW_DIR/memory.x"; }
FLASH_BUDGET=$(($(kib_of FLASH) * 1024))
RAM_BUDGET=$(($(kib_of RAM) * 1024))

VECTOR="$VECTOR_DIR/frames.bin"
# The firmware's build lints it (clippy -D warnings, scripts/lib/lint.sh).
lint_in_builds

step "firmware toolchain"
ensure_rust_target thumbv7em-none-eabihf
ensure_packages qemu-system-arm:qemu-system-arm size:binutils
ensure_cargo_tool defmt-print

step "build and lint firmware (release, thumbv7em-none-eabihf)"
# Its own workspace and .cargo/config.toml (target, runner, DEFMT_LOG): build from its dir.
# Its own target dir too, whatever CARGO_TARGET_DIR the caller set, so $ELF is the fresh build.
(cd "$FW_DIR" && CARGO_TARGET_DIR="$PWD/target" cargo build --release --locked)

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

step "panic call sites: none may come from sndt-core"
bash scripts/panic-sites.sh "$ELF"

step "run firmware under QEMU (mps2-an386, Cortex-M4F)"
# UART0 (the spill run's record stream) goes to a file, byte for byte.
# pipefail: the status is QEMU's, i.e. the firmware's semihosting exit code (or timeout's 124).
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
log="$tmp/firmware.log"
uart="$tmp/uart.bin"
run_mps2_an386 120 "$ELF" "file:$uart" | defmt-print -e "$ELF" | tee "$log"

step "cross-architecture CRCs: Cortex-M4F firmware vs host (x86-64) vs expected_*crc.txt"
host_log="$tmp/host.log"
# `--workspace`: features resolved as `cargo test --workspace` resolves them, so the rest of
# the test command uses this build of sndt-host instead of building it again.
cargo build -q --workspace --bin sndt
SNDT="${CARGO_TARGET_DIR:-target}/debug/sndt"
"$SNDT" testvector --check "$VECTOR" >"$host_log"
# check_crc NAME FIRMWARE_TEXT HOST_LINE EXPECTED_FILE: the CRC after FIRMWARE_TEXT in the
# firmware's output and the host's line "HOST_LINE 0x..." must both equal the committed file.
check_crc() {
    local fw host expected
    fw=$(last_hex "$log" "$2")
    host=$(last_hex "$host_log" "^$3")
    expected=$(committed_crc "$4")
    printf '%s CRC: Cortex-M4F (QEMU) %s, host (%s) %s, %s %s\n' \
        "$1" "${fw:-none}" "$(uname -m)" "${host:-none}" "$4" "$expected"
    if [ -z "$fw" ] || [ "$fw" != "$host" ] || [ "$host" != "$expected" ]; then
        echo "error: $1 CRCs differ across architectures" >&2
        return 1
    fi
}
check_crc snapshot 'snapshot crc' 'crc' expected_crc.txt
check_crc render 'render crc' 'render crc' expected_render_crc.txt

step "spill run: the firmware's UART record stream merged on the host vs the host's own run"
spill_log="$tmp/spill.log"
stream_log="$tmp/stream.log"
"$SNDT" testvector --spill "$VECTOR" | tee "$spill_log"
echo
"$SNDT" testvector --merge-stream "$uart" | tee "$stream_log"
fw_spill_bytes=$(last_number "$log" 'spill stream bytes')
uart_bytes=$(wc -c <"$uart")
fw_device=$(last_hex "$log" 'device crc')
stream_device=$(last_hex "$stream_log" 'device crc')
host_device=$(last_hex "$spill_log" 'device crc')
stream_crc=$(last_hex "$stream_log" 'stream crc')
host_stream_crc=$(last_hex "$spill_log" 'stream crc')
merged=$(last_hex "$stream_log" 'spill crc')
own=$(last_hex "$spill_log" 'spill crc')
expected_spill=$(committed_crc expected_spill_crc.txt)
printf '\nUART stream: %d bytes in %s (the firmware sent %s), stream crc %s (host run writes %s)\n' \
    "$uart_bytes" "$(basename "$uart")" "${fw_spill_bytes:-none}" "${stream_crc:-none}" "${host_stream_crc:-none}"
printf 'device map CRC: Cortex-M4F (QEMU) %s, stream end frame %s, host run %s\n' \
    "${fw_device:-none}" "${stream_device:-none}" "${host_device:-none}"
printf 'spill CRC: firmware stream merged on host %s, host own run %s, expected_spill_crc.txt %s\n' \
    "${merged:-none}" "${own:-none}" "$expected_spill"
if [ "$uart_bytes" != "${fw_spill_bytes:-}" ] || [ -z "$stream_crc" ] || [ "$stream_crc" != "$host_stream_crc" ]; then
    echo "error: the UART stream is not the bytes the firmware reported and the host's run writes" >&2
    exit 1
fi
if [ -z "$fw_device" ] || [ "$fw_device" != "$stream_device" ] || [ "$fw_device" != "$host_device" ]; then
    echo "error: the device map's CRC differs between the firmware, its stream and the host" >&2
    exit 1
fi
if [ -z "$merged" ] || [ "$merged" != "$own" ] || [ "$own" != "$expected_spill" ]; then
    echo "error: spill CRCs differ (stream merged vs host run vs expected_spill_crc.txt)" >&2
    exit 1
fi

step "memory report"
peak=$(last_number "$log" 'peak stack')
if [ -z "$peak" ]; then
    echo "error: the firmware did not report its peak stack" >&2
    exit 1
fi
ticks=$(last_number "$log" 'systick per frame')
printf 'flash:             %8d bytes (%d KiB of %d KiB)\n' "$flash" $(((flash + 1023) / 1024)) $((FLASH_BUDGET / 1024))
printf 'static RAM:        %8d bytes\n' "$ram"
printf 'peak stack:        %8d bytes (measured, paint-stack)\n' "$peak"
grep -oE 'spill stream per frame.*' "$log" | tail -n 1 | sed 's/^/firmware: /' || true
printf 'RAM + peak stack:  %8d bytes (%d KiB of %d KiB in memory.x)\n' $((ram + peak)) $(((ram + peak + 1023) / 1024)) $((RAM_BUDGET / 1024))
if [ -n "$ticks" ]; then
    printf 'per frame:         %8d instructions (QEMU -icount: %d SysTick ticks x 40; 19,200 points of 160x120)\n' \
        $((ticks * 40)) "$ticks"
fi
if ((ram + peak > RAM_BUDGET)); then
    echo "error: static RAM + peak stack exceed the RAM budget of memory.x" >&2
    exit 1
fi
echo "firmware: ok"
