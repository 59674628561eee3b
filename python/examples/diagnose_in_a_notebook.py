"""Why does the model not match the robot? Diagnose a real KUKA run against its description.
In a notebook, the Diagnosis object itself shows the HTML report, plots inline; here it is
written to a folder.

usage: python python/examples/diagnose_in_a_notebook.py [OUT_DIR]   (from the repository root)
"""
import sys

import physid

robot = physid.Robot("data/kuka_lwr4/kuka_lwr4.urdf")
d = physid.diagnose(robot, "data/kuka_lwr4/measurements_3.csv")
print(d.verdict, "-", d.summary)
print(d.gap().round(3).to_string(index=False))   # validation RMS per joint, step by step
print(d.effects().round(3).to_string(index=False))   # every effect's magnitude per joint, with its SE
print("payload:", d.payload)                     # a physid.BodyChange (body, mass, com), or None
d.write_report(f"{sys.argv[1] if len(sys.argv) > 1 else '.'}/kuka_diagnosis")   # report.html, .md, .json, SVGs
# In Jupyter: `d` alone renders the report (Diagnosis._repr_html_).
