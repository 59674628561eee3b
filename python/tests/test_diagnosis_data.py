"""The diagnosis as data: a payload injected into a real KUKA run (computed with the robot's
own regressor, the logged q, q̇, q̈) is a physid.BodyChange with its mass and centre of mass;
the ladder and the effects are DataFrames equal to the report's JSON; the unchanged run
names no payload."""
import warnings

import numpy as np
import pytest

import physid
from conftest import KUKA_URDF, kuka_run

PI_NAMES = ["m", "hx", "hy", "hz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"]


def point_mass(mass, com):
    """π of a point mass `mass` (kg) at `com` (m, body frame): inertia about the frame origin."""
    c = np.asarray(com, dtype=float)
    inertia = mass * (c @ c * np.eye(3) - np.outer(c, c))
    return np.array([mass, *(mass * c), inertia[0, 0], inertia[0, 1], inertia[0, 2],
                     inertia[1, 1], inertia[1, 2], inertia[2, 2]])


def with_payload(robot, src, dst, body, pi):
    """The KUKA log `src` written to `dst` with a payload π on `body` added to its torques."""
    header = open(src).readline().strip().split(",")
    data = np.loadtxt(src, delimiter=",", skiprows=1)
    col = {name: i for i, name in enumerate(header)}
    joints = range(1, robot.dof + 1)
    q, qd, qdd = (data[:, [col[f"{s}{j}"] for j in joints]] for s in ("q", "dq", "ddq"))
    names = robot.parameter_names
    columns = [names.index(f"{body}.{k}") for k in PI_NAMES]
    tau = robot.regressor(q, qd, qdd)[:, :, columns] @ pi
    for j in joints:
        data[:, col[f"tau{j}"]] += tau[:, j - 1]
    np.savetxt(dst, data, delimiter=",", header=",".join(header), comments="", fmt="%.10g")


@pytest.fixture(scope="module")
def diagnoses(tmp_path_factory):
    """The description identified on run 1 (its sidecar carries the fit's information, so the
    diagnosis reads it with a ladder); run 3 with 2 kg at 5 cm on the flange, and run 3 as
    it is."""
    folder = tmp_path_factory.mktemp("payload")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", physid.PhysidWarning)
        kuka = physid.Robot(KUKA_URDF)
        physid.identify(kuka, kuka_run(1), constraints="consistent").write_urdf(folder / "described.urdf")
        described = physid.Robot(folder / "described.urdf")
        with_payload(kuka, kuka_run(3), folder / "loaded.csv", "lwr_7_link", point_mass(2.0, [0, 0, 0.05]))
        return physid.diagnose(described, folder / "loaded.csv"), physid.diagnose(described, kuka_run(3))


def test_the_payload_is_a_value_with_its_mass_and_centre_of_mass(diagnoses):
    loaded, unchanged = diagnoses
    p = loaded.payload
    assert isinstance(p, physid.BodyChange) and p.payload and p.body == "lwr_7_link"
    assert abs(p.mass - 2.0) < 0.1 and 0 < p.mass_se < 0.05, p
    assert np.linalg.norm(np.subtract(p.com, [0, 0, 0.05])) < 0.03, p.com
    assert loaded.bodies[0] == p and len(p.pi) == 10
    ladder = loaded.to_dict()["ladder"]
    assert p.mass == ladder["bodies"][0]["mass"] and p.final_mass == ladder["bodies"][0]["last"]["mass"]
    assert unchanged.payload is None
    assert all(not b.payload for b in unchanged.bodies)


def test_the_ladder_is_a_table_of_the_reports_rungs(diagnoses):
    loaded, unchanged = diagnoses
    for d in (loaded, unchanged):
        table, rungs = d.ladder(), d.to_dict()["ladder"]["rungs"]
        assert list(table["step"]) == [r["step"] for r in rungs]
        assert np.array_equal(table["overall"].to_numpy(), [r["overall"] for r in rungs])
        joints = d.to_dict()["joints"]
        assert list(table.columns[-len(joints):]) == joints
        assert np.array_equal(table[joints].to_numpy(), [r["rms"] for r in rungs])
    table = loaded.ladder()
    step = table[table["step"] == "+ payload on lwr_7_link"]
    assert len(step) == 1 and step["kind"].iloc[0] == "payload"
    assert step["mass"].iloc[0] == loaded.payload.mass
    assert table["mass"].isna().sum() == len(table) - 1
    assert not unchanged.ladder()["kind"].isin(["payload", "body_change"]).any()


def test_the_effects_are_a_long_table_of_the_reports_magnitudes(diagnoses):
    loaded, _ = diagnoses
    report = loaded.to_dict()
    table = loaded.effects()
    found = report["effects"] + report["described_effects"]
    assert len(table) == sum(len(e["magnitudes"]) for e in found)
    first = found[0]
    rows = table[table["effect"] == first["kind"]]
    assert list(rows["joint"]) == [m["joint"] for m in first["magnitudes"]]
    assert np.array_equal(rows["value"].to_numpy(), [m["value"] for m in first["magnitudes"]])
    assert np.array_equal(rows["se"].to_numpy(), [m["se"] for m in first["magnitudes"]])
    assert loaded.effect_kinds == [e["kind"] for e in report["effects"]]
    assert "payload" in set(table["effect"])


def test_without_a_ladder_the_tables_have_their_columns_and_no_rows(kuka):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", physid.PhysidWarning)
        d = physid.diagnose(kuka, kuka_run(3), description_information=False)
    assert d.to_dict()["ladder"] is None and d.bodies == [] and d.payload is None
    table = d.ladder()
    assert len(table) == 0 and list(table.columns[:3]) == ["step", "kind", "param"]
    assert list(d.ladder(backend="polars").columns) == list(table.columns)


def test_the_find_a_payload_example_runs(tmp_path):
    import os
    import subprocess
    import sys

    from conftest import ROOT

    env = dict(os.environ, PYTHONPATH=os.environ.get("PHYSID_PYTHON", ""))
    out = subprocess.run([sys.executable, "python/examples/find_a_payload.py", str(tmp_path)],
                         capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert "payload=True" in lines[0] and "body='lwr_7_link'" in lines[0]
    assert lines[-1].startswith("diagnosis: lwr_7_link carries 2.0")
    assert lines[-2].startswith("identification: validation RMS 0.")
    assert (tmp_path / "ladder.png").stat().st_size > 1000 and (tmp_path / "identified.physid.toml").exists()
