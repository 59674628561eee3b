"""physid.Error and its subclasses: each also the built-in exception of its kind, messages in
keywords, a missing file named as Python names one."""
import errno

import pytest

import physid
from conftest import KUKA_URDF, kuka_run


def test_the_errors_are_the_builtins_of_their_kind():
    assert issubclass(physid.InputError, ValueError) and issubclass(physid.InputError, physid.Error)
    assert issubclass(physid.MissingFileError, FileNotFoundError)
    assert issubclass(physid.MissingFileError, physid.Error)
    assert issubclass(physid.SolverError, RuntimeError) and issubclass(physid.SolverError, physid.Error)
    assert not issubclass(physid.Error, ValueError)


@pytest.mark.parametrize(
    "call",
    [
        lambda missing: physid.Robot(missing / "arm.urdf"),
        lambda missing: physid.identify(physid.Robot("cheetah3"), missing / "run.csv"),
        lambda missing: physid.identify(physid.Robot(KUKA_URDF), kuka_run(1), validate_data=missing / "run.csv"),
        lambda missing: physid.load(physid.Robot("cheetah3"), missing / "run.mcap"),
        lambda missing: physid.simulate(missing / "scenario.toml", missing.parent / "out.mcap"),
        lambda missing: physid.experiment(missing / "scenario.toml"),
    ],
    ids=["robot", "identify data", "identify validate_data", "load", "simulate", "experiment"],
)
def test_a_missing_file_is_a_file_not_found_error_naming_it(tmp_path, call):
    missing = tmp_path / "nowhere"
    with pytest.raises(FileNotFoundError) as raised:
        call(missing)
    e = raised.value
    assert isinstance(e, physid.MissingFileError)
    assert e.errno == errno.ENOENT
    assert str(e.filename).startswith(str(missing))
    assert str(e) == f"[Errno 2] No such file or directory: '{e.filename}'"


def test_bad_keywords_are_input_errors_named_as_keywords():
    kuka = physid.Robot(KUKA_URDF)
    with pytest.raises(physid.InputError, match=r"^prior_weight must be a finite number >= 0, got -1$"):
        physid.identify(kuka, kuka_run(1), prior_weight=-1.0)
    with pytest.raises(physid.InputError, match=r"^train and validate pick samples of one data file"):
        physid.identify(kuka, [kuka_run(1), kuka_run(2)], train="0:100")
    with pytest.raises(physid.InputError, match=r"^rotor_model: 'spin' is not one of full, reflected$"):
        physid.Robot("cheetah3", rotor_model="spin")
