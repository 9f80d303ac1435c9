#!/usr/bin/env bash
# What the execution ports allow: the least time a generated function's instructions can take.
#
# For each entry of the profile driver given (example `profile`,
# `crates/krang-dynamics/benches/profile/functions.rs`; default: M into a kept matrix, c, g, τ,
# the Coriolis matrix and the derivatives into a kept workspace), this
#   1. times it with the x86-64-v3 copies forced (the profile driver's fastest batch of 1000
#      calls, the best of three runs),
#   2. counts the instructions one call executes, each by its address (callgrind, 1000 calls
#      less 500: the driver's set-up cancels; valgrind runs the x86-64-v3 copies too, since it
#      hides AVX-512),
#   3. measures the core clock (a chain of dependent integer multiplies, 3 cycles each),
# and prints `port_bound.py`'s per-call instruction mix, its lower bounds in cycles (rename
# width, the two multiply-add ports, the three vector ports, loads, stores) and the measured
# cycles beside them. The README's "What the ports allow" figures come from it.
#
# Usage: tools/port-bound/run.sh [entry ...]
# Needs: valgrind, objdump (binutils), python3, cc; x86-64 Linux.
set -euo pipefail
cd "$(dirname "$0")/../.."
for tool in valgrind objdump python3 cc; do
    command -v "$tool" >/dev/null || {
        echo "tools/port-bound/run.sh needs \`$tool\` on the PATH (e.g. apt install valgrind binutils python3 gcc)" >&2
        exit 1
    }
done
[ "$(uname -m)" = x86_64 ] || { echo "tools/port-bound/run.sh: x86-64 only (the port model is Intel Golden Cove's)" >&2; exit 1; }
entries=("$@")
[ ${#entries[@]} -gt 0 ] || entries=(mass_matrix_into coriolis gravity inverse_dynamics
    coriolis_matrix inverse_dynamics_derivatives_with)
cargo build --release -q -p krang-dynamics \
    --features batch,kinematics,derivatives,coriolis-matrix --example profile
profile=${CARGO_TARGET_DIR:-target}/release/examples/profile
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

# The clock: 3·10⁹ cycles of dependent `imul`s (latency 3).
cat > "$dir/clock.c" <<'C'
#include <stdio.h>
#include <time.h>
int main(void) {
    double best = 1e30;
    for (int round = 0; round < 5; round++) {
        struct timespec a, b;
        long n = 250000000, x = 3;
        clock_gettime(CLOCK_MONOTONIC, &a);
        __asm__ volatile("1: imul %0, %0; imul %0, %0; imul %0, %0; imul %0, %0; dec %1; jnz 1b"
                         : "+r"(x), "+r"(n));
        clock_gettime(CLOCK_MONOTONIC, &b);
        double s = (b.tv_sec - a.tv_sec) + (b.tv_nsec - a.tv_nsec) * 1e-9;
        if (s < best) best = s;
    }
    printf("%.2f\n", 250000000.0 * 4 * 3 / best / 1e9);
    return 0;
}
C
cc -O2 -o "$dir/clock" "$dir/clock.c"
ghz=$("$dir/clock")
echo "core clock: $ghz GHz (dependent imul chain)"

for entry in "${entries[@]}"; do
    best=""
    for _ in 1 2 3; do
        ns=$("$profile" "$entry" 200000 x86-64-v3 2>/dev/null | awk '{print $2}')
        best=$(printf '%s\n%s\n' "$ns" "$best" | grep . | sort -g | head -1)
    done
    for n in 500 1000; do
        valgrind --tool=callgrind --dump-instr=yes --compress-strings=no --compress-pos=no \
            --callgrind-out-file="$dir/cg.$n" "$profile" "$entry" "$n" >/dev/null 2>&1
    done
    echo
    echo "== $entry: $best ns per call (x86-64-v3 copies, fastest batch of 1000)"
    python3 tools/port-bound/port_bound.py "$dir/cg.500" 500 "$dir/cg.1000" 1000 "$ghz" "$best"
done
