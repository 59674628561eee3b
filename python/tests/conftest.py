"""pytest fixtures of the Python package's tests: the package built by scripts/test.sh
($PHYSID_PYTHON, a folder holding physid/ with its extension), the CLI binary ($PHYSID_BIN)
for the comparisons, and the repository's data."""
import json
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
KUKA = os.path.join(ROOT, "data", "kuka_lwr4")
KUKA_URDF = os.path.join(KUKA, "kuka_lwr4.urdf")

if os.environ.get("PHYSID_PYTHON"):
    sys.path.insert(0, os.environ["PHYSID_PYTHON"])


def kuka_run(k):
    return os.path.join(KUKA, f"measurements_{k}.csv")


@pytest.fixture(scope="session")
def cli():
    """Runs `physid ARGS... --json` and returns the parsed JSON."""
    binary = os.environ.get("PHYSID_BIN") or os.path.join(
        os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release", "physid"
    )
    if not os.path.exists(binary):
        pytest.fail(f"no physid binary at {binary}: build it (cargo build --release) or set PHYSID_BIN")

    def call(*args):
        out = subprocess.run([binary, *args, "--json"], capture_output=True, text=True, cwd=ROOT)
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout)

    return call


@pytest.fixture(scope="session")
def kuka():
    import warnings

    import physid

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", physid.PhysidWarning)
        return physid.Robot(KUKA_URDF)
