"""physid.excite against `physid excite --json`, its scenario run by physid.simulate, the
reference trajectory against the design's own limits, and bad inputs."""
import os
import subprocess

import numpy as np
import pytest

import physid
from conftest import ROOT, KUKA_URDF
from test_identify import without_timings

SHELL = os.path.join(ROOT, "scenarios", "cheetah3_shell.toml")
QUICK = dict(iterations=30, starts=2, duration=4.0)


@pytest.fixture(scope="module")
def designed(tmp_path_factory):
    d = tmp_path_factory.mktemp("excite")
    return physid.excite("cheetah3", out=str(d / "designed.toml"), csv=str(d / "ref.csv"), **QUICK), d


def test_the_design_equals_the_cli(designed, cli, tmp_path):
    e, d = designed
    ref = cli("excite", "--robot", "cheetah3", "--iterations", "30", "--starts", "2", "--duration", "4",
              "--out", str(tmp_path / "cli.toml"))
    got = e.to_dict()
    assert got["schema"] == ref["schema"] == "physid.excite/1"
    assert without_timings(got["design"]) == without_timings(ref["design"])
    assert got["simulated"] == ref["simulated"] and got["within_limits"] is ref["within_limits"] is True
    # The same scenario text, written or returned.
    assert (tmp_path / "cli.toml").read_text() == e.scenario == (d / "designed.toml").read_text()
    assert str(e.written) == str(d / "designed.toml")


def test_the_written_scenario_runs_and_the_reference_keeps_the_limits(designed, tmp_path):
    e, d = designed
    sim = physid.simulate(str(d / "designed.toml"), str(tmp_path / "run.mcap"), duration=2.0)
    assert sim.truth["q"].shape[1] == 3
    ref = e.reference(rate=500.0)
    assert ref["q"].shape == ref["qdd"].shape == (2001, 3)
    assert np.allclose(np.diff(ref["t"]), 1 / 500.0)
    # Starts and ends at rest (the default ramp), within the design's acceleration limit.
    assert np.abs(ref["qd"][0]).max() < 1e-9 and np.abs(ref["qd"][-1]).max() < 1e-9
    # (The design checks its limits on 4 x 200 points per period; between them a peak may pass
    # the margined limit by a hair, never the robot's own.)
    accel = np.array(e.design["limits"]["acceleration"])
    assert (np.abs(ref["qdd"]).max(axis=0) <= accel * 1.001).all()
    assert np.abs(ref["qdd"]).max() > 0.9 * accel.max()
    # The CSV written beside it is the same trajectory at the default 1 kHz.
    csv = np.genfromtxt(d / "ref.csv", delimiter=",", names=True)
    assert len(csv) == 4001
    limits = e.limits()
    assert len(limits) == 3 and limits["within"].all()
    use = e.to_dict()["simulated"]
    assert list(limits["q_min"]) == [u["q_range"][0] for u in use]
    assert list(limits["acceleration"]) == [u["acceleration"] for u in use]
    assert (limits["velocity"] < 1).all() and (limits["torque"] < 1).all()


def test_a_robot_object_and_a_urdf_are_designed_for(kuka):
    e = physid.excite(kuka, iterations=0, duration=3.0, check=False, max_acceleration=[2.0],
                      max_jerk=[20.0])
    assert e.within_limits is None and e.written is None
    assert e.design["parameters"] == 84 and 0 < e.design["identifiable"] <= 84
    assert len(e.limits()) == 0
    assert "urdf" in e.scenario
    # A Robot whose rotor options changed its dynamics is not what a scenario naming its file
    # gives: refused, not silently designed for the file's robot.
    no_rotors = physid.Robot("cheetah3", no_rotors=True)
    with pytest.raises(ValueError, match="rotor options"):
        physid.excite(no_rotors, **QUICK)


def test_bad_inputs_are_named_as_keywords(tmp_path):
    cases = [
        (dict(duration=0.0), "duration must be a positive number of seconds, got 0"),
        (dict(rate=0.0), "rate must be a sample rate in (0, 100000] Hz, got 0"),
        (dict(margin=2.0), "margin must be a fraction in [0, 0.9), got 2"),
        (dict(harmonics=0), "harmonics must be 1 to 50, got 0"),
        (dict(max_acceleration=[1.0, 2.0]), "max_acceleration must be one value, or one per joint, got 2"),
        (dict(objective="a-optimal"), "objective: 'a-optimal' is not one of d-optimal, e-optimal, condition"),
        (dict(scenario=SHELL), "give a robot or a base scenario, not both"),
    ]
    for kwargs, message in cases:
        with pytest.raises(physid.InputError) as err:
            physid.excite("cheetah3", **QUICK | kwargs)
        assert str(err.value).startswith(message), (kwargs, str(err.value))
    with pytest.raises(ValueError, match="give a robot"):
        physid.excite()
    with pytest.raises(ValueError, match="refusing to write over the input"):
        physid.excite(scenario=SHELL, out=SHELL, **QUICK)
    with pytest.raises(FileNotFoundError, match="nope.urdf"):
        physid.excite(str(tmp_path / "nope.urdf"))
    assert list(tmp_path.iterdir()) == []


def test_a_scenario_s_own_motion_is_scored_as_the_cli_scores_it(cli):
    got = physid.score_motion(SHELL, duration=4.0)
    ref = cli("excite", "--scenario", SHELL, "--score", "--duration", "4")
    assert got == ref
    assert got["samples"] > 3000 and np.isfinite(got["d_optimal"]) and got["condition"] >= 1.0
    # The objective weights the score as it weights a design.
    e = physid.score_motion(SHELL, duration=4.0, objective="e-optimal")
    assert e == cli("excite", "--scenario", SHELL, "--score", "--duration", "4", "--objective", "e-optimal")


def test_scoring_refuses_bad_input_by_name(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.toml"):
        physid.score_motion(str(tmp_path / "nope.toml"), duration=4.0)
    with pytest.raises(ValueError, match="duration"):
        physid.score_motion(SHELL, duration=-1.0)
    with pytest.raises(ValueError, match="objective"):
        physid.score_motion(SHELL, objective="best")


def test_progress_reaches_one_in_order_and_an_exception_stops_the_design(tmp_path):
    import threading

    seen = []
    physid.excite("cheetah3", **QUICK, progress=lambda f: seen.append((f, threading.get_ident())))
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions) and len(set(fractions)) == len(fractions)
    assert fractions[-1] == 1.0 and 0 < fractions[0] < 0.1
    assert {thread for _, thread in seen} == {threading.get_ident()}

    def boom(f):
        raise RuntimeError("enough")

    out = tmp_path / "designed.toml"
    with pytest.raises(RuntimeError, match="enough"):
        physid.excite("cheetah3", **QUICK, out=out, progress=boom)
    assert not out.exists()
