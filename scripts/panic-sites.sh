#!/usr/bin/env bash
# Counts the panic call sites in a firmware ELF and fails if any of them comes from sndt-core.
#
# Usage: scripts/panic-sites.sh ELF
#
# A call site is a `bl`/`b.w` to one of core's panic entry points (panic_fmt,
# panic_bounds_check, slice_index_fail, unwrap_failed, ...). The ELF's debug info tells, for
# every such call, the chain of functions inlined into it; a site counts as the core's when
# any function of that chain is in `sndt_core`. The core promises never to halt the
# co-processor: every index it takes is proven in range by construction, so the compiler
# drops the bounds check and no panic call remains. Sites of the firmware itself (its own
# slicing, RefCell borrows, ...) are listed, not failed. Needs llvm-objdump and
# llvm-addr2line (Debian's `llvm`, installed when missing).
set -euo pipefail

elf="${1:?usage: panic-sites.sh ELF}"
# From where it is, not the repository root: ELF is relative to the caller's directory.
# shellcheck source=scripts/lib/common.sh
. "$(dirname "$0")/lib/common.sh"
ensure_packages llvm-objdump:llvm llvm-addr2line:llvm

# Panic entry points: the functions a failed check calls (names as llvm-objdump -C prints).
panic_fn='panic|_fail(ed)?$|assert_failed'

dis="$(mktemp)"
chains="$(mktemp)"
trap 'rm -f "$dis" "$chains"' EXIT
llvm-objdump -d --no-show-raw-insn -C "$elf" >"$dis"

# Call sites: direct calls and tail branches to an entry point, from outside the entry points
# themselves (panic_fmt calling the panic handler is not a site).
mapfile -t sites < <(awk -v pat="$panic_fn" '
    function symbol(line) { sub(/^[^<]*</, "", line); sub(/>[^>]*$/, "", line); return line }
    /^[0-9a-f]+ <.*>:$/ { inside = (symbol($0) ~ pat); next }
    !inside && $2 ~ /^(bl|b|b\.w)$/ && /</ && symbol($0) ~ pat { sub(":", "", $1); print "0x" $1 }
' "$dis")

if ((${#sites[@]} > 0)); then
    # -a: each chain starts with its address; -i: inlined frames, innermost first.
    llvm-addr2line -a -f -i -C -e "$elf" "${sites[@]}" >"$chains"
fi

# One line per site: "core|firmware ADDRESS FUNCTION (file:line)": the innermost frame of
# sndt_core when the chain has one (the core function that holds the check), else the
# innermost frame outside the standard library.
awk '
    # Legacy Rust symbols as addr2line leaves them: drop the hash, decode the escapes.
    function demangle(s) {
        sub(/::h[0-9a-f]+$/, "", s)
        gsub(/\$LT\$/, "<", s); gsub(/\$GT\$/, ">", s); gsub(/\$C\$/, ",", s)
        gsub(/\$u20\$/, " ", s); gsub(/\$u7b\$/, "{", s); gsub(/\$u7d\$/, "}", s)
        gsub(/\.\./, "::", s); sub(/^_</, "<", s)
        return s
    }
    function flush() {
        if (addr == "") return
        if (core != "") printf "core %s %s (%s)\n", addr, core, core_at
        else printf "firmware %s %s (%s)\n", addr, last, last_at
        addr = ""; core = ""; last = ""
    }
    /^0x[0-9a-f]+$/ { flush(); addr = $0; expect_fn = 1; next }
    expect_fn { fn = $0; expect_fn = 0; next }
    {
        at = $0; sub(/.*\//, "", at)
        name = demangle(fn)
        if (core == "" && name ~ /^sndt_core::/) { core = name; core_at = at }
        # For the firmware'"'"'s own sites: the innermost frame outside the standard library.
        if (last == "" && name !~ /^_?<?(core|alloc)::/) { last = name; last_at = at }
        expect_fn = 1
    }
    END { flush() }
' "$chains" | sort -k3 >"$dis"

core_sites=$(grep -c '^core ' "$dis" || true)
fw_sites=$(grep -c '^firmware ' "$dis" || true)
echo "panic call sites in $(basename "$elf"): $((core_sites + fw_sites))"
if ((fw_sites > 0)); then
    echo "  of the firmware itself: $fw_sites"
    grep '^firmware ' "$dis" | cut -d' ' -f3- | sort | uniq -c | sed 's/^/   /'
fi
echo "panic sites in sndt_core: $core_sites"
if ((core_sites > 0)); then
    grep '^core ' "$dis" | cut -d' ' -f3- | sort | uniq -c | sed 's/^/   /'
    echo "error: sndt-core code can panic on the MCU (sites above)" >&2
    exit 1
fi
