"""physid.compare against the CLI on the committed results, and bad inputs."""
import os
import subprocess

import pytest

import physid
from conftest import ROOT

BASELINE = os.path.join(ROOT, "results", "ci_baseline")


def cli_compare(*args):
    # Never into a CI step summary: this is a test's comparison, not the run's.
    env = {k: v for k, v in os.environ.items() if k != "GITHUB_STEP_SUMMARY"}
    return subprocess.run([os.environ["PHYSID_BIN"], "compare", *args], capture_output=True, text=True,
                          cwd=ROOT, env=env)


def test_variant_equals_the_cli():
    c = physid.compare(BASELINE, variant="ellipsoid<=consistent", allow_too_few=True)
    out = cli_compare(BASELINE, "--variant", "ellipsoid<=consistent", "--allow-too-few")
    assert c.markdown() == out.stdout
    assert (c.regressions > 0) == (out.returncode == 1)
    g = c.groups()
    assert len(g) == len(c.to_dict()["groups"]) > 0
    assert set(g["outcome"]) <= {"pass", "regression", "too_few_pairs"}


def test_a_result_against_itself_passes():
    c = physid.compare(BASELINE, baseline=BASELINE, allow_too_few=True)
    out = cli_compare(BASELINE, "--baseline", BASELINE, "--allow-too-few")
    assert c.markdown() == out.stdout and c.regressions == 0 and out.returncode == 0
    assert (c.groups()["median_ratio"] == 1.0).all()


@pytest.mark.parametrize(
    "kw, message",
    [
        (dict(), "give baseline=DIR or variant"),
        (dict(variant="ellipsoid"), "variant 'ellipsoid': give two constraint sets as A<=B"),
        (dict(variant="a<=b", baseline=BASELINE), "give baseline or variant, not both"),
        (dict(variant="ellipsoid<=consistent", alpha=2.0), "alpha must be"),
        (dict(variant="ellipsoid<=consistent", metric="nope"), ".*rows.parquet: no column 'nope'"),
    ],
)
def test_bad_inputs(kw, message):
    with pytest.raises(physid.InputError, match="^" + message) as raised:
        physid.compare(BASELINE, **kw)
    assert "--" not in str(raised.value), "a CLI flag in a Python message"
