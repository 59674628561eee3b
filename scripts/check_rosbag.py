"""A ROS 2 bag written by an independent writer (rosbags, MCAP storage) identifies to the same
model as the same samples in a CSV.

The KUKA LWR4+ run 1 is written twice: as a CSV with columns named by joint, and as a rosbag2
directory whose sensor_msgs/JointState messages list the joints in a shuffled order, add a
gripper joint the URDF does not have, and carry absolute header stamps (2025, in nanoseconds;
a float64 of seconds would lose a microsecond there). `physid identify --stamp header` on the
bag must give the CSV's parameters to 1e-9 relative. A bag without one of the URDF's joints
must fail with an error naming that joint. Exits non-zero on disagreement.

usage: python scripts/check_rosbag.py [--physid PATH]
"""
import csv
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from physid_common import KUKA_URDF, Report, physid_bin

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RUN1 = os.path.join(ROOT, "data", "kuka_lwr4", "measurements_1.csv")
T0_NS = 1_760_000_000_123_456_789  # an absolute stamp in 2025
JOINTS = [f"lwr_{i}_joint" for i in range(7)]


def read_run(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    n = len(JOINTS)
    col = lambda name: np.array([[float(r[f"{name}{j + 1}"]) for j in range(n)] for r in rows])
    t = np.array([float(r["t"]) for r in rows])
    return t, col("q"), col("dq"), col("tau")


def write_csv(path, t_ns, q, dq, tau):
    """Named columns (q_<joint>, ...), times from the integer nanoseconds exactly as a reader
    that subtracts the first stamp in integers would compute them."""
    names = (["t"] + [f"q_{j}" for j in JOINTS] + [f"dq_{j}" for j in JOINTS] + [f"tau_{j}" for j in JOINTS])
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(names)
        for k in range(len(t_ns)):
            t = int(t_ns[k] - t_ns[0]) / 1e9
            w.writerow([repr(t)] + [repr(float(x)) for x in (*q[k], *dq[k], *tau[k])])


def write_bag(path, t_ns, q, dq, tau, joints, seed=3):
    store = get_typestore(Stores.ROS2_HUMBLE)
    JointState = store.types["sensor_msgs/msg/JointState"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    rng = np.random.default_rng(seed)
    with Writer(path, version=8, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection("/joint_states", JointState.__msgtype__, typestore=store)
        for k in range(len(t_ns)):
            names = [j for j in joints] + ["gripper_finger_joint"]
            order = rng.permutation(len(names))
            idx = {j: i for i, j in enumerate(JOINTS)}
            value = lambda arr, name: float(arr[k][idx[name]]) if name in idx else 0.0123
            stamp = int(t_ns[k])
            msg = JointState(
                header=Header(stamp=Time(sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id=""),
                name=[names[i] for i in order],
                position=np.array([value(q, names[i]) for i in order], dtype=np.float64),
                velocity=np.array([value(dq, names[i]) for i in order], dtype=np.float64),
                effort=np.array([value(tau, names[i]) for i in order], dtype=np.float64),
            )
            # The log time lags the stamp by a jittered transport delay: --stamp header must
            # ignore it.
            log_time = stamp + int(rng.integers(100_000, 900_000))
            w.write(conn, log_time, store.serialize_cdr(msg, JointState.__msgtype__))


def identify(binary, data, extra=()):
    out = subprocess.run(
        [binary, "identify", "--robot", KUKA_URDF, "--data", data, "--constraints", "consistent", "--json", *extra],
        capture_output=True, text=True)
    return out.returncode, out.stdout, out.stderr


def main():
    binary = physid_bin(sys.argv)
    report = Report("check_rosbag")
    t, q, dq, tau = read_run(RUN1)
    t_ns = T0_NS + np.round((t - t[0]) * 1e9).astype(np.int64)
    with tempfile.TemporaryDirectory() as d:
        csv_path, bag = os.path.join(d, "run1.csv"), os.path.join(d, "run1_bag")
        write_csv(csv_path, t_ns, q, dq, tau)
        write_bag(bag, t_ns, q, dq, tau, JOINTS)
        rc1, out1, err1 = identify(binary, csv_path)
        rc2, out2, err2 = identify(binary, bag, ["--stamp", "header"])
        if rc1 or rc2:
            print(err1, err2)
            report.add("identify ran on the CSV and on the bag", 1.0, 0.0)
        else:
            a, b = json.loads(out1), json.loads(out2)
            pa = np.array([x["pi"] for x in a["bodies"]]).ravel()
            pb = np.array([x["pi"] for x in b["bodies"]]).ravel()
            err = float(np.abs(pa - pb).max() / np.abs(pa).max())
            report.add(f"bag (shuffled, +gripper, absolute stamps) = CSV, {len(t)} samples", err, 1e-9)
            noted = "gripper_finger_joint" in err2
            report.add("the extra gripper joint is named in a note", 0.0 if noted else 1.0, 0.0)
        missing = os.path.join(d, "missing_bag")
        write_bag(missing, t_ns[:200], q[:200], dq[:200], tau[:200], [j for j in JOINTS if j != "lwr_3_joint"])
        rc, _, err = identify(binary, missing, ["--stamp", "header"])
        named = rc != 0 and "lwr_3_joint" in err
        print(f"     missing joint: exit {rc}, {err.strip().splitlines()[-1] if err.strip() else ''}")
        report.add("a bag without lwr_3_joint fails naming it", 0.0 if named else 1.0, 0.0)
    report.finish()


if __name__ == "__main__":
    main()
