"""physid.Data: a run held in memory goes through the data pipeline as its file does, and is
taken wherever a data file is; identify_arrays is identify on one."""
import numpy as np
import pytest

import physid
from conftest import kuka_run


def columns(k):
    """Run k of the KUKA as arrays: t, q, q̇, q̈, τ (the file's own columns)."""
    d = np.loadtxt(kuka_run(k), delimiter=",", skiprows=1)
    return d[:, 0], d[:, 1:8], d[:, 8:15], d[:, 15:22], d[:, 22:29]


@pytest.fixture(scope="module")
def run1():
    return columns(1)


def test_arrays_identify_as_their_file_does(kuka, run1):
    t, q, qd, qdd, tau = run1
    from_file = physid.identify(kuka, kuka_run(1), validate_data=kuka_run(2), constraints="consistent")
    _, q2, qd2, qdd2, tau2 = columns(2)
    held_out = physid.Data(q2, tau2, qd=qd2, qdd=qdd2, rate=1 / np.median(np.diff(t)), name="run 2")
    from_arrays = physid.identify_arrays(kuka, q, qd, qdd, tau, t=t, validate_data=held_out,
                                         constraints="consistent")
    assert isinstance(from_arrays, physid.Identification)
    assert np.array_equal(from_file.theta, from_arrays.theta)
    assert from_file.train_rms == from_arrays.train_rms
    assert abs(from_file.validation_rms - from_arrays.validation_rms) < 1e-12
    report = from_arrays.to_dict()
    assert report["data"] == "<arrays" + report["data"].split("<arrays")[1] and report["data"].endswith(">")
    assert [r["file"] for r in report["validation"]["runs"]] == ["run 2"]


def test_a_run_without_derivatives_is_derived_as_a_file_without_them(kuka, run1, tmp_path):
    t, q, _, _, tau = run1
    header = ["t", *(f"q{j}" for j in range(1, 8)), *(f"tau{j}" for j in range(1, 8))]
    path = tmp_path / "positions_only.csv"
    np.savetxt(path, np.column_stack([t, q, tau]), delimiter=",", header=",".join(header), comments="", fmt="%.17g")
    from_file = physid.identify(kuka, path)
    from_arrays = physid.identify(kuka, physid.Data(q, tau, t=t, name="positions only"))
    assert np.array_equal(from_file.theta, from_arrays.theta)
    assert any("positions only: no velocities or accelerations: q̇ and q̈ derived" in n for n in from_arrays.notices)


def test_too_few_samples_are_refused_as_for_a_file(kuka, run1):
    _, q, qd, qdd, tau = run1
    with pytest.raises(physid.InputError, match=r"^<arrays \d+>: 5 samples give 35 equations for 84 parameters"):
        physid.identify_arrays(kuka, q[:5], qd[:5], qdd[:5], tau[:5])
    fit = physid.identify_arrays(kuka, q[:5], qd[:5], qdd[:5], tau[:5], allow_few_samples=True)
    assert fit.to_dict()["train"]["runs"][0]["samples_used"] == 5


def test_arrays_write_urdf_and_load_and_diagnose(kuka, run1, tmp_path):
    t, q, qd, qdd, tau = run1
    run = physid.Data(q, tau, qd=qd, qdd=qdd, t=t, name="run 1")
    fit = physid.identify(kuka, run, constraints="consistent")
    fit.write_urdf(tmp_path / "identified.urdf")
    assert physid.Robot(tmp_path / "identified.urdf").dof == 7
    loaded = physid.load(kuka, run)
    assert str(loaded[0]["file"]) == "run 1" and np.array_equal(loaded[0]["runs"][0]["q"], q)
    on_file = physid.diagnose(kuka, kuka_run(1), holdout=0.3)
    on_arrays = physid.diagnose(kuka, run, holdout=0.3)
    assert on_file.summary == on_arrays.summary and on_file.effect_kinds == on_arrays.effect_kinds


def test_one_run_given_twice_is_refused(kuka, run1):
    t, q, _, _, tau = run1
    run = physid.Data(q, tau, t=t, name="twice")
    with pytest.raises(physid.InputError, match="the same recording is given twice"):
        physid.identify(kuka, run, validate_data=run)


@pytest.mark.parametrize(
    "kw, message",
    [
        (dict(q=np.zeros((10, 7)), tau=np.zeros((10, 6)), rate=100.0), r"^tau has shape \(10, 6\): q has shape \(10, 7\)$"),
        (dict(q=np.zeros((10, 7)), tau=np.zeros((10, 7)), qd=np.zeros((9, 7)), rate=100.0), r"^qd has shape \(9, 7\)"),
        (dict(q=np.zeros(7), tau=np.zeros(7), rate=100.0), r"^q has shape \[7\]: give \(samples, joints\)"),
        (dict(q=np.zeros((10, 7)), tau=np.zeros((10, 7))), r"^give t \(time stamps, s\) or rate"),
        (dict(q=np.zeros((10, 7)), tau=np.zeros((10, 7)), rate=100.0, t=np.arange(10)), r"^give t .* or rate .*, not both"),
        (dict(q=np.zeros((10, 7)), tau=np.zeros((10, 7)), rate=0.0), r"^rate must be a sample rate in Hz"),
        (dict(q=np.zeros((10, 7)), tau=np.zeros((10, 7)), t=np.arange(9)), r"^t has 9 time stamps for 10 samples"),
    ],
)
def test_bad_arrays_are_named(kw, message):
    with pytest.raises(physid.InputError, match=message):
        physid.Data(**kw)


def test_bad_runs_are_named_by_sample_and_joint(kuka, run1):
    t, q, _, _, tau = run1
    with pytest.raises(physid.InputError, match=r"^short: 3 joints \(columns of q\), the robot has 7$"):
        physid.identify(kuka, physid.Data(q[:, :3], tau[:, :3], t=t, name="short"))
    bad = tau.copy()
    bad[17, 2] = np.nan
    with pytest.raises(physid.InputError, match=r"^nan: .*sample 17.*tau3"):
        physid.identify(kuka, physid.Data(q, bad, t=t, name="nan"))
    with pytest.raises(physid.InputError, match="data: give a path, a physid.Data or a list of them"):
        physid.identify(kuka, 42)
    # A table is not read as a list of file names (its columns).
    pd = pytest.importorskip("pandas")
    frame = pd.DataFrame(np.column_stack([t, q]), columns=["t", *(f"q{j}" for j in range(1, 8))])
    for table in (frame, q):
        with pytest.raises(physid.InputError, match=r"^data: an array or table is not a run: hold arrays as physid.Data"):
            physid.identify(kuka, table)
