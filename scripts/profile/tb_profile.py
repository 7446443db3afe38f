#!/usr/bin/env python3
"""Instruction profile of a QEMU run, from QEMU's own log (`-d in_asm,exec,nochain`).

QEMU translates guest code in translation blocks (TBs) and logs each TB's instructions once
(`IN:`) and every execution of a TB (`Trace ...[.../PC/...]`). With `nochain` every
execution is logged, so instructions executed per address = executions of its TB. The
addresses are then attributed with `llvm-addr2line -i` (inlined chains) to:

- the outermost function (the symbol the code is compiled into),
- the innermost function of a chosen crate (default `sndt_core`), and its file:line,
- software floating point and libm calls, by the line that called them (the last
  instruction of the last TB outside those helpers): on a Cortex-M4F every f64 operation,
  every 64-bit integer to float conversion and `libm::sqrtf` is a library call.

Usage: tb_profile.py LOG ELF [CRATE]   (LOG may be a FIFO; it is read once, streaming)
With PROFILE_ADDRESSES=FILE set, also writes "address executions" per instruction to FILE
(to put beside `llvm-objdump -d`).
"""
import collections
import os
import re
import subprocess
import sys

SOFT = re.compile(r"compiler_builtins|__aeabi|sqrtf|fmaxf|fminf|fmax|fmin|memclr|memcpy|memset")
TRACE = re.compile(r"\[[0-9a-f]+/([0-9a-f]+)/[^\]]*\]\s*(.*)$")
INSN = re.compile(r"0x([0-9a-f]+):")


def read_log(path):
    """(instructions of each TB by start pc, executions per TB pc, soft calls by caller)."""
    tbs, execs, soft = {}, collections.Counter(), collections.Counter()
    block, caller = None, None
    with open(path, errors="replace") as log:
        for line in log:
            if line.startswith("IN:"):
                block = []
                continue
            if block is not None:
                m = INSN.match(line)
                if m:
                    block.append(int(m.group(1), 16))
                    continue
                if block:
                    tbs.setdefault(block[0], block)
                block = None
            if line.startswith("Trace"):
                m = TRACE.search(line)
                if not m:
                    continue
                pc, symbol = int(m.group(1), 16), m.group(2).strip()
                execs[pc] += 1
                if SOFT.search(symbol):
                    soft[(caller, helper_name(symbol))] += len(tbs.get(pc, [pc]))
                else:
                    # The call is the last instruction of the caller's TB.
                    caller = tbs.get(pc, [pc])[-1]
    return tbs, execs, soft


def helper_name(symbol):
    for name in ("adddf3", "muldf3", "divdf3", "subdf3", "sqrtf", "fmaxf", "fminf", "memclr"):
        if name in symbol:
            return name
    m = re.search(r"(__aeabi_\w+|f(max|min)\b)", symbol)
    return m.group(1) if m else symbol[-30:]


def demangle(name):
    name = re.sub(r"::h[0-9a-f]{16}$", "", name)
    for a, b in (("$LT$", "<"), ("$GT$", ">"), ("$C$", ","), ("$u20$", " "),
                 ("$u7b$", "{"), ("$u7d$", "}"), ("..", "::")):
        name = name.replace(a, b)
    return name


def chains(elf, addresses):
    """Inlined call chain (innermost first) of every address: [(function, file:line)]."""
    out = subprocess.run(
        ["llvm-addr2line", "-a", "-f", "-i", "-C", "-e", elf] + [hex(a) for a in addresses],
        capture_output=True, text=True, check=True).stdout.splitlines()
    result, at, i = {}, None, 0
    while i < len(out):
        if re.fullmatch(r"0x[0-9a-f]+", out[i]):
            at = int(out[i], 16)
            result[at] = []
            i += 1
        elif at is not None and i + 1 < len(out):
            result[at].append((demangle(out[i]), out[i + 1].rsplit("/", 1)[-1]))
            i += 2
        else:
            i += 1
    return result


def table(title, counter, total, rows):
    print(f"\n== {title}")
    for key, n in counter.most_common(rows):
        print(f"{n:>13,} {100 * n / total:5.1f}%  {key}")


def main():
    log, elf = sys.argv[1], sys.argv[2]
    crate = sys.argv[3] if len(sys.argv) > 3 else "sndt_core"
    tbs, execs, soft = read_log(log)
    per_address = collections.Counter()
    for pc, n in execs.items():
        for a in tbs.get(pc, [pc]):
            per_address[a] += n
    total = sum(per_address.values())
    print(f"instructions executed: {total:,}")
    if os.environ.get("PROFILE_ADDRESSES"):
        # Executions per instruction address, to annotate a disassembly with.
        with open(os.environ["PROFILE_ADDRESSES"], "w") as out:
            for a in sorted(per_address):
                out.write(f"{a:x} {per_address[a]}\n")
    where = chains(elf, sorted(per_address))
    outer, inner, line = collections.Counter(), collections.Counter(), collections.Counter()
    for a, n in per_address.items():
        chain = where.get(a) or [("?", "?")]
        outer[chain[-1][0]] += n
        own = next(((f, l) for f, l in chain if f.startswith(crate + "::")), None)
        if own:
            inner[own[0]] += n
            line[f"{own[0].rsplit('::', 1)[-1]} {own[1]}"] += n
    table("by outermost function", outer, total, 30)
    table(f"by innermost {crate} function", inner, total, 40)
    table(f"by innermost {crate} function and line", line, total, 40)
    callers = chains(elf, sorted({c for c, _ in soft if c is not None}))
    named = collections.Counter()
    for (c, h), n in soft.items():
        chain = callers.get(c) or [("?", "?")]
        f, l = next(((f, l) for f, l in chain if f.startswith(crate + "::")), chain[-1])
        named[f"{h:<14} <- {f.rsplit('::', 1)[-1]} {l}"] += n
    table("software floating point and libm, by caller", named, total, 25)


if __name__ == "__main__":
    main()
