"""Every model and result pickles and deep-copies: the copy answers every method as the
original does, and results cross to worker processes (multiprocessing, spawned)."""
import copy
import multiprocessing
import os
import pickle
import warnings

import numpy as np
import pytest

import physid
from conftest import KUKA_URDF, ROOT, kuka_run
from test_excite import QUICK, SHELL
from test_sweep import sweep_file


def same(a, b):
    """`b` answers as `a` does: its dict form, repr and (where it has them) tables and text."""
    assert type(a) is type(b) and a is not b
    assert repr(a) == repr(b)
    if hasattr(a, "to_dict"):
        assert a.to_dict() == b.to_dict()
    for method in ("text", "markdown", "html"):
        if callable(getattr(a, method, None)):
            assert getattr(a, method)() == getattr(b, method)()
    for table in ("bodies", "joints", "gap", "ladder", "effects", "rows", "summary", "groups", "limits"):
        if callable(getattr(a, table, None)):
            assert getattr(a, table)().equals(getattr(b, table)()), table


def round_trips(value):
    for copied in (pickle.loads(pickle.dumps(value)), copy.deepcopy(value), copy.copy(value)):
        same(value, copied)
    return pickle.loads(pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL))


@pytest.fixture(scope="module")
def quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", physid.PhysidWarning)
        yield


def test_robots_pickle_with_their_dynamics(quiet):
    for robot in (physid.Robot("cheetah3"), physid.Robot(KUKA_URDF), physid.Robot("cheetah3", rotor_model="reflected")):
        back = round_trips(robot)
        q = np.random.default_rng(1).normal(size=(5, robot.dof))
        assert np.array_equal(robot.inverse_dynamics(q, q, q), back.inverse_dynamics(q, q, q))
        assert np.array_equal(robot.regressor(q, q, q), back.regressor(q, q, q))
        assert np.array_equal(robot.parameters(), back.parameters())
        assert robot.describe() == back.describe() and robot.notices == back.notices


def test_an_identification_pickles_and_writes_the_same_urdf(quiet, tmp_path):
    fit = physid.identify(physid.Robot(KUKA_URDF), kuka_run(1), validate_data=kuka_run(2),
                          friction="viscous,coulomb,offset")
    back = round_trips(fit)
    assert np.array_equal(fit.theta, back.theta) and fit.validation_rms == back.validation_rms
    for folder, f in (("a", fit), ("b", back)):
        (tmp_path / folder).mkdir()
        f.write_urdf(tmp_path / folder / "kuka.urdf")
    for name in ("kuka.urdf", "kuka.physid.toml"):
        assert (tmp_path / "a" / name).read_text() == (tmp_path / "b" / name).read_text()


def test_a_diagnosis_pickles_with_its_report(quiet, kuka):
    d = physid.diagnose(kuka, kuka_run(3), description_uncertainty=0.05)
    back = round_trips(d)
    assert d._repr_html_() == back._repr_html_() and d.payload == back.payload


def test_simulations_excitations_and_experiments_pickle(quiet, tmp_path):
    sim = physid.simulate(SHELL, tmp_path / "run.mcap", duration=1.0)
    back = round_trips(sim)
    for signals in ("truth", "measured", "processed"):
        a, b = getattr(sim, signals), getattr(back, signals)
        assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    assert back.robot.describe() == sim.robot.describe()
    e = physid.excite("cheetah3", **QUICK)
    back = round_trips(e)
    assert back.scenario == e.scenario
    assert np.array_equal(back.reference(100.0)["q"], e.reference(100.0)["q"])
    round_trips(physid.experiment(os.path.join(ROOT, "scenarios", "ci.toml"), seeds=1, threads=1))
    round_trips(physid.sweep(sweep_file(tmp_path), out=tmp_path / "sweep", threads=1))
    round_trips(physid.compare(os.path.join(ROOT, "results", "ci_baseline"), variant="ellipsoid<=consistent",
                               allow_too_few=True))


def validation_rms(fit):
    return fit.validation_rms, fit.theta.sum()


def test_results_cross_to_worker_processes(quiet, monkeypatch):
    robot = physid.Robot(KUKA_URDF)
    fits = [physid.identify(robot, kuka_run(k), validate_data=kuka_run(3)) for k in (1, 2)]
    here = os.path.dirname(os.path.abspath(__file__))
    path = [p for p in (os.environ.get("PHYSID_PYTHON"), here, os.environ.get("PYTHONPATH")) if p]
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(path))
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        answers = pool.map(validation_rms, fits)
    assert answers == [validation_rms(f) for f in fits]


def test_a_state_of_another_version_is_refused():
    reduced = physid.Robot("cheetah3").__reduce__()
    restore, (cls, version, state) = reduced
    assert (cls, version) == ("Robot", physid.__version__)
    with pytest.raises(physid.InputError, match=r"pickled by physid 0\.0\.0: this is physid .*, which reads only its own"):
        restore(cls, "0.0.0", state)
    with pytest.raises(physid.InputError, match="unpickling a physid.Robot: its state does not read"):
        restore(cls, version, state[: len(state) // 2])
    with pytest.raises(physid.InputError, match="physid has no class 'Nope'"):
        restore("Nope", version, state)
