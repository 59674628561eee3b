"""A ROS 2 bag written by an independent writer (rosbags, MCAP storage) identifies to the same
model as the same samples in a CSV.

The KUKA LWR4+ run 1 is written twice: as a CSV with columns named by joint, and as a rosbag2
directory whose sensor_msgs/JointState messages list the joints in a shuffled order, add a
gripper joint the URDF does not have, and carry absolute header stamps (2025, in nanoseconds;
a float64 of seconds would lose a microsecond there). `physid identify --stamp header` on the
bag must give the CSV's parameters to 1e-9 relative. A bag without one of the URDF's joints
must fail with an error naming that joint.

A floating robot's log likewise: a trotting quadruped's CSV from `physid simulate-floating`
written as rosbag2 directories (MCAP and SQLite storage) with sensor_msgs/JointState,
nav_msgs/Odometry (pose in the world, twist in the trunk frame) and physid_msgs/FootForces,
absolute header stamps and jittered log times; `physid identify-floating --stamp header` must
give the CSV's parameters to 1e-9 relative, and with the odometry at half the rate, starting
later, the left-out samples must be noted and the identified mass stay within 1 % of the CSV's.
Exits non-zero on disagreement.
"""
import csv
import json
import os
import subprocess
import tempfile

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from physid_common import KUKA_URDF, Report, arguments, physid_bin

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


FOOT_FORCES = """# the ground's force on each foot (N, world: x, y, z of each foot in turn), contact states
std_msgs/Header header
string[] name
float64[] force
bool[] contact
"""


def read_floating_csv(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    header = list(rows[0].keys())
    cols = lambda prefix: [h for h in header if h.startswith(prefix)]
    arr = lambda names: np.array([[float(r[n]) for n in names] for r in rows])
    joints = [h[2:] for h in cols("q_")]
    feet = [h[len("contact_"):] for h in cols("contact_")]
    force_cols = [f"force_{f}_{c}" for f in feet for c in "xyz"]
    return {
        "t": arr(["t"])[:, 0], "joints": joints, "feet": feet,
        "q": arr([f"q_{j}" for j in joints]), "tau": arr([f"tau_{j}" for j in joints]),
        "dq": arr([f"dq_{j}" for j in joints]) if cols("dq_") else None,
        "base": arr(["base_x", "base_y", "base_z", "base_qw", "base_qx", "base_qy", "base_qz",
                     "base_wx", "base_wy", "base_wz", "base_vx", "base_vy", "base_vz"]),
        "force": arr(force_cols), "contact": arr([f"contact_{f}" for f in feet]) > 0.5,
        "accel": arr(["base_ax", "base_ay", "base_az"]) if "base_ax" in header else None,
    }


def write_floating_bag(path, log, storage, odometry_every=1, odometry_from=0, seed=5):
    """The log as a rosbag2 directory: absolute header stamps, log times a jittered delay
    later; the odometry every `odometry_every`-th sample from `odometry_from`."""
    from rosbags.typesys import get_types_from_msg
    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg(FOOT_FORCES, "physid_msgs/msg/FootForces"))
    T = store.types
    rng = np.random.default_rng(seed)
    plugin = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}[storage]
    t_ns = T0_NS + np.round((log["t"] - log["t"][0]) * 1e9).astype(np.int64)
    with Writer(path, version=8, storage_plugin=plugin) as w:
        topics = [("js", "/joint_states", "sensor_msgs/msg/JointState"),
                  ("odom", "/odometry", "nav_msgs/msg/Odometry"),
                  ("feet", "/foot_forces", "physid_msgs/msg/FootForces")]
        if log["accel"] is not None:
            topics.append(("imu", "/imu", "sensor_msgs/msg/Imu"))
        conns = {name: w.add_connection(topic, kind, typestore=store) for name, topic, kind in topics}
        for k in range(len(t_ns)):
            stamp = int(t_ns[k])
            header = lambda frame: T["std_msgs/msg/Header"](
                stamp=T["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id=frame)
            msgs = [("js", T["sensor_msgs/msg/JointState"](
                header=header(""), name=log["joints"], position=log["q"][k].copy(),
                velocity=log["dq"][k].copy() if log["dq"] is not None else np.zeros(0), effort=log["tau"][k].copy()))]
            if k >= odometry_from and (k - odometry_from) % odometry_every == 0:
                b = log["base"][k]
                v3 = lambda x: T["geometry_msgs/msg/Vector3"](x=x[0], y=x[1], z=x[2])
                pose = T["geometry_msgs/msg/Pose"](
                    position=T["geometry_msgs/msg/Point"](x=b[0], y=b[1], z=b[2]),
                    orientation=T["geometry_msgs/msg/Quaternion"](x=b[4], y=b[5], z=b[6], w=b[3]))
                twist = T["geometry_msgs/msg/Twist"](linear=v3(b[10:13]), angular=v3(b[7:10]))
                msgs.append(("odom", T["nav_msgs/msg/Odometry"](
                    header=header("odom"), child_frame_id="trunk",
                    pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
                    twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)))))
            if log["accel"] is not None and k % 2 == 1:
                # The IMU at half the rate, from the second sample: interpolated in between.
                b, a = log["base"][k], log["accel"][k]
                v3 = lambda x: T["geometry_msgs/msg/Vector3"](x=x[0], y=x[1], z=x[2])
                msgs.append(("imu", T["sensor_msgs/msg/Imu"](
                    header=header("trunk"),
                    orientation=T["geometry_msgs/msg/Quaternion"](x=b[4], y=b[5], z=b[6], w=b[3]),
                    orientation_covariance=np.zeros(9), angular_velocity=v3(b[7:10]),
                    angular_velocity_covariance=np.zeros(9), linear_acceleration=v3(a),
                    linear_acceleration_covariance=np.zeros(9))))
            # The feet listed in reverse: matched by name.
            rev = list(range(len(log["feet"])))[::-1]
            msgs.append(("feet", T["physid_msgs/msg/FootForces"](
                header=header("world"), name=[log["feet"][i] for i in rev],
                force=np.concatenate([log["force"][k][3 * i:3 * i + 3] for i in rev]),
                contact=np.array([log["contact"][k][i] for i in rev], dtype=bool))))
            for name, msg in msgs:
                log_time = stamp + int(rng.integers(100_000, 900_000))
                w.write(conns[name], log_time, store.serialize_cdr(msg, msg.__msgtype__))


def identify_floating(binary, data, extra=()):
    out = subprocess.run([binary, "identify-floating", "--data", data, "--json", *extra],
                         capture_output=True, text=True)
    return out.returncode, out.stdout, out.stderr


def fit_apart(want, got):
    """How far two identifications of the same samples lie apart in what their data determine:
    the fit's RMS (relative) and each base parameter (in units of its standard error). Not the
    parameters themselves: those the data leave undetermined are placed by the constraints, to
    the solver's accuracy, along a path rounding steers (a CSV's and its bag's fits part by 1e-6
    there under OpenBLAS's SkylakeX kernels while their RMS agree to 1e-11)."""
    rms = abs(got["identified_rms"] - want["identified_rms"]) / want["identified_rms"]
    base = [[b["value"] for b in r["identifiability"]["base"]] for r in (want, got)]
    if len(base[0]) != len(base[1]):
        return rms, float("inf")
    se = np.array([b["standard_error"] for b in want["identifiability"]["base"]])
    return rms, float(np.max(np.abs(np.array(base[1]) - np.array(base[0])) / se))


def check_floating(binary, report, d):
    csv_path = os.path.join(d, "trot.csv")
    subprocess.run([binary, "simulate-floating", "--out", csv_path, "--duration", "3", "--seed", "5",
                    "--trot", "0.15,2.5"], check=True, capture_output=True)
    log = read_floating_csv(csv_path)
    rc, out, err = identify_floating(binary, csv_path)
    if rc:
        print(err)
        report.add("identify-floating ran on the CSV", 1.0, 0.0)
        return
    want = json.loads(out)
    for storage in ["mcap", "sqlite3"]:
        bag = os.path.join(d, f"trot_{storage}")
        write_floating_bag(bag, log, storage)
        rc, out, err = identify_floating(binary, bag, ["--stamp", "header"])
        if rc:
            print(err)
            report.add(f"identify-floating ran on the {storage} bag", 1.0, 0.0)
            continue
        rms, base = fit_apart(want, json.loads(out))
        same = f"floating bag ({storage}: JointState, Odometry, FootForces) = CSV, {len(log['t'])} samples"
        report.add(f"{same}: the fit's RMS", rms, 1e-9)
        report.add(f"{same}: base parameters, in standard errors", base, 1e-4)
    bag = os.path.join(d, "trot_half_rate")
    write_floating_bag(bag, log, "mcap", odometry_every=2, odometry_from=7)
    rc, out, err = identify_floating(binary, bag, ["--stamp", "header"])
    if rc:
        print(err)
        report.add("identify-floating ran on the half-rate odometry", 1.0, 0.0)
        return
    got = json.loads(out)
    report.check("half-rate odometry: the 7 samples before it noted as left out",
                  "7 joint samples before" in err)
    report.add("half-rate odometry: identified mass against the CSV's (relative)",
               abs(got["identified_mass"] / want["identified_mass"] - 1.0), 1e-2)
    check_floating_imu(binary, report, d)


def check_floating_imu(binary, report, d):
    """A standing log with the IMU's accelerometer, its bag carrying sensor_msgs/Imu at half
    the joint states' rate from the second sample: the accelerometer interpolated to the joint
    samples identifies (joint torques alone, where the trunk's acceleration carries the rows)
    within 1 % of the CSV's mass, and the samples outside the IMU's span are noted."""
    csv_path = os.path.join(d, "standing_imu.csv")
    subprocess.run([binary, "simulate-floating", "--out", csv_path, "--duration", "4", "--seed", "3",
                    "--sensors", "accelerometer=true"], check=True, capture_output=True)
    log = read_floating_csv(csv_path)
    extra = ["--setting", "torques-only", "--constraints", "none"]
    rc, out, err = identify_floating(binary, csv_path, extra)
    bag = os.path.join(d, "standing_imu_bag")
    write_floating_bag(bag, log, "mcap")
    rc2, out2, err2 = identify_floating(binary, bag, ["--stamp", "header", *extra])
    if rc or rc2:
        print(err, err2)
        report.add("identify-floating ran on the CSV and the bag with an IMU", 1.0, 0.0)
        return
    want, got = json.loads(out), json.loads(out2)
    report.check("bag with sensor_msgs/Imu at half rate: the first joint sample, before the IMU's first "
                 "message, noted as left out", "1 joint samples before" in err2 and "/imu" in err2)
    report.add("bag with sensor_msgs/Imu at half rate: identified mass (torques alone) against the CSV's",
               abs(got["identified_mass"] / want["identified_mass"] - 1.0), 1e-2)
    report.add("bag with sensor_msgs/Imu: the accelerometer read (mass against the truth's 45 kg)",
               abs(got["identified_mass"] / 45.0 - 1.0), 1e-2)


def main():
    binary = physid_bin(arguments(__doc__).physid)
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
        check_floating(binary, report, d)
    report.finish()


if __name__ == "__main__":
    main()
