"""physid.simulate_floating and physid.identify_floating against the CLI, the identified robot
loaded by pinocchio and MuJoCo, and bad inputs."""
import json
import os
import pickle
import subprocess

import numpy as np
import pytest

import physid


def cli(*args):
    out = subprocess.run([os.environ["PHYSID_BIN"], *args], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out.stdout


@pytest.fixture(scope="module")
def log(tmp_path_factory):
    path = tmp_path_factory.mktemp("floating") / "standing.csv"
    summary = physid.simulate_floating(path, duration=3.0, seed=2)
    assert summary["samples"] == 3000 and len(summary["feet"]) == 4
    assert summary["truth"] == str(path.with_name("standing.truth.urdf"))
    return path


def test_the_log_is_the_cli_s_byte_for_byte(log, tmp_path):
    cli("simulate-floating", "--out", str(tmp_path / "cli.csv"), "--duration", "3", "--seed", "2")
    assert (tmp_path / "cli.csv").read_bytes() == log.read_bytes()


def test_a_dropped_and_pushed_run_on_ice_is_the_cli_s(tmp_path):
    ours = physid.simulate_floating(tmp_path / "py.csv", duration=0.5, still=True, drop=0.02,
                                    push=(0.5, 0.0, 0.0), ground_friction=0.2)
    assert ours["drop"] == 0.02 and ours["push"] == [0.5, 0.0, 0.0] and ours["ground"][2] == 0.2
    cli("simulate-floating", "--out", str(tmp_path / "cli.csv"), "--duration", "0.5", "--still",
        "--drop", "0.02", "--push", "0.5,0,0", "--ground-friction", "0.2")
    assert (tmp_path / "cli.csv").read_bytes() == (tmp_path / "py.csv").read_bytes()


def test_identification_equals_the_cli_and_loads_in_pinocchio_and_mujoco(log, tmp_path):
    urdf, xml = tmp_path / "id.urdf", tmp_path / "id.xml"
    truth = log.with_name("standing.truth.urdf")
    fit = physid.identify_floating(log, setting="torques_and_contacts", out_urdf=urdf, out_mjcf=xml,
                                   truth=truth)
    assert fit.to_dict()["truth"]["mass"] == pytest.approx(45.0, abs=1e-9)
    ours = fit.to_dict()
    theirs = json.loads(cli("identify-floating", "--data", str(log), "--json", "--truth", str(truth)))
    assert ours["truth"] == theirs["truth"]
    assert ours["theta"] == theirs["theta"] and ours["identified_rms"] == theirs["identified_rms"]
    assert ours["identifiability"] == theirs["identifiability"] and ours["notices"] == theirs["notices"]
    assert ours["change"] == theirs["change"] and ours["change"]["changed"] is None
    assert ours["identifiability"]["rank"] < ours["identifiability"]["parameters"] == 274
    assert fit.constraints_hold and abs(fit.mass - 45.0) < 0.5
    np.testing.assert_array_equal(fit.theta, np.asarray(theirs["theta"]))
    import pinocchio as pin
    model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer(), True)
    assert abs(pin.computeTotalMass(model) - fit.mass) < 1e-9 * fit.mass
    import mujoco
    assert abs(mujoco.MjModel.from_xml_path(str(xml)).body_mass.sum() - fit.mass) < 1e-9 * fit.mass
    again = pickle.loads(pickle.dumps(fit))
    np.testing.assert_array_equal(again.theta, fit.theta)
    assert "FloatingIdentification" in repr(fit) and "<table" in fit._repr_html_()


def test_a_baseline_log_is_the_cli_s(log, tmp_path):
    before = tmp_path / "before.csv"
    physid.simulate_floating(before, duration=3.0, seed=5)
    fit = physid.identify_floating(log, baseline=before)
    change = fit.to_dict()["change"]
    assert change["baseline"] == str(before) and change["changed"] is None
    assert 0.0 < change["baseline_visibility"]
    theirs = cli("identify-floating", "--data", str(log), "--baseline-data", str(before), "--json")
    assert json.loads(theirs)["change"] == change
    with pytest.raises(physid.InputError, match="the log itself"):
        physid.identify_floating(log, baseline=log)


def test_feet_sensors_and_settings_as_keywords(log, tmp_path):
    feet = ["fr_shank:0,0,-0.34", ("fl_shank", (0, 0, -0.34)), "hr_shank:0,0,-0.34", "hl_shank:0,0,-0.34"]
    base = physid.identify_floating(log, setting="base-only", foot=feet, constraints="consistent")
    assert base.to_dict()["setting"] == "base_only" and base.constraints_hold
    exact = physid.simulate_floating(tmp_path / "exact.csv", duration=2.0, sensors="exact")
    assert exact["samples"] == 2000
    trot = physid.simulate_floating(tmp_path / "trot.csv", duration=3.0, trot=(0.15, 2.5))
    assert trot["contact_share"] < 0.85
    noisy = physid.simulate_floating(tmp_path / "noisy.csv", duration=1.0, sensors={"force_noise": 5.0, "velocities": True})
    assert noisy["samples"] == 1000
    assert "dq_fr_hip_joint" in (tmp_path / "noisy.csv").read_text().splitlines()[0]


def test_an_mcap_log_and_its_topics_are_the_cli_s(tmp_path):
    path = tmp_path / "standing.mcap"
    physid.simulate_floating(path, duration=2.0, seed=3)
    cli("simulate-floating", "--out", str(tmp_path / "cli.mcap"), "--duration", "2", "--seed", "3")
    ours = physid.identify_floating(path, stamp="header").to_dict()
    theirs = json.loads(cli("identify-floating", "--data", str(tmp_path / "cli.mcap"), "--stamp", "header", "--json"))
    assert ours["theta"] == theirs["theta"] and ours["samples_used"] == theirs["samples_used"]
    with pytest.raises(physid.InputError, match="no /odom messages"):
        physid.identify_floating(path, odometry_topic="/odom")
    with pytest.raises(physid.InputError, match="stamp: unknown stamp 'gps'"):
        physid.identify_floating(path, stamp="gps")


@pytest.mark.parametrize(
    "kw, message",
    [
        (dict(setting="walking"), "setting: 'walking' is not one of"),
        (dict(constraints="tight"), "constraints: 'tight' is not one of"),
        (dict(foot=["paw:0,0,0"]), "foot 'paw': the robot has no body of that name"),
        (dict(foot=["fr_shank"]), "expected BODY:X,Y,Z"),
        (dict(foot=[3]), "give \"BODY:X,Y,Z\" or (body, (x, y, z))"),
        (dict(prior_weight=-1.0), "prior_weight"),
        (dict(contact_force=float("nan")), "contact_force"),
        (dict(odometry_topic="/odom"), "apply to MCAP files and rosbag2 directories only"),
        (dict(topic="/odometry"), "topic and odometry_topic are both /odometry"),
    ],
)
def test_bad_identification_keywords_are_named(log, kw, message):
    with pytest.raises(physid.InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        physid.identify_floating(log, **kw)


@pytest.mark.parametrize(
    "kw, message",
    [
        (dict(sensors={"bogus": 1}), "unknown field `bogus`"),
        (dict(sensors={"tilt_noise": 1.0}), "no state estimator's"),
        (dict(sensors="noisy"), "is not \"exact\""),
        (dict(duration=0.0), "duration"),
        (dict(rate=50.0), "rate"),
        (dict(trot=(0.2, 1.5), duration=4.0), "the robot fell at t = "),
        (dict(trot=(0.15, 2.5), still=True), "still and trot"),
        (dict(drop=0.6), "drop must be 0 <= m <= 0.5, got 0.6"),
        (dict(drop=float("nan")), "drop must be 0 <= m <= 0.5, got NaN"),
        (dict(push=(3.0, 3.0, 3.0)), "push: expected a velocity VX,VY,VZ of at most 5 m/s"),
        (dict(push=(0.0, 4.0, 0.0), duration=2.0), "the robot fell at t = "),
        (dict(ground_friction=-1.0), "ground_friction must be 0 <= μ <= 2, got -1"),
    ],
)
def test_bad_simulation_keywords_are_named(tmp_path, kw, message):
    out = tmp_path / "never.csv"
    with pytest.raises(physid.InputError, match=message):
        physid.simulate_floating(out, **kw)
    assert not out.exists()
    with pytest.raises(TypeError, match="'still'"):
        physid.simulate_floating(out, still="yes")
    with pytest.raises(physid.InputError, match="push: expected VX,VY,VZ"):
        physid.simulate_floating(out, push=(1.0, 2.0))
    with pytest.raises(TypeError, match="'push'"):
        physid.simulate_floating(out, push="fast")
    assert not out.exists()


def test_a_whole_robot_scenario_is_the_cli_s_not_experiment_s(tmp_path):
    scenario = tmp_path / "quadruped.toml"
    scenario.write_text("[whole_robot]\nsizes = [100]\nseeds = 1\n")
    with pytest.raises(physid.InputError, match=r"a whole-robot scenario \(\[whole_robot\]\)"):
        physid.experiment(scenario)


@pytest.mark.parametrize("rotors", [False, True])
def test_floating_robot_dynamics_are_pinocchio_s_free_flyer(tmp_path, rotors):
    # The quadruped exported as a floating URDF (rotors as mimic joints), read by pinocchio under
    # its free flyer; q, v, a in pinocchio's layout, the joints in physid's order.
    import pinocchio as pin
    urdf = tmp_path / "quadruped.urdf"
    cli("export", "--robot", "cheetah3", "--floating-base", "--urdf", str(urdf), *([] if rotors else ["--no-rotors"]))
    robot = physid.FloatingRobot("cheetah3", no_rotors=not rotors)
    model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer(), rotors)
    data = model.createData()
    nq, nv = robot.sizes
    assert (nq, nv) == (model.nq, model.nv) == (19, 18)
    jids = [model.getJointId(name) for name in robot.joint_names]
    iq = np.r_[0:7, [model.joints[j].idx_q for j in jids]]
    iv = np.r_[0:6, [model.joints[j].idx_v for j in jids]]
    rng = np.random.default_rng(3)
    qs, vs, as_ = [], [], []
    for _ in range(5):
        quat = rng.normal(size=4)
        qs.append(np.r_[rng.normal(size=3), quat / np.linalg.norm(quat), rng.uniform(-1, 1, nq - 7)])
        vs.append(rng.normal(size=nv))
        as_.append(rng.normal(size=nv))
    tau = robot.inverse_dynamics(np.array(qs), np.array(vs), np.array(as_))
    m = robot.mass_matrix(np.array(qs))
    y = robot.regressor(np.array(qs), np.array(vs), np.array(as_))
    assert tau.shape == (5, nv) and m.shape == (5, nv, nv) and y.shape == (5, nv, len(robot.parameter_names))
    for k, (q, v, a) in enumerate(zip(qs, vs, as_)):
        qp, vp, ap = np.zeros(nq), np.zeros(nv), np.zeros(nv)
        qp[iq], vp[iv], ap[iv] = q, v, a
        theirs = pin.rnea(model, data, qp, vp, ap)[iv]
        scale = np.abs(theirs).max()
        assert np.abs(tau[k] - theirs).max() < 1e-10 * scale
        mp = pin.crba(model, data, qp)
        mp = (np.triu(mp) + np.triu(mp, 1).T)[np.ix_(iv, iv)]
        assert np.abs(m[k] - mp).max() < 1e-10 * np.abs(mp).max()
        # The last 2n columns are the joints' viscous and Coulomb friction, which rnea leaves out.
        inertial = len(robot.parameter_names) - 2 * (nv - 6)
        assert np.abs(y[k][:, :inertial] @ robot.parameters()[:inertial] - theirs).max() < 1e-10 * scale
    one = robot.inverse_dynamics(qs[0], vs[0], as_[0])
    assert one.shape == (nv,) and np.array_equal(one, tau[0])
    again = pickle.loads(pickle.dumps(robot))
    assert again.parameter_names == robot.parameter_names and repr(again) == repr(robot)
    np.testing.assert_array_equal(again.inverse_dynamics(np.array(qs), np.array(vs), np.array(as_)), tau)


@pytest.mark.parametrize(
    "args, message",
    [
        ((np.zeros(19), np.zeros(18), np.zeros(18)), "q: sample 0: the quaternion .* has norm 0.000000000, not 1"),
        ((np.r_[np.zeros(6), 1.0, np.zeros(12)], np.zeros(17), np.zeros(18)), "v has shape \\[17\\]: give \\(samples, 18\\)"),
        ((np.r_[np.zeros(6), 1.0, np.zeros(12)], np.zeros((2, 18)), np.zeros(18)), "q has 1 samples, v 2 and a 1"),
        ((np.r_[np.zeros(6), np.nan, np.zeros(12)], np.zeros(18), np.zeros(18)), "q: sample 0, joint 6 is NaN"),
    ],
)
def test_bad_floating_states_are_named(args, message):
    with pytest.raises(physid.InputError, match=message):
        physid.FloatingRobot().inverse_dynamics(*args)


def test_a_floating_robot_is_taken_where_a_robot_is(log, tmp_path):
    robot = physid.FloatingRobot("cheetah3", no_rotors=True)
    by_object = physid.identify_floating(log, robot=robot, constraints="consistent")
    by_path = physid.identify_floating(log, no_rotors=True, constraints="consistent")
    np.testing.assert_array_equal(by_object.theta, by_path.theta)
    assert len(by_object.theta) == len(robot.parameter_names)
    with pytest.raises(physid.InputError, match="no_rotors: give it when loading the FloatingRobot"):
        physid.identify_floating(log, robot=robot, no_rotors=True)
    with pytest.raises(physid.InputError, match="robot: give a physid.FloatingRobot"):
        physid.simulate_floating(tmp_path / "never.csv", robot=3)
    assert not (tmp_path / "never.csv").exists()
