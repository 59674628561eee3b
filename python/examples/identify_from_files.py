"""Identify a URDF robot from its logs (CSV here; an MCAP file or a rosbag2 folder is read the
same way, `topic=` naming its JointState topic), check the answer on a held-out run, and write
the identified URDF.

usage: python python/examples/identify_from_files.py [OUT_DIR]   (from the repository root)
"""
import sys

import physid

robot = physid.Robot("data/kuka_lwr4/kuka_lwr4.urdf")
fit = physid.identify(robot, "data/kuka_lwr4/measurements_1.csv",
                      validate_data="data/kuka_lwr4/measurements_2.csv",
                      constraints="consistent", friction="viscous,coulomb,offset")
print(fit)
print(fit.joints().round(3).to_string(index=False))
print(fit.bodies()[["name", "m", "min_eig_J"]].to_string(index=False))
fit.write_urdf(f"{sys.argv[1] if len(sys.argv) > 1 else '.'}/kuka_identified.urdf")
