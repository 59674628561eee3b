"""physid.Robot: the CLI's robot flags as keyword arguments, its loader warnings, bad input."""
import warnings

import pytest

import physid
from conftest import KUKA_URDF


def test_loader_warnings_are_python_warnings():
    with pytest.warns(physid.PhysidWarning, match="kuka_lwr4.urdf: joint 'box_lwr_base_joint' has more than one <origin>"):
        physid.Robot(KUKA_URDF)


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
        (["nothing.urdf"], {}, "nothing.urdf: No such file or directory"),
        (["arm.xml"], {}, "arm.xml"),
        ([3], {}, "robot: give \"cheetah3\" or a path"),
        (["cheetah3"], dict(rotor_model="spinning"), "--rotor-model: 'spinning' is not one of full, reflected"),
        ([KUKA_URDF], dict(package_dirs="/no/such/folder"), "--package-dir /no/such/folder: does not exist"),
        ([KUKA_URDF], dict(ellipsoid_margin=-1.0), "margin"),
    ],
)
def test_bad_robots_raise_naming_what_is_wrong(args, kw, message):
    with pytest.raises(ValueError, match=message):
        physid.Robot(*args, **kw)
