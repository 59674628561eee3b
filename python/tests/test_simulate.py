"""physid.simulate against the CLI, its signals against the robot's own inverse dynamics,
progress, identification of the simulated log against its ground truth, and bad inputs."""
import json
import os
import subprocess

import numpy as np
import pytest

import physid
from conftest import ROOT
from test_identify import without_timings

SHELL = os.path.join(ROOT, "scenarios", "cheetah3_shell.toml")
TIMINGS = {"wall_seconds", "real_time_factor"}


def strip(report):
    report = without_timings(report)
    return {k: v for k, v in report.items() if k not in TIMINGS | {"out"}}


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    d = tmp_path_factory.mktemp("sim")
    seen = []
    sim = physid.simulate(SHELL, str(d / "run.mcap"), csv=str(d / "run.csv"), duration=2.0, seed=3,
                          progress=seen.append)
    return sim, d, seen


def test_simulation_equals_the_cli(run, tmp_path):
    sim, d, _ = run
    binary = os.environ.get("PHYSID_BIN")
    out = subprocess.run([binary, "simulate", SHELL, "--out", str(tmp_path / "cli.mcap"), "--csv",
                          str(tmp_path / "cli.csv"), "--duration", "2", "--seed", "3", "--json"],
                         capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    ref = json.loads(out.stdout)
    got = sim.to_dict()
    assert strip(got) == strip(ref) and got["out"] == str(d / "run.mcap")
    assert (d / "run.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()


def test_signals_are_the_robots_own_dynamics(run):
    sim, d, _ = run
    truth, robot = sim.truth, sim.robot
    n = robot.dof
    assert truth["q"].shape == (len(truth["t"]), n) and len(truth["t"]) == sim.to_dict()["samples"]
    # The actuators' torque is the rigid-body torque (the regressor times the true inertias,
    # friction columns zeroed) plus the true friction and effect torques.
    theta = robot.parameters()
    theta[-2 * n:] = 0.0
    rigid = robot.regressor(truth["q"], truth["qd"], truth["qdd"]) @ theta
    scale = np.max(np.abs(truth["tau"]))
    residual = rigid + truth["friction"] + truth["effects"] - truth["tau"]
    assert np.max(np.abs(residual)) <= 1e-12 * scale
    csv = np.loadtxt(d / "run.csv", delimiter=",", skiprows=1)
    p = sim.processed
    assert np.allclose(csv[:, 0], p["t"], rtol=0, atol=1e-9)
    assert np.allclose(csv[:, 1:1 + n], p["q"], rtol=1e-12, atol=1e-12)


def test_progress_reaches_one_in_order(run):
    _, _, seen = run
    assert len(seen) >= 10 and seen[-1] == 1.0 and seen == sorted(seen)


def test_the_simulated_log_identifies_as_the_cli_does(run, cli):
    sim, d, _ = run
    log = str(d / "run.mcap")
    fit = physid.identify(physid.Robot("cheetah3"), log, train="0:1200", validate="1200:")
    ref = cli("identify", "--data", log, "--train", "0:1200", "--validate", "1200:")
    assert without_timings(fit.to_dict()) == without_timings(ref)
    assert fit.constraints == "ellipsoid" and fit.constraints_hold
    # The log carries its ground truth: every body's errors are reported.
    assert [e["name"] for e in ref["truth_errors"]] == [b["name"] for b in ref["bodies"]]


@pytest.mark.parametrize(
    "kw, message",
    [
        (dict(engine="bullet"), "engine: 'bullet' is not one of physid, rapier"),
        (dict(duration=-1.0), "simulating .*cheetah3_shell.toml: scenario simulation.duration: -1 must be a finite number > 0"),
    ],
)
def test_bad_options(tmp_path, kw, message):
    with pytest.raises(physid.InputError, match="^" + message) as raised:
        physid.simulate(SHELL, str(tmp_path / "x.mcap"), **kw)
    assert "--" not in str(raised.value), "a CLI flag in a Python message"
    assert not (tmp_path / "x.mcap").exists()


def test_outputs_never_replace_inputs(tmp_path):
    before = open(SHELL, "rb").read()
    with pytest.raises(ValueError, match="refusing to write over the input"):
        physid.simulate(SHELL, SHELL)
    assert open(SHELL, "rb").read() == before
    with pytest.raises(FileNotFoundError, match="nope.toml"):
        physid.simulate(str(tmp_path / "nope.toml"), str(tmp_path / "x.mcap"))


def test_a_failing_progress_callback_raises_its_error(tmp_path):
    def boom(f):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        physid.simulate(SHELL, str(tmp_path / "x.mcap"), duration=0.5, progress=boom)


def test_the_integrator_is_the_scenario_s_and_named_in_the_report(tmp_path):
    """Ralston's third-order method through the package: the report names it as the CLI's
    does; with the sensors ideal (no quantization or noise, the true velocity fed back, so
    that only the integration differs) one step per period of either method stays within the
    scenario's error budget, a tenth of its 0.3 N m torque noise, of RK4 at 16 steps; and the
    rapier engine refuses a physid integrator by key, writing nothing."""
    text = open(SHELL).read()
    ideal = (text.replace("encoder_step = 3.6e-5 ", "encoder_step = 0.0 ")
             .replace('velocity_feedback = "finite_difference"', 'velocity_feedback = "true"'))
    assert ideal.count("= 0.0 ") > text.count("= 0.0 ") and '"true"' in ideal

    def scenario(method, substeps):
        p = tmp_path / f"{method}_{substeps}.toml"
        p.write_text(ideal.replace("substeps = 4 ", f"substeps = {substeps} ")
                     .replace("seed = 1\n", f'seed = 1\nintegrator = "{method}"\n'))
        return str(p)

    def tau(method, substeps):
        sim = physid.simulate(scenario(method, substeps), str(tmp_path / f"{method}_{substeps}.mcap"),
                              duration=1.0)
        d = sim.to_dict()
        assert (d["engine"], d["integrator"], d["substeps"]) == ("physid", method, substeps)
        return sim.truth["tau"]

    reference = tau("rk4", 16)
    for method in ["rk4", "ralston3"]:
        error = np.max(np.abs(tau(method, 1) - reference))
        assert 0.0 < error < 0.03, (method, error)
    with pytest.raises(ValueError, match="simulation.integrator.*rapier"):
        physid.simulate(scenario("ralston3", 1), str(tmp_path / "r.mcap"), engine="rapier")
    assert not (tmp_path / "r.mcap").exists()


def interrupted(call, after=0.3):
    """`call()` interrupted by a Ctrl-C `after` seconds in (KeyboardInterrupt expected)."""
    import _thread
    import signal
    import threading

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(after, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            call()
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)


def test_an_interrupted_simulation_stops_and_writes_nothing(tmp_path):
    # Before: the abandoned run kept going and wrote its log seconds later, over the file of
    # the next call.
    import time

    from test_identify import physid_workers

    out, csv = tmp_path / "long.mcap", tmp_path / "long.csv"
    interrupted(lambda: physid.simulate(SHELL, str(out), csv=str(csv), duration=100.0))
    # The worker stops at its next progress report (a percent of the run) ...
    for _ in range(400):
        if not physid_workers():
            break
        time.sleep(0.05)
    assert physid_workers() == []
    # ... and wrote nothing.
    assert not out.exists() and not csv.exists()
    assert [p.name for p in tmp_path.iterdir()] == []
