"""Helpers shared by the cross-check scripts: run the physid binary, load its JSON."""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

# Paper order [m, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz] from pinocchio's
# [m, hx, hy, hz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]: paper[k] = pin[PIN_FROM_PAPER[k]].
PIN_FROM_PAPER = [0, 1, 2, 3, 4, 5, 7, 6, 8, 9]

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
KUKA_URDF = os.path.join(ROOT, "data", "kuka_lwr4", "kuka_lwr4.urdf")
SOLO12_URDF = os.path.join(ROOT, "data", "solo12", "solo12.urdf")


def arguments(doc, *options, binary=True):
    """The script's command line, parsed: `--physid PATH` (if the script runs the `binary`) and
    the script's own `options`, each `(flags, argparse keywords)`. `-h` prints the script's
    docstring; an unknown option, a missing value or a value of the wrong type exits with
    argparse's message naming it."""
    parser = argparse.ArgumentParser(description=doc,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    if binary:
        parser.add_argument("--physid", metavar="PATH",
                            help="the physid binary (default: $PHYSID_BIN, else the release build)")
    for flags, keywords in options:
        parser.add_argument(*flags, **keywords)
    return parser.parse_args()


# The `--package DIR` option of the scripts that import the built Python package.
PACKAGE_OPTION = (["--package"], dict(
    metavar="DIR", default=os.environ.get("PHYSID_PYTHON"),
    help="a folder holding the built physid package (default: $PHYSID_PYTHON)"))


def on_path(package):
    """Puts the built package's folder (`--package`) first on the import path; exits saying
    what to give when there is none."""
    if not package:
        sys.exit("give --package DIR or $PHYSID_PYTHON (a folder holding the built physid package)")
    sys.path.insert(0, package)


def positive_int(text):
    """An argparse type: an integer of at least 1."""
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text} is not at least 1")
    return value


def names_from(choices):
    """An argparse type: a comma-separated list of names, each one of `choices`."""
    def parse(text):
        names = [n for n in text.split(",") if n]
        unknown = [n for n in names if n not in choices]
        if unknown or not names:
            what = f"unknown {', '.join(unknown)}" if unknown else "no name given"
            raise argparse.ArgumentTypeError(f"{what} (choose from {', '.join(choices)})")
        return names
    return parse


def physid_bin(path=None):
    """The physid binary: `path` (from --physid), $PHYSID_BIN, or the release build."""
    if path:
        return path
    if os.environ.get("PHYSID_BIN"):
        return os.environ["PHYSID_BIN"]
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
    return os.path.join(target, "release", "physid")


def timed(cmd):
    """Wall time (s) and stdout of a whole process (`cmd` with its arguments); exits naming the
    command if it fails."""
    t0 = time.perf_counter()
    res = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if res.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{res.stderr}")
    return wall, res.stdout


def run(binary, *args):
    res = subprocess.run([binary, *args], capture_output=True, text=True)
    if res.returncode != 0:
        sys.exit(f"physid {' '.join(args)} failed:\n{res.stderr}")
    return res.stdout


def dynamics(binary, robot_args, samples=25, seed=7):
    """Random states with physid's tau, Y and H, as a dict."""
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "dyn.json")
        run(binary, "dynamics", *robot_args, "--samples", str(samples), "--seed", str(seed), "--out", out)
        with open(out) as f:
            return json.load(f)


def export(binary, robot_args, fmt, directory):
    path = os.path.join(directory, "model." + ("xml" if fmt == "mjcf" else "urdf"))
    run(binary, "export", *robot_args, f"--{fmt}", path)
    return path


class Report:
    """Collects (case, max error, tolerance) and exits non-zero if any exceeds its tolerance."""

    def __init__(self, name):
        self.name, self.rows = name, []

    def add(self, case, err, tol):
        ok = err <= tol
        self.rows.append(ok)
        print(f"{'ok  ' if ok else 'FAIL'} {case:<58} max rel. error {err:.2e} (tol {tol:.2g})")

    def check(self, case, ok):
        """A pass/fail check without a numeric error."""
        self.rows.append(bool(ok))
        print(f"{'ok  ' if ok else 'FAIL'} {case}")

    def finish(self):
        failed = self.rows.count(False)
        print(f"{self.name}: {len(self.rows) - failed} passed, {failed} failed")
        sys.exit(1 if failed or not self.rows else 0)


def rel_err(a, b):
    import numpy as np
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / (1.0 + np.max(np.abs(b))))


def identified_quadruped(binary, directory, robot_args, seconds=3):
    """The quadruped simulated standing for `seconds` (`simulate-floating`, noisy sensors) and
    identified from that log (`identify-floating`, ellipsoid set): its JSON, and the identified
    robot written as URDF (trunk as root link) and MJCF (free joint)."""
    log = os.path.join(directory, "standing.csv")
    urdf = os.path.join(directory, "identified_quadruped.urdf")
    xml = os.path.join(directory, "identified_quadruped.xml")
    run(binary, "simulate-floating", *robot_args, "--out", log, "--duration", str(seconds))
    out = run(binary, "identify-floating", *robot_args, "--data", log, "--out-urdf", urdf,
              "--out-mjcf", xml, "--json")
    return json.loads(out), urdf, xml
