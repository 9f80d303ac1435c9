#!/usr/bin/env bash
# Pinocchio side by side (docs/performance.md): Krang (models/krang.toml) in
# Pinocchio's C++ and in kanegen's generated Rust, checked against each other on random
# parameters and states, then timed alternately in one run.
#
#   benches/pinocchio/run.sh            # from anywhere; everything goes to target/pinocchio,
#                                       # this run's results to target/pinocchio/YYYY-MM-DD
#
# Needs python3 (with venv), a C++17 compiler (g++ or clang++; CXX to choose), cargo, and network
# access to PyPI. Steps:
#   1. a virtual environment target/pinocchio/venv with Pinocchio from PyPI (`pin`: its wheel
#      ships the C++ headers through cmeel) and `cmeel-eigen` (Eigen's headers, which the `pin`
#      wheel does not ship); the include path is `python -m cmeel cmake` + /include;
#   2. the C++ harness benches/pinocchio/harness.cpp, header-only, -O3 -march=native;
#   3. the Rust side, examples/pinocchio_side_by_side.rs (release): writes cases.txt (the model
#      exported by kanegen::pinocchio for 100 parameter sets, one state each, and the generated
#      code's M, c, g, τ, C);
#   4. RUNS times (default 3), alternately: the harness (agreement check on all cases, then
#      Pinocchio's timings), with CODEGEN=1 the codegen harness, and the Rust timings; then the
#      table, best of the runs;
#   5. free-flyer models: `examples/pinocchio_free_flyer.rs write` writes ff-cases.txt (Solo 12
#      and a 35-speed humanoid of tests/corpus on a floating base, exported with a
#      JointModelFreeFlyer root, random states, the free-flyer reference recursion's M, nle, g,
#      rnea, ccrba, Ȧ_G v, RNEA derivatives and the contact-constrained dynamics of
#      kanegen_runtime::contact); in each of the RUNS, benches/pinocchio/harness_ff.cpp compares
#      them with Pinocchio's crba, nonLinearEffects, computeGeneralizedGravity, rnea, ccrba,
#      computeCentroidalMomentumTimeVariation, computeRNEADerivatives and constraintDynamics,
#      then times those and aba; `pinocchio_free_flyer time` checks the generated modules of
#      both robots against the reference and times them; `report` prints a table per robot.
# With CODEGEN=1 also Pinocchio's own generated code (its CppADCodeGen path, the other code
# generator to compare with): step 1 adds `cmeel-cppad` and `cmeel-cppadcodegen` (headers), step 2 compiles
# benches/pinocchio/codegen.cpp, whose first run records crba, nonLinearEffects, gravity, rnea
# and computeRNEADerivatives on case 0's model and on each free-flyer model (Solo 12, the
# humanoid) and compiles each to a shared library with
# `$CC -O3 -march=native` (CC default /usr/bin/gcc) into OUT/RUN_NAME/cg (about 25 s for Krang on
# a 2-core Intel Xeon; delete that directory to regenerate); later runs load them. Compiling the
# codegen harness itself takes about 7 minutes (CppAD's templates).
# Environment: PIN_VERSION (default 4.1.0), EIGEN_VERSION (cmeel-eigen, 3.4.1), RUNS (3),
# CODEGEN (0; 1 for Pinocchio's generated code), CPPAD_VERSION (cmeel-cppad, 20250000.2),
# CPPADCG_VERSION (cmeel-cppadcodegen, 2.4.3),
# CXX (g++), OUT (target/pinocchio),
# CXXFLAGS_EXTRA (appended to the compiler flags), RUN_NAME (the results directory under OUT,
# default today's date, YYYY-MM-DD: name it to keep runs apart, e.g. RUN_NAME=native). cargo's own variables apply to the Rust side, e.g. for both sides with the
# machine's instruction set (a separate target directory keeps the default build):
#   RUSTFLAGS="-C target-cpu=native" CARGO_TARGET_DIR=target/native RUN_NAME=native \
#       benches/pinocchio/run.sh
# Not part of CI (it downloads). Takes about 8 minutes on a 2-core machine, most of it compiling
# the harnesses (Pinocchio's templates) and the Rust examples; about 8 more with CODEGEN=1.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="${OUT:-$root/target/pinocchio}"
pin_version="${PIN_VERSION:-4.1.0}"
eigen_version="${EIGEN_VERSION:-3.4.1}"
runs="${RUNS:-3}"
codegen="${CODEGEN:-0}"
cppad_version="${CPPAD_VERSION:-20250000.2}"
cppadcg_version="${CPPADCG_VERSION:-2.4.3}"
cxx="${CXX:-g++}"
run_dir="$out/${RUN_NAME:-$(date +%Y-%m-%d)}"
mkdir -p "$run_dir"

echo "== 1. Pinocchio $pin_version from PyPI into $out/venv"
if [ ! -x "$out/venv/bin/python" ]; then
    python3 -m venv "$out/venv"
fi
packages=("pin==$pin_version" "cmeel-eigen==$eigen_version")
if [ "$codegen" = 1 ]; then
    packages+=("cmeel-cppad==$cppad_version" "cmeel-cppadcodegen==$cppadcg_version")
fi
"$out/venv/bin/python" -m pip install --quiet --disable-pip-version-check "${packages[@]}"
prefix="$("$out/venv/bin/python" -m cmeel cmake 2>/dev/null | head -n 1)"
if [ ! -f "$prefix/include/pinocchio/config.hpp" ] || [ ! -d "$prefix/include/eigen3" ]; then
    echo "error: no Pinocchio or Eigen headers under $prefix/include (pin and cmeel-eigen wheels)" >&2
    exit 1
fi
echo "headers: $prefix/include ($(grep -m1 'define PINOCCHIO_VERSION ' "$prefix/include/pinocchio/config.hpp"))"

echo "== 2. C++ harness ($cxx -O3 -march=native, header-only Pinocchio)"
flags=(-std=c++17 -O3 -march=native -DNDEBUG
    # Pinocchio's CMake target pinocchio_headers sets these:
    -DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30
    -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12
    -w -I"$prefix/include" -I"$prefix/include/eigen3")
# shellcheck disable=SC2206
flags+=(${CXXFLAGS_EXTRA:-})
# Compiles benches/pinocchio/NAME.cpp to OUT/NAME (extra arguments after the source) unless it
# is up to date: built after its source and cases.hpp, with the compiler and flags recorded in
# OUT/NAME.flags.
compile() {
    local name="$1" duration="$2"
    shift 2
    local src="$root/benches/pinocchio/$name.cpp" bin="$out/$name" stamp="$out/$name.flags"
    if [ ! -x "$bin" ] || [ "$src" -nt "$bin" ] || [ "$root/benches/pinocchio/cases.hpp" -nt "$bin" ] \
        || [ "$(cat "$stamp" 2>/dev/null)" != "$cxx ${flags[*]}" ]; then
        echo "compiling $name.cpp (about $duration)"
        "$cxx" "${flags[@]}" "$src" -o "$bin" "$@"
        echo "$cxx ${flags[*]}" > "$stamp"
    fi
}
compile harness "2-3 minutes"
compile harness_ff "2 minutes"
if [ "$codegen" = 1 ]; then
    if [ ! -f "$prefix/include/cppad/cg.hpp" ]; then
        echo "error: no CppADCodeGen headers under $prefix/include (cmeel-cppadcodegen wheel)" >&2
        exit 1
    fi
    compile codegen "7 minutes" -ldl
fi

echo "== 3. Rust side: cargo build --release --example pinocchio_side_by_side"
(cd "$root" && cargo build --release --quiet --example pinocchio_side_by_side)
rust="${CARGO_TARGET_DIR:-$root/target}/release/examples/pinocchio_side_by_side"
"$rust" write "$run_dir"
(cd "$root" && cargo build --release --quiet --example pinocchio_free_flyer)
ff="${CARGO_TARGET_DIR:-$root/target}/release/examples/pinocchio_free_flyer"
"$ff" write "$run_dir"

echo "== 4. agreement and timings, $runs runs alternating Pinocchio and kanegen"
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | xargs), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "compilers: $("$cxx" --version | head -n 1); $(rustc --version)"
rm -f "$run_dir/pinocchio-times.txt" "$run_dir/kanegen-times.txt" \
    "$run_dir/pinocchio-ff-times.txt" "$run_dir/kanegen-ff-times.txt"
status=0
for r in $(seq 1 "$runs"); do
    echo "-- run $r"
    "$out/harness" "$run_dir" || status=$?
    if [ "$codegen" = 1 ]; then
        "$out/codegen" "$run_dir" || status=$?
    fi
    "$rust" time "$run_dir"
    "$out/harness_ff" "$run_dir" || status=$?
    "$ff" time "$run_dir" || status=$?
done
echo "== table (load $(cut -d' ' -f1-3 /proc/loadavg))"
"$rust" report "$run_dir"
echo "== 5. free-flyer models (floating base), load $(cut -d' ' -f1-3 /proc/loadavg)"
"$ff" report "$run_dir"
if [ "$status" -ne 0 ]; then
    echo "error: Pinocchio and kanegen disagree (see above)" >&2
    exit "$status"
fi
