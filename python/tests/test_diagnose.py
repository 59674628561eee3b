"""physid.diagnose against the CLI on a real KUKA run: the same diagnosis, the same report
files, the notebook view, and bad inputs."""
import json
import os
import subprocess
import warnings

import numpy as np
import pytest

import physid
from conftest import KUKA, KUKA_URDF, ROOT, kuka_run
from test_identify import without_timings


@pytest.fixture(scope="module")
def run3(kuka):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", physid.PhysidWarning)
        return physid.diagnose(kuka, kuka_run(3))


def test_diagnosis_equals_the_cli(run3, cli, tmp_path):
    ref = cli("diagnose", "--robot", KUKA_URDF, "--data", kuka_run(3))
    assert without_timings(run3.to_dict()) == without_timings(ref)
    assert run3.verdict == ref["verdict"] and run3.summary == ref["summary"]
    assert run3.effect_kinds == [e["kind"] for e in ref["effects"]]
    gap = run3.gap()
    assert list(gap["joint"]) == [g["joint"] for g in ref["gap"]]
    assert np.array_equal(gap["nominal"].to_numpy(), [g["nominal"] for g in ref["gap"]])
    assert np.array_equal(gap["noise_floor"].to_numpy(), [g["noise_floor"] for g in ref["gap"]])
    for i, name in enumerate(run3.effect_kinds):
        assert np.array_equal(gap[f"+ {name}"].to_numpy(), [g["after"][i] for g in ref["gap"]])


def test_report_files_equal_the_clis(run3, tmp_path):
    binary = os.environ.get("PHYSID_BIN")
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    out = subprocess.run([binary, "diagnose", "--robot", KUKA_URDF, "--data", kuka_run(3), "--report", str(cli_dir)],
                         capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    run3.write_report(str(py_dir))
    names = sorted(os.listdir(cli_dir))
    assert names == sorted(os.listdir(py_dir)) and "report.html" in names and "how_far.svg" in names
    for name in names:
        a, b = (cli_dir / name).read_text(), (py_dir / name).read_text()
        if name == "report.json":
            a, b = without_timings(json.loads(a)), without_timings(json.loads(b))
        assert a == b, name
    assert run3.markdown() == (py_dir / "report.md").read_text()
    assert run3.text() == out.stdout and "\nHOW FAR\n" in out.stdout
    html = run3.html()
    assert html == (py_dir / "report.html").read_text() and html.count("<svg") >= 2
    assert run3._repr_html_() in html  # the notebook's view is the page's body


def test_write_report_never_into_an_input_folder(run3):
    with pytest.raises(ValueError, match="refusing to write over the folder of the input"):
        run3.write_report(KUKA)


@pytest.mark.parametrize(
    "kw, message",
    [
        (dict(baseline_data=kuka_run(2)), r"a baseline \(baseline_data\) needs description_uncertainty"),
        (dict(validate=kuka_run(3)), r".*measurements_3.csv: the same recording is given twice \(data .*measurements_3.csv and validate .*measurements_3.csv\)"),
        (dict(holdout=2.0), "the held-out fraction 2 must lie strictly between 0 and 1"),
        (dict(description_uncertainty=-1.0), "description_uncertainty must be a positive fraction"),
        (dict(constraints="tight"), "constraints"),
        (dict(lock="nosuch"), "lock: the robot has no joint 'nosuch'"),
        (dict(stamp="later"), "stamp"),
    ],
)
def test_bad_options_raise_the_clis_message(kuka, kw, message):
    with pytest.raises(physid.InputError, match="^" + message) as raised:
        physid.diagnose(kuka, kuka_run(3), **kw)
    assert "--" not in str(raised.value), "a CLI flag in a Python message"


def test_short_runs_warn(kuka, tmp_path):
    # The first 1,500 samples of run 3 (about 4 s), below the 10 s the cross-validation needs
    # for a decisive verdict.
    short = tmp_path / "short.csv"
    short.write_text("\n".join(open(kuka_run(3)).read().splitlines()[:1501]) + "\n")
    with pytest.warns(physid.PhysidWarning, match=r"\d\.\d s of training data: below 10 s"):
        d = physid.diagnose(kuka, str(short))
    assert any("s of training data" in n for n in d.notices)


def test_the_example_runs(tmp_path):
    import sys

    env = dict(os.environ, PYTHONPATH=os.environ.get("PHYSID_PYTHON", ""))
    out = subprocess.run([sys.executable, "python/examples/diagnose_in_a_notebook.py", str(tmp_path)],
                         capture_output=True, text=True, cwd=ROOT, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("partially_explained - ")
    assert (tmp_path / "kuka_diagnosis" / "report.html").exists()


def test_a_description_written_by_identify_carries_its_information(kuka, cli, tmp_path):
    from test_identify import quiet_identify

    fit = quiet_identify(kuka, kuka_run(1), constraints="consistent")
    out = tmp_path / "identified.urdf"
    fit.write_urdf(str(out))
    assert "\n[information]\nsamples = 5027\n" in (tmp_path / "identified.physid.toml").read_text()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", physid.PhysidWarning)
        described = physid.Robot(str(out))
        d = physid.diagnose(described, kuka_run(3))
        off = physid.diagnose(described, kuka_run(3), description_information=False)
    assert any("information matrix" in n and "5027 samples" in n for n in d.notices), d.notices
    assert any("plus 5 % stated" in n for n in d.notices), d.notices
    assert d.to_dict()["ladder"] is not None and off.to_dict()["ladder"] is None
    ref = cli("diagnose", "--robot", str(out), "--data", kuka_run(3))
    assert without_timings(d.to_dict()) == without_timings(ref)
    ref_off = cli("diagnose", "--robot", str(out), "--data", kuka_run(3), "--no-description-information")
    assert without_timings(off.to_dict()) == without_timings(ref_off)
