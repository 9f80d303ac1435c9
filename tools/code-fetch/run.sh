#!/usr/bin/env bash
# How fast the CPU runs straight-line code that does not fit its level-1 instruction cache.
#
# Builds, with the system C compiler, functions that are one long run of 8-byte NOPs
# (`nopl 0x0(%rax,%rax,1)` with a 4-byte displacement: nothing to execute but the fetch and
# decode) of 16 to 128 KB (or the sizes given), and prints for each the best time per call over
# 200 rounds and the bytes fetched per ns. On an Intel Xeon (Nov 2026, 2 cores, 64 KB level-1
# instruction cache) runs of up to 64 KB went at 120-180 B/ns, longer ones at about 46 B/ns:
# the rate of code streamed from the level-2 cache, whatever the instructions. Long generated
# functions above the cache run at that rate (e.g. the Coriolis matrix's 8-state batch), which
# is why the generator emits loop forms for the largest functions.
#
# Usage: tools/code-fetch/run.sh [sizes in KB ...]   (x86-64 Linux, cc on the PATH)
set -euo pipefail
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(16 32 48 56 64 72 96 128)
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cat > "$dir/main.c" <<'C'
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
void sled(void);
int main(int argc, char **argv) {
    long calls = atol(argv[1]);
    double best = 1e30;
    for (int round = 0; round < 200; round++) {
        struct timespec a, b;
        clock_gettime(CLOCK_MONOTONIC, &a);
        for (long i = 0; i < calls; i++) sled();
        clock_gettime(CLOCK_MONOTONIC, &b);
        double ns = ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / calls;
        if (ns < best) best = ns;
    }
    printf("%.1f\n", best);
    return 0;
}
C
printf '%8s %12s %8s\n' "KB" "ns per call" "B/ns"
for kb in "${sizes[@]}"; do
    n=$((kb * 1024 / 8))
    {
        printf '.text\n.globl sled\n.type sled,@function\n.p2align 6\nsled:\n'
        printf '.rept %d\n.byte 0x0f, 0x1f, 0x84, 0x00, 0x00, 0x00, 0x00, 0x00\n.endr\nret\n' "$n"
        printf '.section .note.GNU-stack,"",@progbits\n'
    } > "$dir/sled.s"
    cc -O2 -o "$dir/sled" "$dir/main.c" "$dir/sled.s"
    ns=$("$dir/sled" 200)
    printf '%8s %12s %8s\n' "$kb" "$ns" "$(awk -v b=$((kb * 1024)) -v t="$ns" 'BEGIN { printf "%.0f", b / t }')"
done
