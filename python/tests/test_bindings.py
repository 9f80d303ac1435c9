"""The Python modules against the Rust results (reference file of `bindings_reference`): every
function, single state, `out=` and batched, to 1e-14; parameters; typed errors."""

import numpy as np
import pytest

from conftest import close

# The state arguments of each function.
INPUTS = {
    "mass_matrix": "q",
    "gravity": "q",
    "center_of_mass": "q",
    "com_jacobian": "q",
    "potential_energy": "q",
    "frame_pose": "q",
    "frame_jacobian": "q",
    "gravity_regressor": "q",
    "base_gravity_regressor": "q",
    "centroidal_momentum_matrix": "q",
    "centroidal_inertia": "q",
    "coriolis": "qu",
    "coriolis_matrix": "qu",
    "com_bias_acceleration": "qu",
    "kinetic_energy": "qu",
    "nonlinear_effects": "qu",
    "frame_bias_acceleration": "qu",
    "centroidal_momentum_bias": "qu",
    "inverse_dynamics": "qu ud",
    "inverse_dynamics_derivatives": "qu ud",
    "inverse_dynamics_regressor": "qu ud",
    "base_regressor": "qu ud",
}
PER_FRAME = {"frame_pose", "frame_jacobian", "frame_bias_acceleration"}


def state_args(name, state):
    keys = ["q", "u", "ud"][: {"q": 1, "qu": 2, "qu ud": 3}[INPUTS[name]]]
    return [np.array(state[k]) for k in keys]


def batch_args(name, states):
    keys = ["q", "u", "ud"][: {"q": 1, "qu": 2, "qu ud": 3}[INPUTS[name]]]
    return [np.array([s[k] for s in states]) for k in keys]


def test_every_function_has_reference_values(case):
    _, cls, ref = case
    assert set(cls.FUNCTIONS) == set(ref["results"])


def test_single_state_results_equal_rust(case):
    _, cls, ref = case
    robot = cls()
    for name in cls.FUNCTIONS:
        f = getattr(robot, name)
        for i, state in enumerate(ref["states"]):
            args = state_args(name, state)
            if name in PER_FRAME:
                for k, frame in enumerate(cls.FRAME_NAMES):
                    expected = ref["results"][name][frame][i]
                    assert close(f(*args, frame), expected), (name, frame)
                    assert close(f(*args, k), expected), (name, k)
            else:
                assert close(f(*args), ref["results"][name][i]), name


def test_out_arrays_are_filled_and_returned(case):
    _, cls, ref = case
    robot = cls()
    state = ref["states"][0]
    for name in cls.FUNCTIONS:
        args = state_args(name, state)
        extra = [cls.FRAME_NAMES[-1]] if name in PER_FRAME else []
        fresh = getattr(robot, name)(*args, *extra)
        if np.isscalar(fresh):
            continue
        out = np.full(fresh.shape, np.nan)
        again = getattr(robot, name)(*args, *extra, out=out)
        assert again is out
        assert np.array_equal(out, fresh), name


def test_batched_results_equal_rust(case):
    _, cls, ref = case
    robot = cls()
    states = ref["states"]
    for name in cls.FUNCTIONS:
        args = batch_args(name, states)
        frames = [cls.FRAME_NAMES[-1]] if name in PER_FRAME else [None]
        for frame in frames:
            extra = [] if frame is None else [frame]
            batch = getattr(robot, name + "_batch")(*args, *extra)
            assert batch.shape[0] == len(states)
            for i in range(len(states)):
                expected = ref["results"][name]
                expected = expected[frame][i] if frame is not None else expected[i]
                assert close(batch[i], expected), (name, i)
            out = np.full(batch.shape, np.nan)
            assert getattr(robot, name + "_batch")(*args, *extra, out=out) is out
            assert np.array_equal(out, batch)


def test_an_empty_batch_gives_an_empty_result(case):
    _, cls, _ = case
    robot = cls()
    q = np.zeros((0, cls.DOF))
    assert robot.mass_matrix_batch(q).shape == (0, cls.DOF, cls.DOF)


def test_names_are_class_attributes(case):
    _, cls, ref = case
    assert cls.DOF == ref["dof"]
    assert len(cls.SPEED_NAMES) == len(cls.COORDINATE_NAMES) == cls.DOF
    assert list(cls.FRAME_NAMES) == ref["frames"]
    assert len(cls.PARAM_NAMES) == len(cls().params)
    assert list(cls().params) == list(cls.PARAM_NAMES)


def test_parameters_by_name_and_from_a_dict(case):
    _, cls, ref = case
    changed = ref["changed"]
    name, value = changed["name"], changed["value"]
    q = np.array(ref["states"][0]["q"])
    robot = cls()
    robot.set_param(name, value)
    assert robot.get_param(name) == value
    assert close(robot.mass_matrix(q), changed["mass_matrix"])
    assert close(cls({name: value}).mass_matrix(q), changed["mass_matrix"])
    other = cls()
    other.params = {name: value}
    assert other.params[name] == value
    assert close(other.mass_matrix(q), changed["mass_matrix"])
    other.update_params({name: cls().get_param(name)})
    assert close(other.mass_matrix(q), ref["results"]["mass_matrix"][0])
    assert np.array_equal(other.param_array(), np.array(list(cls().params.values())))


def test_parameter_errors_raise_and_change_nothing(case):
    module, cls, ref = case
    name = ref["changed"]["name"]
    robot = cls()
    before = robot.params
    for bad_name, bad_value in [(name, -1.0), (name, float("nan")), ("no_such_parameter", 1.0)]:
        with pytest.raises(module.ParameterError):
            robot.set_param(bad_name, bad_value)
        with pytest.raises(module.ParameterError):
            robot.update_params({cls.PARAM_NAMES[0]: 1.0, bad_name: bad_value})
        with pytest.raises(module.ParameterError):
            cls({bad_name: bad_value})
        assert robot.params == before
    with pytest.raises(module.ParameterError):
        robot.get_param("no_such_parameter")
    with pytest.raises(module.ParameterError):
        robot.update_params({name: "heavy"})
    with pytest.raises(module.ParameterError):
        robot.update_params({1: 2.0})
    assert issubclass(module.ParameterError, ValueError)


def test_arrays_of_the_wrong_shape_or_dtype_raise(case):
    module, cls, _ = case
    robot = cls()
    n = cls.DOF
    q = np.zeros(n)
    with pytest.raises(module.ShapeError):
        robot.gravity(np.zeros(n + 1))
    with pytest.raises(module.ShapeError):
        robot.gravity(np.zeros((1, n)))
    with pytest.raises(module.DtypeError):
        robot.gravity(np.zeros(n, dtype=np.float32))
    with pytest.raises(module.DtypeError):
        robot.gravity(np.zeros(n, dtype=np.int64))
    with pytest.raises(module.DtypeError):
        robot.gravity([0.0] * n)
    with pytest.raises(module.DtypeError):
        robot.inverse_dynamics(q, q, None)
    with pytest.raises(module.ShapeError):
        robot.mass_matrix(q, out=np.zeros((n, n + 1)))
    with pytest.raises(module.ShapeError):
        robot.mass_matrix(q, out=np.zeros(n * n))
    with pytest.raises(module.DtypeError):
        robot.mass_matrix(q, out=np.zeros((n, n), dtype=np.float32))
    with pytest.raises(module.ShapeError):
        robot.mass_matrix(q, out=np.zeros((n, n), order="F"))
    read_only = np.zeros((n, n))
    read_only.flags.writeable = False
    with pytest.raises(module.ShapeError):
        robot.mass_matrix(q, out=read_only)
    assert issubclass(module.ShapeError, ValueError)
    assert issubclass(module.DtypeError, TypeError)


def test_strided_inputs_are_read(case):
    _, cls, ref = case
    robot = cls()
    q = np.array(ref["states"][0]["q"])
    wide = np.zeros(2 * cls.DOF)
    wide[::2] = q
    assert np.array_equal(robot.mass_matrix(wide[::2]), robot.mass_matrix(q))


def test_batch_errors_raise(case):
    module, cls, _ = case
    robot = cls()
    n = cls.DOF
    qs = np.zeros((4, n))
    with pytest.raises(module.ShapeError):
        robot.coriolis_batch(qs, np.zeros((3, n)))
    with pytest.raises(module.ShapeError):
        robot.gravity_batch(np.zeros((4, n + 1)))
    with pytest.raises(module.ShapeError):
        robot.gravity_batch(np.zeros(n))
    with pytest.raises(module.ShapeError):
        robot.gravity_batch(np.zeros((n, 4)).T)
    with pytest.raises(module.ShapeError):
        robot.gravity_batch(qs, out=np.zeros((5, n)))
    # An `out=` array that is also an input is refused, not read and written at once.
    with pytest.raises(module.ShapeError):
        robot.gravity_batch(qs, out=qs)
    with pytest.raises(module.DtypeError):
        robot.gravity_batch(qs.astype(np.float32))


def test_frames_by_name_or_index_and_unknown_frames_raise(case):
    module, cls, _ = case
    robot = cls()
    q = np.zeros(cls.DOF)
    last = len(cls.FRAME_NAMES) - 1
    assert np.array_equal(
        robot.frame_pose(q, cls.FRAME_NAMES[last]), robot.frame_pose(q, last)
    )
    for bad in ["no_such_frame", len(cls.FRAME_NAMES), -1, 1.5]:
        with pytest.raises(module.FrameError):
            robot.frame_pose(q, bad)
    assert issubclass(module.FrameError, KeyError)
