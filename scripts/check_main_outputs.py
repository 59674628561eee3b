"""Checks the outputs of the README's main command (scripts/run.sh) the way a reader would open
them: every file is there, the CSV and Parquet tables parse (pyarrow) and agree, the grid is the
one the provenance declares, the numbers are finite, the SVGs are well-formed XML, and the
physics of the result holds (the physically consistent sets give consistent models).
"""
import csv
import json
import math
import os
import xml.etree.ElementTree as ET

import pyarrow.parquet as pq

from physid_common import Report, arguments

FILES = ["rows.parquet", "rows.csv", "summary.parquet", "summary.csv", "summary.md",
         "validation_error.svg", "parameter_error.svg", "provenance.json"]


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main():
    out = arguments(__doc__, (["result_dir"], dict(
        metavar="RESULT_DIR", help="the folder scripts/run.sh wrote")), binary=False).result_dir
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
    for svg in ("validation_error.svg", "parameter_error.svg"):
        root = ET.parse(os.path.join(out, svg)).getroot()
        report.check(f"{svg} is an SVG document with drawn elements",
                     root.tag.endswith("svg") and len(list(root.iter())) > 50)
    report.finish()


if __name__ == "__main__":
    main()
