"""The commands a user waits on, whole process, and how parallel work scales (issue 58).

Rows (medians of `--rounds` runs, default 5, each a fresh process):

- `diagnose_kuka`: `physid diagnose` of the real KUKA run 3 against the description identified
  on runs 1 and 2 (`identify --out-urdf`, untimed), report written;
- `excite_kuka`: `physid excite --robot kuka_lwr4.urdf --duration 30`, checked in simulation;
- `main_job_T`: the main job (`physid experiment scenarios/sample_size.toml --threads T`) for
  each T of `--threads` (default 1,2,4,8,16), with its speed-up over one thread and the
  parallel efficiency (speed-up / min(T, cores)); threads beyond the machine's cores are run
  and reported, marked as oversubscribed. With `--quick` the main job runs 3 seeds.
- `blind_T`: the simulated blind benchmark (`physid blind --cases N --seed 1 --threads T`,
  `--blind-cases`, default 21: one of each category's slots) for each T of `--threads`, scaled
  the same way. Not in the default rows (a 21-case run takes about half a minute on 2 cores);
  `--rows blind` adds it.

- `excite_kuka_scipy_peer`: scripts/excite_peer.py, SLSQP over pinocchio's regressor with the
  same basis, objective, timing and limits as physid's design (from its scenario and JSON),
  run side by side (`--no-peer` skips it: it takes one to two minutes a run). Both designs are
  scored on their true motion by `physid excite --score`.

There is no Python peer of the diagnosis. Timing is reported, never asserted.
"""
import argparse
import json
import os
import re
import statistics
import sys
import tempfile

from physid_common import (KUKA_URDF, ROOT, arguments, names_from, physid_bin, positive_int, run,
                           timed)

ROWS = ["diagnose_kuka", "excite_kuka", "main_job", "blind"]
DEFAULT_ROWS = ["diagnose_kuka", "excite_kuka", "main_job"]


def median_of(cmd, rounds):
    """Median and spread (min, max) of `rounds` whole-process runs, and the last run's stdout."""
    runs = [timed(cmd) for _ in range(rounds)]
    times = [t for t, _ in runs]
    return statistics.median(times), min(times), max(times), runs[-1][1]


def main_job_scenario(d, quick):
    """The main job's scenario, or a copy with 3 seeds (`--quick`), its paths kept."""
    path = os.path.join(ROOT, "scenarios", "sample_size.toml")
    if not quick:
        return path
    with open(path) as f:
        text = f.read()
    text = re.sub(r"(?m)^seeds\s*=.*$", "seeds = 3", text)
    copy = os.path.join(d, "sample_size.toml")
    with open(copy, "w") as f:
        f.write(text)
    return copy


def score(binary, scenario):
    """`log det F / r` of a written scenario's true motion, by `physid excite --score`."""
    out = run(binary, "excite", "--scenario", scenario, "--score", "--duration", "30", "--json")
    return json.loads(out)["d_optimal"]


def excite_rows(binary, d, rounds, peer):
    """physid's 30 s KUKA design, and the SciPy peer's of the same objective from the same
    timing and limits, each timed whole-process and scored on its true motion by one scorer."""
    out = os.path.join(d, "kuka_excitation.toml")
    m, lo, hi, report = median_of([binary, "excite", "--robot", KUKA_URDF, "--duration", "30",
                                   "--out", out, "--json"], rounds)
    design = os.path.join(d, "kuka_excitation.json")
    with open(design, "w") as f:
        f.write(report)
    print(f"{'excite_kuka':<22} {m:7.2f} s ({lo:.2f}..{hi:.2f})  log det F/r {score(binary, out):.3f}",
          flush=True)
    if not peer:
        return
    theirs = os.path.join(d, "kuka_peer.toml")
    peer_cmd = [sys.executable, os.path.join(ROOT, "scripts", "excite_peer.py"), out, design, theirs]
    pm, plo, phi, _ = median_of(peer_cmd, rounds)
    print(f"{'excite_kuka_scipy_peer':<22} {pm:7.2f} s ({plo:.2f}..{phi:.2f})  "
          f"log det F/r {score(binary, theirs):.3f}  (physid {pm / m:.1f}x faster)", flush=True)


def thread_counts(text):
    """An argparse type: comma-separated thread counts, each at least 1."""
    try:
        return [positive_int(t) for t in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text} is not a list of thread counts such as 1,2,4")


def main():
    args = arguments(
        __doc__,
        (["--rounds"], dict(type=positive_int, default=5, help="runs per row (default 5)")),
        (["--rows"], dict(type=names_from(ROWS), default=DEFAULT_ROWS,
                          help=f"comma-separated rows of {','.join(ROWS)} "
                               f"(default {','.join(DEFAULT_ROWS)})")),
        (["--threads"], dict(type=thread_counts, default=[1, 2, 4, 8, 16],
                             help="thread counts of the main job and blind rows "
                                  "(default 1,2,4,8,16)")),
        (["--quick"], dict(action="store_true", help="the main job with 3 seeds")),
        (["--blind-cases"], dict(type=positive_int, default=21,
                                 help="cases of the blind row (default 21)")),
        (["--no-peer"], dict(action="store_true", help="skip the SciPy excitation peer")))
    binary = physid_bin(args.physid)
    rounds, chosen, threads = args.rounds, args.rows, args.threads
    cores = os.cpu_count() or 1
    print(f"whole process, medians of {rounds} runs (min..max), {cores} cores")
    real = [os.path.join(ROOT, "data", "kuka_lwr4", f"measurements_{i}.csv") for i in (1, 2, 3)]
    with tempfile.TemporaryDirectory() as d:
        if "diagnose_kuka" in chosen:
            described = os.path.join(d, "kuka_identified.urdf")
            run(binary, "identify", "--robot", KUKA_URDF, "--data", real[0], real[1],
                "--friction", "viscous,coulomb,offset", "--out-urdf", described)
            m, lo, hi, _ = median_of([binary, "diagnose", "--robot", described, "--data", real[2],
                                   "--report", os.path.join(d, "diagnosis")], rounds)
            print(f"{'diagnose_kuka':<22} {m:7.2f} s ({lo:.2f}..{hi:.2f})", flush=True)
        if "excite_kuka" in chosen:
            excite_rows(binary, d, rounds, not args.no_peer)
        if "main_job" in chosen:
            scenario = main_job_scenario(d, args.quick)
            scaling_rows("main_job", [binary, "experiment", scenario], d, threads, rounds)
        if "blind" in chosen:
            blind = [binary, "blind", "--scenario", os.path.join(ROOT, "scenarios", "blind.toml"),
                     "--cases", str(args.blind_cases), "--seed", "1"]
            scaling_rows("blind", blind, d, threads, rounds)


def scaling_rows(name, cmd, d, threads, rounds):
    """`cmd --out DIR --threads T` for each T, timed, with its speed-up over one thread and the
    parallel efficiency (speed-up / min(T, cores)); threads beyond the cores are marked."""
    cores = os.cpu_count() or 1
    one = None
    for t in threads:
        out = os.path.join(d, f"{name}_{t}")
        m, lo, hi, _ = median_of([*cmd, "--out", out, "--threads", str(t)], rounds)
        one = m if t == 1 else one
        line = f"{f'{name}_{t}':<22} {m:7.2f} s ({lo:.2f}..{hi:.2f})"
        if one is not None:
            speedup = one / m
            line += f"  speed-up {speedup:4.2f}x, efficiency {speedup / min(t, cores):4.2f}"
        if t > cores:
            line += "  (oversubscribed)"
        print(line, flush=True)


if __name__ == "__main__":
    main()
