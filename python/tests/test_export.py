"""Robot.write_mjcf / write_urdf and Identification.write_mjcf: the CLI's export bytes, MuJoCo
loading the file with the masses written, and never over an input."""
import os
import subprocess
import warnings

import numpy as np
import pytest

import physid
from conftest import ROOT, KUKA_URDF, kuka_run
from test_identify import quiet_identify


def test_robot_exports_equal_the_clis(tmp_path):
    leg = physid.Robot("cheetah3")
    leg.write_mjcf(str(tmp_path / "py.xml"))
    leg.write_urdf(str(tmp_path / "py.urdf"))
    binary = os.environ.get("PHYSID_BIN")
    out = subprocess.run([binary, "export", "--robot", "cheetah3", "--mjcf", str(tmp_path / "cli.xml"),
                          "--urdf", str(tmp_path / "cli.urdf")], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "py.xml").read_bytes() == (tmp_path / "cli.xml").read_bytes()
    assert (tmp_path / "py.urdf").read_bytes() == (tmp_path / "cli.urdf").read_bytes()
    assert (tmp_path / "py.physid.toml").read_text() == (tmp_path / "cli.physid.toml").read_text().replace("cli.urdf", "py.urdf")


def test_the_identified_mjcf_carries_the_identified_masses(kuka, tmp_path):
    mujoco = pytest.importorskip("mujoco")
    fit = quiet_identify(kuka, kuka_run(1), constraints="consistent")
    path = tmp_path / "identified.xml"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", physid.PhysidWarning)
        fit.write_mjcf(str(path))
    m = mujoco.MjModel.from_xml_path(str(path))
    bodies = fit.bodies()
    for name, mass in zip(bodies["name"], bodies["m"]):
        assert m.body(name).mass[0] == pytest.approx(mass, rel=1e-9), name
    with pytest.raises(ValueError, match="refusing to write over the input"):
        fit.write_mjcf(KUKA_URDF)
    with pytest.raises(ValueError, match="refusing to write over the input"):
        kuka.write_urdf(KUKA_URDF)
