"""Per-call times from Python: kanegen's generated extensions against Pinocchio's Python
bindings (PyPI `pin`) on the same robots and states, NumPy round trip included.

Robots: the 7-DOF arm of `models/singlearm.urdf` (module `singlearm`, generated with
`kanegen python models/singlearm.urdf --functions all --module singlearm`) and Krang
(`python/krang_dynamics`), both built with `maturin develop --release`; Pinocchio's models come
from kanegen's Pinocchio export in the reference file of `bindings_reference`:

    cargo run --example bindings_reference -- target/python/reference.json
    python python/bench/compare_pinocchio.py target/python/reference.json

Prints a Markdown table: the best of 7 repeats of each loop, per call (per state for the
batches of 1,000 states, against a Python loop over Pinocchio's function).
"""

import json
import pathlib
import sys
import timeit

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests"))
from pinocchio_export import Exported  # noqa: E402
import pinocchio as pin  # noqa: E402

BATCH = 1000


def best(stmt, number):
    """Seconds per call of `stmt`: the best of 7 repeats of `number` calls."""
    return min(timeit.repeat(stmt, number=number, repeat=7)) / number


def rows(label, robot, ex, rng):
    n = robot.DOF
    q, u, ud = (rng.uniform(-1.0, 1.0, n) for _ in range(3))
    pq, pv, pa = ex.configuration(q), ex.velocity(u), ex.velocity(ud)
    model, data = ex.model, ex.data
    m_out = np.empty((n, n))
    tau_out = np.empty(n)
    calls = 20000
    out = []

    def row(what, ours, theirs, per=1):
        t_ours = best(ours, calls // per) / per
        t_pin = best(theirs, calls // per) / per
        out.append((label, what, t_ours, t_pin))

    row("M: `mass_matrix(q)` / `crba`", lambda: robot.mass_matrix(q), lambda: pin.crba(model, data, pq))
    row(
        "M into `out=`",
        lambda: robot.mass_matrix(q, out=m_out),
        lambda: pin.crba(model, data, pq),
    )
    row(
        "τ: `inverse_dynamics(q, u, ud)` / `rnea`",
        lambda: robot.inverse_dynamics(q, u, ud),
        lambda: pin.rnea(model, data, pq, pv, pa),
    )
    row(
        "τ into `out=`",
        lambda: robot.inverse_dynamics(q, u, ud, out=tau_out),
        lambda: pin.rnea(model, data, pq, pv, pa),
    )
    row(
        "g: `gravity(q)` / `computeGeneralizedGravity`",
        lambda: robot.gravity(q),
        lambda: pin.computeGeneralizedGravity(model, data, pq),
    )
    Q, U, UD = (rng.uniform(-1.0, 1.0, (BATCH, n)) for _ in range(3))
    PQ = [ex.configuration(x) for x in Q]
    PV = [ex.velocity(x) for x in U]
    PA = [ex.velocity(x) for x in UD]
    M_out = np.empty((BATCH, n, n))
    T_out = np.empty((BATCH, n))

    def crba_loop():
        for x in PQ:
            pin.crba(model, data, x)

    def rnea_loop():
        for x, v, a in zip(PQ, PV, PA):
            pin.rnea(model, data, x, v, a)

    row(
        f"M, batch of {BATCH:,} (per state)",
        lambda: robot.mass_matrix_batch(Q, out=M_out),
        crba_loop,
        per=BATCH,
    )
    row(
        f"τ, batch of {BATCH:,} (per state)",
        lambda: robot.inverse_dynamics_batch(Q, U, UD, out=T_out),
        rnea_loop,
        per=BATCH,
    )
    return out


def main():
    ref = json.loads(pathlib.Path(sys.argv[1]).read_text())
    import krang_dynamics
    import singlearm

    rng = np.random.default_rng(7)
    table = rows("arm (7 DOF)", singlearm.SingleArm(), Exported(ref["arm"]["pinocchio"]), rng)
    table += rows("Krang (19 DOF)", krang_dynamics.Krang(), Exported(ref["krang"]["pinocchio"]), rng)
    print(f"pin {pin.__version__}, numpy {np.__version__}, Python {sys.version.split()[0]}")
    print("| robot | call | kanegen | Pinocchio | speed-up |")
    print("|---|---|--:|--:|--:|")
    for label, what, ours, theirs in table:
        print(f"| {label} | {what} | {ours * 1e6:.2f} µs | {theirs * 1e6:.2f} µs | {theirs / ours:.1f}× |")


if __name__ == "__main__":
    main()
