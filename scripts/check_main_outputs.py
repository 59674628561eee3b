"""Checks the outputs of the README's main command (scripts/run.sh) the way a reader would open
them: every file is there, the CSV and Parquet tables parse (pyarrow) and agree, the grid is the
one the provenance declares, the numbers are finite, the SVGs are well-formed XML, and the
physics of the result holds (the physically consistent sets give consistent models), and the
run reproduces the committed results/sample_size/ (`--committed`) wherever the data determine
the fits (see COMMITTED_TOLERANCE): committed results the code no longer produces fail it.
"""
import csv
import json
import math
import os
import xml.etree.ElementTree as ET

import pyarrow.parquet as pq

from physid_common import ROOT, Report, arguments

FILES = ["rows.parquet", "rows.csv", "summary.parquet", "summary.csv", "summary.md",
         "validation_error.svg", "parameter_error.svg", "provenance.json"]


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


# The summary's statistics a regeneration must reproduce, and how closely: 1 % covers the
# round-off of other BLAS kernels and summation orders (up to 7e-4 relative seen) where the data
# determine the fit; a change of the code that moves a cell by more leaves the committed results
# stale. Cells with fewer equations (n_s x joints) than parameters are not compared: there the
# prior and the solver's tolerance place the parameters the data leave free, and round-off alone
# moved a median by 1.7 %.
STATISTICS = [f"{v}_{q}" for v in ("val_rms", "val_truth_rms", "j_err")
              for q in ("q25", "median", "q75")]
COMMITTED_TOLERANCE = 0.01


def committed(report, summary, reference, joints, parameters):
    """The run's summary against the committed one: the same cells and, in each with at least
    as many equations as `parameters`, each statistic within COMMITTED_TOLERANCE (relative) and
    the same consistent fraction."""
    key = lambda r: (int(r["n_s"]), r["constraints"])
    ref = {key(r): r for r in reference}
    report.check(f"the same {len(summary)} (n_s, set) cells as the committed results",
                 sorted(ref) == sorted(key(r) for r in summary))
    worst, where = 0.0, "none"
    for r in summary:
        c = ref.get(key(r))
        if c is None or int(r["n_s"]) * joints < parameters:
            continue
        for col in STATISTICS:
            a, b = float(r[col]), float(c[col])
            err = abs(a - b) / max(abs(b), 1e-12)
            if not err <= worst:
                worst, where = err, f"n_s {r['n_s']} {r['constraints']} {col}: {a:.6g} vs {b:.6g}"
        if r["consistent_fraction"] != c["consistent_fraction"]:
            worst, where = math.inf, f"n_s {r['n_s']} {r['constraints']} consistent_fraction"
    smallest = min((n for n, _ in ref if n * joints >= parameters), default=None)
    report.check(f"every statistic from n_s = {smallest} on ({joints} joints, {parameters} "
                 f"parameters) within {COMMITTED_TOLERANCE:.0%} of the committed results "
                 f"(largest: {worst:.1e}, {where}; if the code changed them: "
                 "bash scripts/regenerate.sh sample_size)", worst <= COMMITTED_TOLERANCE)


def main():
    args = arguments(
        __doc__,
        (["result_dir"], dict(metavar="RESULT_DIR", help="the folder scripts/run.sh wrote")),
        (["--committed"], dict(metavar="DIR", default=os.path.join(ROOT, "results", "sample_size"),
                               help="the committed results the run must reproduce "
                                    "(default results/sample_size)")),
        binary=False)
    out = args.result_dir
    report = Report("main command outputs")
    missing = [f for f in FILES if not os.path.isfile(os.path.join(out, f))]
    report.check(f"all {len(FILES)} files written (missing: {', '.join(missing) or 'none'})",
                 not missing)
    if missing:
        report.finish()

    with open(os.path.join(out, "provenance.json")) as f:
        prov = json.load(f)
    exp = prov["experiment"]
    sets = exp["constraints"]
    cells = len(prov["seeds"]) * exp["points"] * len(sets)

    rows = read_csv(os.path.join(out, "rows.csv"))
    table = pq.read_table(os.path.join(out, "rows.parquet"))
    report.check(f"rows.csv has seeds x sizes x sets = {cells} rows ({len(rows)})", len(rows) == cells)
    report.check(f"rows.parquet has the same {table.num_rows} rows and columns as rows.csv",
                 table.num_rows == len(rows) and set(table.column_names) == set(rows[0]))
    val = table.column("val_rms").to_pylist()
    csv_val = [float(r["val_rms"]) for r in rows]
    report.add("val_rms equal in Parquet and CSV",
               max(abs(a - b) / max(1.0, abs(b)) for a, b in zip(val, csv_val)), 1e-12)
    report.check("every val_rms finite and positive", all(math.isfinite(v) and v > 0 for v in val))

    # The physically consistent sets must return consistent models in every cell.
    bad = [r for r in rows if r["constraints"] in ("consistent", "ellipsoid") and r["consistent"] != "true"]
    report.check(f"consistent/ellipsoid cells all physically consistent ({len(bad)} not)", not bad)

    summary = read_csv(os.path.join(out, "summary.csv"))
    sq = pq.read_table(os.path.join(out, "summary.parquet"))
    n_summary = exp["points"] * len(sets)
    report.check(f"summary has sizes x sets = {n_summary} rows (csv {len(summary)}, parquet {sq.num_rows})",
                 len(summary) == n_summary == sq.num_rows)
    # The paper's claim at the smallest size: the tightest set beats least squares.
    n_min = min(int(r["n_s"]) for r in summary)
    med = {r["constraints"]: float(r["val_rms_median"]) for r in summary if int(r["n_s"]) == n_min}
    report.check(f"at n_s = {n_min}, ellipsoid median {med['ellipsoid']:.3g} < none {med['none']:.3g} N m",
                 med["ellipsoid"] < med["none"])

    with open(os.path.join(out, "summary.md")) as f:
        md = f.read()
    report.check("summary.md has the validation table with every set as a column",
                 all(f"| {s} " in md for s in sets))
    if os.path.realpath(out) != os.path.realpath(args.committed):
        needed = [os.path.join(args.committed, f) for f in ("provenance.json", "summary.csv")]
        absent = [f for f in needed if not os.path.isfile(f)]
        report.check(f"the committed results to compare with are there (missing: "
                     f"{', '.join(absent) or 'none'})", not absent)
        if absent:
            report.finish()
        with open(needed[0]) as f:
            reference = json.load(f)
        if all(prov.get(k) == reference.get(k) for k in ("scenario", "experiment", "seeds")):
            # Joints and parameters from the rows' per-joint and per-body columns: ten inertial
            # parameters per body, viscous and Coulomb friction per joint.
            joints = sum(1 for c in rows[0] if c.startswith("val_rms_"))
            bodies = sum(1 for c in rows[0] if c.startswith("j_err_"))
            committed(report, summary, read_csv(os.path.join(args.committed, "summary.csv")),
                      joints, 10 * bodies + 2 * joints)
        else:
            print(f"note: {out} is not a run of the committed scenario and experiment "
                  f"({args.committed}): not compared with it")
    for svg in ("validation_error.svg", "parameter_error.svg"):
        root = ET.parse(os.path.join(out, svg)).getroot()
        report.check(f"{svg} is an SVG document with drawn elements",
                     root.tag.endswith("svg") and len(list(root.iter())) > 50)
    report.finish()


if __name__ == "__main__":
    main()
