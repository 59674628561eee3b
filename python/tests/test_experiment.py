"""physid.experiment against the CLI's tables, independent of the thread count, with progress
and bad inputs."""
import os
import subprocess

import numpy as np
import pandas as pd
import pytest

import physid
from conftest import ROOT

CI = os.path.join(ROOT, "scenarios", "ci.toml")
TIMING = ["solve_ms", "solve_ms_median"]


@pytest.fixture(scope="module")
def ci():
    seen = []
    e = physid.experiment(CI, seeds=2, threads=2, progress=lambda done, total: seen.append((done, total)))
    return e, seen


def test_progress_counts_the_seeds_in_order(ci):
    _, seen = ci
    assert seen == [(1, 2), (2, 2)]


def test_tables_equal_the_clis(ci, tmp_path):
    e, _ = ci
    out = subprocess.run([os.environ["PHYSID_BIN"], "experiment", CI, "--seeds", "2", "--out", str(tmp_path / "r")],
                         capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    for got, name in [(e.rows(), "rows.csv"), (e.summary(), "summary.csv")]:
        ref = pd.read_csv(tmp_path / "r" / name)
        assert list(got.columns) == list(ref.columns)
        keep = [c for c in ref.columns if c not in TIMING]
        pd.testing.assert_frame_equal(got[keep], ref[keep], check_exact=True)
    assert len(e.rows()) == 2 * 4 * 4 and e.constraints == ["none", "semi", "consistent", "ellipsoid"]


def test_the_thread_count_changes_nothing(ci):
    e, _ = ci
    one = physid.experiment(CI, seeds=2, threads=1).rows()
    both = e.rows()
    keep = [c for c in both.columns if c not in TIMING]
    pd.testing.assert_frame_equal(one[keep], both[keep], check_exact=True)


def test_tighter_constraints_win_with_few_samples(ci):
    # The paper's claim on this scenario: at the smallest n_s the median validation error falls
    # from none to semi to consistent to ellipsoid.
    s = ci[0].summary()
    few = s[s["n_s"] == s["n_s"].min()].set_index("constraints")["val_rms_median"]
    assert few["none"] > few["semi"] > few["consistent"] > few["ellipsoid"]


def test_progress_counts_every_seed(ci):
    _, seen = ci
    assert sorted(seen) == [(1, 2), (2, 2)]


@pytest.mark.parametrize(
    "args, kw, message",
    [
        ([CI], dict(seeds=0), ".*ci.toml: experiment.seeds: must be at least 1"),
        ([os.path.join(ROOT, "scenarios", "excitation", "compare.toml")], {}, r".*compare.toml: an experiment over several excitation motions .* is not in the Python package yet"),
    ],
)
def test_bad_inputs(args, kw, message):
    with pytest.raises(physid.InputError, match="^" + message) as raised:
        physid.experiment(*args, **kw)
    assert "--" not in str(raised.value), "a CLI flag in a Python message"


def test_a_failing_progress_callback_raises_its_error():
    def boom(done, total):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        physid.experiment(CI, seeds=1, progress=boom)


def test_the_example_runs(tmp_path):
    import sys

    env = dict(os.environ, PYTHONPATH=os.environ.get("PHYSID_PYTHON", ""))
    out = subprocess.run([sys.executable, "python/examples/sample_size.py", str(tmp_path)],
                         capture_output=True, text=True, cwd=ROOT, env=env)
    assert out.returncode == 0, out.stderr
    assert "ellipsoid" in out.stdout and (tmp_path / "sample_size.png").stat().st_size > 10_000
