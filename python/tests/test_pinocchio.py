"""The Python modules against Pinocchio's Python bindings (PyPI `pin`) on the same model:
Krang and the 7-DOF arm exported by `kanegen::pinocchio` (default parameters), M, g, τ and
c + g on the reference states. Skipped where `pin` is not installed."""

import numpy as np
import pytest

from conftest import close

pytest.importorskip("pinocchio")
from pinocchio_export import Exported  # noqa: E402


def test_results_equal_pinocchio(case):
    _, cls, ref = case
    robot = cls()
    pin = Exported(ref["pinocchio"])
    assert pin.dof == cls.DOF
    for state in ref["states"]:
        q, u, ud = (np.array(state[k]) for k in ("q", "u", "ud"))
        assert close(robot.mass_matrix(q), pin.mass_matrix(q), 1e-12)
        assert close(robot.gravity(q), pin.gravity(q), 1e-12)
        assert close(robot.inverse_dynamics(q, u, ud), pin.inverse_dynamics(q, u, ud), 1e-12)
        assert close(robot.nonlinear_effects(q, u), pin.nonlinear_effects(q, u), 1e-12)


def test_batched_results_equal_pinocchio(case):
    _, cls, ref = case
    robot = cls()
    pin = Exported(ref["pinocchio"])
    q = np.array([s["q"] for s in ref["states"]])
    u = np.array([s["u"] for s in ref["states"]])
    ud = np.array([s["ud"] for s in ref["states"]])
    taus = robot.inverse_dynamics_batch(q, u, ud)
    for i in range(len(q)):
        assert close(taus[i], pin.inverse_dynamics(q[i], u[i], ud[i]), 1e-12)
