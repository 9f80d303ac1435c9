#!/usr/bin/env python3
"""Per-call instruction mix of one profile-driver entry and the throughput bounds it implies.

Reads two callgrind outputs of the profile driver (example `profile`,
`crates/krang-dynamics/benches/profile/functions.rs`; the same entry run for N1 and N2 calls,
`--dump-instr=yes --compress-pos=no --compress-strings=no`), takes the difference of the
execution counts of every instruction (so the driver's start-up cancels), divides by N2 - N1,
disassembles each executed instruction with objdump and sorts it into the execution resources
it needs on an Intel Golden Cove core (Sapphire Rapids):

  fma      multiplies and fused multiply-adds, scalar or vector: ports 0 and 1 only
  fadd     additions, subtractions, compares, min/max: ports 1 and 5 (and 0)
  shuffle  lane moves: shuffles, unpacks, permutes, broadcasts from a register, inserts and
           extracts, the register half of a `vmovhpd`/`vmovlpd` load: port 5 (some also 1)
  logic    vector and/xor/or/blend, register merges (`vmovsd x, y, z`): ports 0, 1 and 5
  int      integer ALU work and branches: ports 0, 1, 5, 6 and 10
  load     a memory source operand (3 per cycle), store: a memory destination (2 per cycle)
  string   bytes set or copied by `rep stosb`/`rep movsb` (callgrind counts each byte): taken
           as one instruction and one store per 32 bytes

and prints, per call, the counts and five lower bounds in cycles: the 6-wide rename
(instructions / 6), the two multiply-add ports (fma / 2), the three vector ports
((fma + fadd + shuffle + logic) / 3), the loads (/ 3) and the stores (/ 2). Register-to-register
moves (`vmovapd x, y`) are eliminated at rename and need no port. The code's time cannot be
below the largest bound at any clock; the dependency chains can make it longer.

Usage: port_bound.py CALLGRIND_N1 N1 CALLGRIND_N2 N2 [GHZ NS]
(with GHZ and NS, the measured time per call in cycles beside the bounds).
"""

import re
import subprocess
import sys
from collections import Counter, defaultdict


def parse(path, functions=None):
    """{object: {address: Ir}} from a callgrind output with absolute positions (and, given a
    dict `functions`, each address's function name in it)."""
    counts = defaultdict(Counter)
    obj = None
    fn = None
    skip_next = False
    with open(path) as f:
        for line in f:
            if line.startswith("ob="):
                obj = line[3:].strip()
                continue
            if line.startswith("fn="):
                fn = line[3:].strip()
                continue
            if line.startswith("calls="):
                skip_next = True  # the next cost line is the call's inclusive cost
                continue
            if line.startswith("0x"):
                if skip_next:
                    skip_next = False
                    continue
                parts = line.split()
                counts[obj][int(parts[0], 16)] += int(parts[-1])
                if functions is not None:
                    functions[(obj, int(parts[0], 16))] = fn
    return counts


def disassemble(obj, addresses):
    """{address: (mnemonic, operands)} for the given addresses of `obj` (AT&T syntax)."""
    lo, hi = min(addresses), max(addresses) + 16
    out = subprocess.run(
        ["objdump", "-d", "--no-show-raw-insn", "-M", "att",
         f"--start-address={lo:#x}", f"--stop-address={hi:#x}", obj],
        capture_output=True, text=True, check=True,
    ).stdout
    table = {}
    for line in out.splitlines():
        m = re.match(r"^\s*([0-9a-f]+):\t(\S+)\s*(.*)$", line)
        if m:
            ops = re.sub(r"\s+#.*$", "", m.group(3)).strip()
            table[int(m.group(1), 16)] = (m.group(2), ops)
    return table


FMA = re.compile(r"^v?(mul|fn?m(add|sub)\d*|div|sqrt)[sp][sd]$")
FADD = re.compile(r"^v?(add|sub|min|max|cmp\w*|round|hadd|hsub)[sp][sd]$")
SHUFFLE = re.compile(
    r"^v(shuf|unpck\w+|perm\w+|insertf128|inserti128|extractf128|extracti128|movddup|"
    r"movhlps|movlhps|pshufd|pshufb|broadcast\w+)"
)
LOGIC = re.compile(r"^v?p?(xor|and|andn|or|blend\w*)(p[sd])?$|^vp(xor|and|or|andn)[dq]?$")
MOVES = re.compile(r"^v?mov(apd|aps|upd|ups|dqa|dqu|dqa64|dqu64|sd|ss|q|d|hpd|lpd|hps|lps)$")
BRANCH = re.compile(r"^(j\w+|call\w*|ret\w*)$")
# `rep`-prefixed string instructions (`rep stosb`/`rep movsb`: a `memset`/`memcpy`), which
# callgrind counts once per byte; the fast string microcode moves about 32 bytes per store.
REP_STRING = ("rep", "repz", "repnz", "repe", "repne")
STRING_BYTES_PER_STORE = 32


def operands(ops):
    """Split AT&T operands at top-level commas."""
    parts, depth, cur = [], 0, ""
    for ch in ops:
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(cur.strip())
            cur = ""
        else:
            cur += ch
    if cur.strip():
        parts.append(cur.strip())
    return parts


def classify(mnemonic, ops):
    """Counter of resources one execution of the instruction uses."""
    c = Counter()
    parts = operands(ops)
    is_mem = [("(" in p) for p in parts]
    dest_mem = bool(parts) and is_mem[-1]
    src_mem = any(is_mem[:-1]) if parts else False
    base = mnemonic.split("{")[0]
    if base in REP_STRING:
        c["string"] += 1
        c["store"] += 1 / STRING_BYTES_PER_STORE
        return c
    if base.startswith("nop") or base in ("endbr64", "vzeroupper", "data16", "cs"):
        c["other"] += 1
        return c
    if base.startswith("lea"):
        c["int"] += 1  # an address computed, no memory read
        return c
    if base in ("push",):
        c["store"] += 1
        return c
    if base in ("pop",):
        c["load"] += 1
        return c
    if BRANCH.match(base):
        c["int"] += 1
        if base.startswith("call"):
            c["store"] += 1
        if base.startswith("ret"):
            c["load"] += 1
        return c
    if MOVES.match(base):
        if dest_mem:
            c["store"] += 1
        elif src_mem:
            c["load"] += 1
            if base in ("vmovhpd", "vmovlpd", "vmovhps", "vmovlps", "movhpd", "movlpd"):
                c["shuffle"] += 1  # merged into a register half
        elif base in ("vmovsd", "vmovss") and len(parts) == 3:
            c["logic"] += 1  # a register merge
        elif base in ("vmovq", "vmovd", "movq", "movd"):
            c["logic"] += 1
        else:
            c["eliminated"] += 1
        return c
    if base.startswith("vextract") and dest_mem:
        c["store"] += 1
        return c
    if src_mem:
        c["load"] += 1
    if dest_mem:
        c["load"] += 1
        c["store"] += 1
    if FMA.match(base):
        c["fma"] += 1
    elif FADD.match(base):
        c["fadd"] += 1
    elif base.startswith("vbroadcast") and src_mem:
        pass  # a broadcast load needs only the load port
    elif base == "vmovddup" and src_mem:
        pass
    elif SHUFFLE.match(base):
        c["shuffle"] += 1
    elif LOGIC.match(base):
        c["logic"] += 1
    elif base.startswith("v"):
        c["vector-other"] += 1
    elif base.startswith("mov"):
        if not (src_mem or dest_mem):
            c["int"] += 1
    else:
        c["int"] += 1
    return c


def main():
    if len(sys.argv) not in (5, 7):
        sys.exit(__doc__)
    a, n1, b, n2 = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
    names = {}
    ca, cb = parse(a), parse(b, names)
    per_call = defaultdict(dict)
    for obj in cb:
        for addr, ir in cb[obj].items():
            d = (ir - ca.get(obj, {}).get(addr, 0)) / (n2 - n1)
            if d > 0.5:
                per_call[obj][addr] = d
    totals = Counter()
    by_function = defaultdict(Counter)
    by_mnemonic = Counter()
    instructions = 0.0
    for obj, addrs in per_call.items():
        if not addrs or not obj.startswith("/"):
            continue
        table = disassemble(obj, list(addrs))
        for addr, n in addrs.items():
            if addr not in table:
                totals["unknown"] += n
                continue
            mnemonic, ops = table[addr]
            executed = n / STRING_BYTES_PER_STORE if mnemonic in REP_STRING else n
            function = by_function[names.get((obj, addr), "?")]
            instructions += executed
            by_mnemonic[mnemonic] += executed
            function["instructions"] += executed
            for k, v in classify(mnemonic, ops).items():
                totals[k] += v * n
                function[k] += v * n
    vec = sum(totals[k] for k in ("fma", "fadd", "shuffle", "logic", "vector-other"))
    bounds = {
        "rename (instructions / 6)": instructions / 6,
        "multiply-add ports (fma / 2)": totals["fma"] / 2,
        "vector ports (all vector work) / 3": vec / 3,
        "loads / 3": totals["load"] / 3,
        "stores / 2": totals["store"] / 2,
    }
    print(f"instructions per call: {instructions:,.0f}")
    for k in ("fma", "fadd", "shuffle", "logic", "vector-other", "int", "load", "store",
              "eliminated", "string", "other", "unknown"):
        print(f"  {k:13s} {totals[k]:9,.0f}")
    print("lower bounds, cycles per call:")
    for k, v in bounds.items():
        print(f"  {v:8,.0f}  {k}")
    top = max(bounds, key=bounds.get)
    print(f"largest: {bounds[top]:,.0f} cycles ({top})")
    if len(sys.argv) == 7:
        ghz, ns = float(sys.argv[5]), float(sys.argv[6])
        cycles = ghz * ns
        print(f"measured: {ns:,.0f} ns at {ghz} GHz = {cycles:,.0f} cycles, "
              f"{bounds[top] / cycles:.0%} of it the largest bound")
    print("per function (instructions, fma):")
    for fn, c in sorted(by_function.items(), key=lambda x: -x[1]["instructions"]):
        if c["instructions"] >= 10:
            print(f"  {c['instructions']:8,.0f} {c['fma']:8,.0f}  {fn}")
    print("most executed mnemonics:", ", ".join(
        f"{m} {n:,.0f}" for m, n in by_mnemonic.most_common(12)))


if __name__ == "__main__":
    main()
