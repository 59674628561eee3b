"""physid.Robot: the CLI's robot flags as keyword arguments, its loader warnings, bad input."""
import shutil
import warnings

import pytest

import physid
from conftest import KUKA_URDF


def test_loader_warnings_are_python_warnings_once_per_file(tmp_path):
    # A copy: the KUKA's own file may have been loaded (and warned about) by another test.
    urdf = tmp_path / "kuka_copy.urdf"
    shutil.copy(KUKA_URDF, urdf)
    warning = "kuka_copy.urdf: joint 'box_lwr_base_joint' has more than one <origin>"
    with pytest.warns(physid.PhysidWarning, match=warning):
        first = physid.Robot(urdf)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a second warning about the same file would raise
        again = physid.Robot(urdf)
    for robot in (first, again):
        assert any(warning in n and n.startswith("warning: ") for n in robot.notices)


@pytest.mark.parametrize(
    "flags, kw",
    [
        (["--no-rotors"], dict(no_rotors=True)),
        (["--rotor-model", "reflected"], dict(rotor_model="reflected")),
    ],
)
def test_robot_options_equal_the_cli_flags(cli, flags, kw):
    robot = physid.Robot("cheetah3", **kw)
    assert robot.describe() == cli("model", "--robot", "cheetah3", *flags)
    assert robot.describe() != physid.Robot("cheetah3").describe()


def test_ellipsoid_options_equal_the_cli_flags(cli):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", physid.PhysidWarning)
        for flags, kw in [
            (["--ellipsoid-margin", "0.05"], dict(ellipsoid_margin=0.05)),
            (["--no-geometry-ellipsoids"], dict(no_geometry_ellipsoids=True)),
        ]:
            assert physid.Robot(KUKA_URDF, **kw).describe() == cli("model", "--robot", KUKA_URDF, *flags)


@pytest.mark.parametrize(
    "args, kw, message",
    [
        (["arm.xml"], {}, "unknown robot 'arm.xml'"),
        ([3], {}, "robot: give \"cheetah3\" or a path"),
        (["cheetah3"], dict(rotor_model="spinning"), "rotor_model: 'spinning' is not one of full, reflected"),
        ([KUKA_URDF], dict(package_dirs="/no/such/folder"), "package_dir /no/such/folder: does not exist"),
        ([KUKA_URDF], dict(ellipsoid_margin=-1.0), ".*kuka_lwr4.urdf: ellipsoid margin -1 m must be"),
    ],
)
def test_bad_robots_raise_naming_what_is_wrong(args, kw, message):
    with pytest.raises(physid.InputError, match="^" + message) as raised:
        physid.Robot(*args, **kw)
    assert "--" not in str(raised.value), "a CLI flag in a Python message"
