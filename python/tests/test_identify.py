"""physid.identify and physid.load against the CLI on the real KUKA runs, their outputs, and
their bad inputs."""
import os
import warnings

import numpy as np
import pytest

import physid
from conftest import KUKA_URDF, ROOT, kuka_run

TIMINGS = {"end_to_end_seconds", "seconds", "solve_seconds", "setup_seconds"}


def without_timings(v):
    if isinstance(v, dict):
        return {k: without_timings(x) for k, x in v.items() if k not in TIMINGS}
    if isinstance(v, list):
        return [without_timings(x) for x in v]
    return v


def quiet_identify(*args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", physid.PhysidWarning)
        return physid.identify(*args, **kw)


def test_identify_equals_the_cli_on_real_runs(kuka, cli):
    fit = quiet_identify(
        kuka, kuka_run(1), validate_data=kuka_run(2), constraints="consistent",
        friction="viscous,coulomb,offset",
    )
    ref = cli(
        "identify", "--robot", KUKA_URDF, "--data", kuka_run(1), "--validate-data", kuka_run(2),
        "--constraints", "consistent", "--friction", "viscous,coulomb,offset",
    )
    got = fit.to_dict()
    assert np.max(np.abs(np.array(got["theta"]) - np.array(ref["theta"]))) <= 1e-12
    assert without_timings(got) == without_timings(ref)
    assert np.array_equal(fit.theta, np.array(ref["theta"]))
    assert fit.parameter_names == ref["parameter_names"]
    assert fit.validation_rms == pytest.approx(ref["validation"]["rms_overall"], abs=0)
    assert fit.constraints == "consistent" and fit.constraints_hold


def test_sample_ranges_in_every_form_and_the_default_set(kuka, cli):
    ref = cli("identify", "--robot", KUKA_URDF, "--data", kuka_run(3), "--train", "0:2500",
              "--validate", "2500:")
    for train, validate in [("0:2500", "2500:"), ((0, 2500), (2500, None)), (range(0, 2500), (2500, None))]:
        fit = quiet_identify(kuka, kuka_run(3), train=train, validate=validate)
        assert without_timings(fit.to_dict()) == without_timings(ref)
    assert fit.constraints == ref["constraints"] == "ellipsoid"


def test_tables(kuka):
    fit = quiet_identify(kuka, [kuka_run(1)], validate_data=[kuka_run(2)], constraints="consistent")
    bodies, joints = fit.bodies(), fit.joints()
    d = fit.to_dict()
    assert list(bodies["name"]) == [b["name"] for b in d["bodies"]]
    assert np.allclose(bodies[["m", "hx", "hy", "hz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"]].to_numpy(),
                       [b["pi"] for b in d["bodies"]], rtol=0, atol=0)
    assert bodies["consistent"].all() and (bodies["min_eig_J"] > 0).all()
    assert list(joints["joint"]) == kuka.joint_names
    assert np.allclose(joints["validation_rms"], d["validation"]["rms"], rtol=0, atol=0)
    assert np.allclose(joints["viscous"], d["friction"]["viscous"], rtol=0, atol=0)
    assert "torque_offset" not in joints
    offsets = quiet_identify(kuka, kuka_run(1), friction="viscous,coulomb,offset").joints()
    effects = {e["kind"]: e for e in offsets_report(kuka)}
    assert np.array_equal(offsets["torque_offset"], effects["torque_offset"]["magnitudes"])


def offsets_report(kuka):
    return quiet_identify(kuka, kuka_run(1), friction="viscous,coulomb,offset").to_dict()["effects"]


def test_write_urdf_round_trips_and_never_overwrites_an_input(kuka, tmp_path):
    fit = quiet_identify(kuka, kuka_run(1), constraints="consistent")
    out = tmp_path / "identified.urdf"
    fit.write_urdf(str(out))
    assert out.exists() and (tmp_path / "identified.physid.toml").exists()
    back = physid.Robot(str(out))
    p = len(back.parameters()) - 2 * back.dof  # the inertias; friction follows
    assert np.allclose(back.parameters()[:p], fit.theta[:p], rtol=1e-9, atol=1e-12)
    before = open(kuka_run(1), "rb").read()
    with pytest.raises(ValueError, match="refusing to write over the input"):
        fit.write_urdf(kuka_run(1))
    assert open(kuka_run(1), "rb").read() == before


def test_warnings_are_python_warnings(kuka):
    with pytest.warns(physid.PhysidWarning, match="share 1000 samples"):
        fit = physid.identify(kuka, kuka_run(1), train="0:3000", validate="2000:4000")
    assert any("share 1000 samples" in n for n in fit.notices)


@pytest.mark.parametrize(
    "kw, message",
    [
        (dict(constraints="tight"), "constraints"),
        (dict(friction="viscous"), "friction: viscous and coulomb are the model's own"),
        (dict(friction=["viscous", "coulomb", "sticky"]), "friction: unknown term 'sticky'"),
        (dict(effects="bogus"), "effects: unknown term 'bogus'"),
        (dict(train="5:3"), r"train: 5:3 is not a non-empty range within the 5027 samples"),
        (dict(train="x:3"), "train: 'x' is not a sample index"),
        (dict(train=range(0, 100, 2)), "train: give"),
        (dict(train=3.5), "train: give"),
        (dict(validate="0:10", validate_data=kuka_run(2)), "give validate or validate_data, not both"),
        (dict(validate_data=kuka_run(1)), r".*measurements_1.csv: the same recording is given twice \(data .*measurements_1.csv and validate_data .*measurements_1.csv\)"),
        (dict(lock="nosuch"), "lock: the robot has no joint 'nosuch'"),
        (dict(only=["lwr_0_joint"], lock=["lwr_1_joint"]), "lock and only"),
        (dict(cutoff=-3.0), "cutoff must be a positive frequency in Hz, got -3"),
        (dict(cutoff=float("nan")), "cutoff must be a positive frequency"),
        (dict(prior_weight=-1.0), "prior_weight must be a finite number >= 0, got -1"),
        (dict(eps=float("inf")), "eps"),
        (dict(stamp="wall"), "stamp"),
        (dict(regularizer="l1"), "regularizer"),
        (dict(train="0:5"), ".*measurements_1.csv: 5 samples give 35 equations for 84 parameters: .* allow_few_samples"),
        (dict(mass_bounds=(2.0, 0.5)), r"mass_bounds 2,0.5: give factors"),
        (dict(mass_bounds=(-1.0, 2.0)), r"mass_bounds -1,2: give factors"),
        (dict(mass_bounds=(0.5, float("inf"))), r"mass_bounds 0.5,inf: give factors"),
        (dict(mass_bounds=(float("nan"), 2.0)), r"mass_bounds NaN,2: give factors"),
    ],
)
def test_bad_options_raise_the_clis_message(kuka, kw, message):
    with pytest.raises(physid.InputError, match="^" + message) as raised:
        quiet_identify(kuka, kuka_run(1), **kw)
    assert "--" not in str(raised.value), "a CLI flag in a Python message"


def test_bad_data_raise_naming_the_file(kuka, tmp_path):
    with pytest.raises(FileNotFoundError, match="No such file or directory: .*nope.csv") as e:
        physid.identify(kuka, str(tmp_path / "nope.csv"))
    # The operating system's reason once (before: twice, as the message and as its cause).
    assert str(e.value).count("No such file or directory") == 1, str(e.value)
    with pytest.raises(ValueError, match="data: give a path, a physid.Data or a list of them"):
        physid.identify(kuka, 42)
    with pytest.raises(ValueError, match="data: give at least one run"):
        physid.identify(kuka, [])
    bad = tmp_path / "bad.csv"
    lines = open(kuka_run(1)).read().splitlines()
    cells = lines[100].split(",")
    cells[3] = "nan"
    lines[100] = ",".join(cells)
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match="bad.csv"):
        physid.identify(kuka, str(bad))


def test_load_reads_like_identify(kuka, tmp_path):
    files = physid.load(kuka, [kuka_run(1), kuka_run(2)])
    assert [os.path.basename(f["file"]) for f in files] == ["measurements_1.csv", "measurements_2.csv"]
    run = files[0]["runs"][0]
    n = run["t"].shape[0]
    assert n == files[0]["pipeline"]["samples_kept"] > 5000 - 100
    for key in ["q", "qd", "qdd", "tau"]:
        assert run[key].shape == (n, kuka.dof) and np.isfinite(run[key]).all()
    # The file's own torque is what was read: the first kept sample's torque as in the CSV.
    header = open(kuka_run(1)).readline().strip().split(",")
    row = open(kuka_run(1)).read().splitlines()[1 + run["index"][0]].split(",")
    tau_cols = [header.index(f"tau{j}") for j in range(1, 8)]
    assert np.allclose(run["tau"][0], [float(row[i]) for i in tau_cols], rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="only: the robot has no joint 'x'"):
        physid.load(kuka, kuka_run(1), only="x")
    with pytest.raises(ValueError, match="stamp"):
        physid.load(kuka, kuka_run(1), stamp="later")


def test_the_examples_run(tmp_path):
    import subprocess
    import sys

    env = dict(os.environ, PYTHONPATH=os.environ.get("PHYSID_PYTHON", ""))
    out = subprocess.run([sys.executable, "python/examples/identify_from_files.py", str(tmp_path)],
                         capture_output=True, text=True, cwd=ROOT, env=env)
    assert out.returncode == 0, out.stderr
    assert "constraints hold: True" in out.stdout and (tmp_path / "kuka_identified.urdf").exists()


def physid_workers():
    """The process's threads named 'physid' (the workers of interruptible calls; Linux). A
    thread that ends between listing the tasks and reading its name is not one any more (the
    abandoned worker this test waits for is such a thread: reading its name raced its exit)."""
    tasks = "/proc/self/task"

    def name(t):
        try:
            with open(f"{tasks}/{t}/comm") as f:
                return f.read().strip()
        except (FileNotFoundError, ProcessLookupError):
            return None

    return [t for t in os.listdir(tasks) if name(t) == "physid"]


def test_ctrl_c_interrupts_a_long_identify(kuka, tmp_path):
    import _thread
    import signal
    import threading
    import time

    # Run 1 twenty times over (100,000 samples), so that the fit is still running when the
    # interrupt comes.
    lines = open(kuka_run(1)).read().splitlines()
    span = float(lines[-1].split(",", 1)[0]) + 0.001
    rows = [lines[0]]
    for k in range(20):
        for r in lines[1:]:
            t, rest = r.split(",", 1)
            rows.append(f"{float(t) + k * span:.6f},{rest}")
    long = tmp_path / "long.csv"
    long.write_text("\n".join(rows) + "\n")
    assert physid_workers() == []
    # A job a non-interactive shell starts in the background (`bash scripts/test.sh &`, some CI
    # runners) inherits SIGINT ignored, and interrupt_main then does nothing: Python's own
    # handler is put back for the test.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.3, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            quiet_identify(kuka, str(long), constraints="consistent")
    finally:
        signal.signal(signal.SIGINT, previous)
    # Interrupted, not finished: the abandoned fit is still running in its worker ...
    assert len(physid_workers()) == 1
    # ... which ends by itself, and the next call works.
    for _ in range(1200):
        if not physid_workers():
            break
        time.sleep(0.05)
    assert physid_workers() == []
    assert quiet_identify(kuka, kuka_run(2), constraints="consistent").constraints_hold


def test_mass_bounds_hold_every_mass_and_equal_the_cli(kuka, cli):
    # The slow real run 1 leaves several link masses to the constraints (up to 3.7 times the
    # URDF's); held within 0.5..2 times the description, every mass is, and the fit barely moves.
    kw = dict(constraints="consistent", friction="viscous,coulomb")
    free = quiet_identify(kuka, kuka_run(1), **kw)
    bounded = quiet_identify(kuka, kuka_run(1), mass_bounds=(0.5, 2.0), **kw)
    ref = cli("identify", "--robot", KUKA_URDF, "--data", kuka_run(1), "--constraints", "consistent",
              "--friction", "viscous,coulomb", "--mass-bounds", "0.5,2")
    assert without_timings(bounded.to_dict()) == without_timings(ref)
    described = {n[:-2]: v for n, v in zip(kuka.parameter_names, kuka.parameters()) if n.endswith(".m")}
    masses = {b["name"]: b["pi"][0] for b in bounded.to_dict()["bodies"]}
    outside = [n for n, m in {b["name"]: b["pi"][0] for b in free.to_dict()["bodies"]}.items()
               if not 0.5 <= m / described[n] <= 2.0]
    assert outside, "the free fit keeps every mass within bounds: the test shows nothing"
    for name, m in masses.items():
        assert 0.5 * described[name] * (1 - 1e-6) <= m <= 2.0 * described[name] * (1 + 1e-6), name
    assert any("at the upper bound" in n or "at the lower bound" in n for n in bounded.notices)
    assert bounded.train_rms <= free.train_rms * 1.01


def test_total_mass_holds_the_robot_s_mass_and_equals_the_cli(kuka, cli):
    # Run 1 alone puts 29.8 kg on a 14.4 kg arm (the masses it does not weigh go where the
    # constraints allow); held within 13..14 kg (a scale's reading), the total is 14 kg, on
    # the upper bound, said in a note; the description's own 14.4 kg outside is a warning.
    kw = dict(constraints="consistent", friction="viscous,coulomb")
    free = quiet_identify(kuka, kuka_run(1), **kw)
    held = quiet_identify(kuka, kuka_run(1), total_mass=(13.0, 14.0), **kw)
    ref = cli("identify", "--robot", KUKA_URDF, "--data", kuka_run(1), "--constraints", "consistent",
              "--friction", "viscous,coulomb", "--total-mass", "13,14")
    assert without_timings(held.to_dict()) == without_timings(ref)
    total = lambda r: sum(b["pi"][0] for b in r.to_dict()["bodies"])
    assert total(free) > 20.0, total(free)
    assert 13.0 <= total(held) <= 14.0 * (1 + 1e-6)
    assert any("at the upper bound of total_mass 13,14" in n for n in held.notices)
    assert any("the description's own total is 14.400 kg" in n for n in held.notices)
    for bad in [(0.0, 1.0), (2.0, 1.0), (float("nan"), 1.0)]:
        with pytest.raises(ValueError, match="total_mass"):
            physid.identify(kuka, kuka_run(1), total_mass=bad)
