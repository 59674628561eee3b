"""The scripts' command lines: every script in scripts/ prints its usage and options with `-h`
(status 0, nothing run), and refuses an unknown option or a bad value with status 2 and a
message naming it, before running anything. The scripts run side by side, each in its own
process, as a user would call them.
"""
import glob
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

from physid_common import ROOT, Report, arguments

HERE = os.path.join(ROOT, "scripts")
NOT_SCRIPTS = {"physid_common", "panda_truth"}
# Positional arguments a script requires before it looks at options.
POSITIONALS = {"check_main_outputs": ["results"], "excite_peer": ["a.toml", "a.json", "b.toml"]}

# Bad values of the scripts' own options, with the words the refusal must contain.
BAD_VALUES = [
    ("bench_commands", ["--rounds", "0"], "--rounds: 0 is not at least 1"),
    ("bench_commands", ["--rows", "diagnose"], "unknown diagnose (choose from"),
    ("bench_commands", ["--threads", "1,x"], "--threads: 1,x is not a list of thread counts"),
    ("bench_commands", ["--threads", "2,0"], "--threads: 0 is not at least 1"),
    ("bench_commands", ["--blind-cases", "0"], "--blind-cases: 0 is not at least 1"),
    ("bench_identify", ["--rounds"], "--rounds: expected one argument"),
    ("bench_identify", ["--rows", ","], "--rows: no name given (choose from"),
    ("peer_pinocchio_cvxpy", ["--samples", "-3"], "--samples: -3 is not at least 1"),
    ("peer_pinocchio_cvxpy", ["--samples", "ten"], "--samples: invalid positive_int value: 'ten'"),
    ("excite_peer", ["a.toml", "a.json"], "required: OUT.toml"),
    ("excite_peer", ["a.toml", "a.json", "b.toml", "--maxiter", "0"], "--maxiter: 0 is not at least 1"),
    ("check_main_outputs", [], "required: RESULT_DIR"),
]


def call(script, args):
    """Status and combined output of `python scripts/<script>.py args`."""
    res = subprocess.run([sys.executable, os.path.join(HERE, f"{script}.py"), *args],
                         capture_output=True, text=True, timeout=120)
    return res.returncode, res.stdout + res.stderr


def main():
    arguments(__doc__, binary=False)
    scripts = sorted(os.path.basename(p)[:-3] for p in glob.glob(os.path.join(HERE, "*.py")))
    scripts = [s for s in scripts if s not in NOT_SCRIPTS and s != "check_scripts_cli"]
    cases = [(s, ["-h"]) for s in scripts] + [(s, [*POSITIONALS.get(s, []), "--no-such-option"]) for s in scripts]
    cases += [(s, args) for s, args, _ in BAD_VALUES]
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        results = list(pool.map(lambda case: call(*case), cases))
    report = Report("scripts' command lines")
    for (script, args), (status, out) in zip(cases[:2 * len(scripts)], results):
        if args == ["-h"]:
            ok = status == 0 and out.startswith(f"usage: {script}.py")
            report.check(f"{script} -h prints its usage (status {status})", ok)
        else:
            ok = status == 2 and "unrecognized arguments: --no-such-option" in out
            report.check(f"{script} refuses an unknown option (status {status})", ok)
    for (script, args, words), (status, out) in zip(BAD_VALUES, results[2 * len(scripts):]):
        ok = status == 2 and words in out
        report.check(f"{script} {' '.join(args) or '(no arguments)'}: status {status}, "
                     f"names it ({words!r})", ok)
    report.finish()


if __name__ == "__main__":
    main()
