"""Joint values as a pinocchio or pandas user holds them: numpy arrays of any real dtype, nested
lists, pandas and polars frames, one sample or many; read once, answered in the shape given."""
import numpy as np
import pandas as pd
import polars as pl
import pytest

import physid
from conftest import KUKA_URDF


@pytest.fixture(scope="module")
def kuka():
    with pytest.warns(physid.PhysidWarning):
        return physid.Robot(KUKA_URDF)


@pytest.fixture(scope="module")
def states():
    rng = np.random.default_rng(7)
    return [rng.uniform(-1.0, 1.0, size=(5, 7)) for _ in range(3)]


def test_lists_and_frames_give_the_same_torques_as_float64_arrays(kuka, states):
    q, qd, qdd = states
    tau = kuka.inverse_dynamics(q, qd, qdd)
    assert tau.shape == (5, 7) and tau.dtype == np.float64
    names = [f"j{i}" for i in range(7)]
    for convert in (
        lambda a: a.tolist(),
        lambda a: pd.DataFrame(a, columns=names),
        lambda a: pl.DataFrame(a, schema=names, orient="row"),
        lambda a: np.asfortranarray(a),
        lambda a: a[:, ::-1][:, ::-1],  # a strided view
    ):
        np.testing.assert_array_equal(kuka.inverse_dynamics(convert(q), convert(qd), convert(qdd)), tau)


def test_integer_and_float32_arrays_are_read_as_their_values(kuka, states):
    q, qd, qdd = states
    q32, qd32, qdd32 = (a.astype(np.float32) for a in states)
    expected = kuka.inverse_dynamics(q32.astype(np.float64), qd32.astype(np.float64), qdd32.astype(np.float64))
    np.testing.assert_array_equal(kuka.inverse_dynamics(q32, qd32, qdd32), expected)
    ones, zeros = np.ones((2, 7), dtype=np.int32), np.zeros((2, 7), dtype=np.int64)
    tau = kuka.inverse_dynamics(ones, zeros, zeros)
    np.testing.assert_array_equal(tau, kuka.inverse_dynamics(np.ones((2, 7)), np.zeros((2, 7)), np.zeros((2, 7))))
    # At rest at 1 rad on every joint: the gravity torque (the integers were read as numbers).
    assert np.abs(tau).max() > 1.0


def test_one_sample_in_one_sample_out_as_pinocchio(kuka, states):
    q, qd, qdd = states
    n, p = 7, len(kuka.parameter_names)
    tau = kuka.inverse_dynamics(q[0], qd[0], qdd[0])
    assert tau.shape == (n,)
    np.testing.assert_array_equal(tau, kuka.inverse_dynamics(q, qd, qdd)[0])
    h = kuka.mass_matrix(list(q[0]))
    assert h.shape == (n, n)
    np.testing.assert_array_equal(h, kuka.mass_matrix(q)[0])
    y = kuka.regressor(q[0], qd[0], qdd[0])
    assert y.shape == (n, p)
    np.testing.assert_array_equal(y, kuka.regressor(q, qd, qdd)[0])
    # A batch of one stays a batch.
    assert kuka.inverse_dynamics(q[:1], qd[:1], qdd[:1]).shape == (1, n)


@pytest.mark.parametrize(
    "bad, error, words",
    [
        (np.zeros((3, 7), dtype=complex), TypeError, ["q", "real numbers", "complex"]),
        (np.zeros((3, 7), dtype=bool), TypeError, ["q", "real numbers", "bool"]),
        ([["a"] * 7] * 3, TypeError, ["q", "real numbers"]),
        (np.zeros((3, 6)), ValueError, ["q has shape [3, 6]", "(samples, 7)"]),
        (np.zeros((2, 3, 7)), ValueError, ["q has shape [2, 3, 7]"]),
        (np.zeros(()), ValueError, ["q has shape []"]),
    ],
)
def test_what_is_not_joint_values_is_refused_naming_the_argument(kuka, bad, error, words):
    ok = np.zeros((3, 7))
    with pytest.raises(error) as e:
        kuka.inverse_dynamics(bad, ok, ok)
    for w in words:
        assert w in str(e.value), str(e.value)


def test_a_nan_is_named_by_argument_sample_and_joint(kuka):
    qd = np.zeros((3, 7))
    qd[2, 4] = np.nan
    with pytest.raises(ValueError) as e:
        kuka.inverse_dynamics(np.zeros((3, 7)), qd, np.zeros((3, 7)))
    message = str(e.value)
    assert "qd" in message and "2" in message, message


def test_identify_arrays_takes_lists_as_arrays(kuka):
    rng = np.random.default_rng(3)
    q, qd, qdd = (rng.uniform(-1.5, 1.5, size=(400, 7)) for _ in range(3))
    tau = kuka.inverse_dynamics(q, qd, qdd)
    a = physid.identify_arrays(kuka, q, qd, qdd, tau, constraints="consistent")
    b = physid.identify_arrays(kuka, q.tolist(), qd.tolist(), qdd.tolist(), tau.tolist(), constraints="consistent")
    np.testing.assert_array_equal(a.theta, b.theta)
    assert a.constraints_hold
