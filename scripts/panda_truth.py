"""Ground truth for the Franka Panda (data/panda), made with pinocchio, and logs written as a
robot writes them: ROS 2 bags (rosbags, MCAP or SQLite storage) and CSV files without
accelerations, joints shuffled, extra joints, dropped samples and gaps.

The truth is not the description: each link is a uniform solid of the convex hull of its
collision geometry (mesh vertices, box corners), its mass the description's scaled by a random
factor in [0.8, 1.25]; joint friction is viscous + Coulomb (`sign(q̇)`), and the logged torque
carries white noise. Nothing here uses physid.
"""
import csv
import os
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
from scipy.spatial import ConvexHull

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PKG = os.path.join(ROOT, "data", "panda")
URDF = os.path.join(PKG, "example-robot-data", "robots", "panda_description", "urdf", "panda.urdf")
ARM = [f"panda_joint{i}" for i in range(1, 8)]
FINGERS = ["panda_finger_joint1", "panda_finger_joint2"]
# Friction per arm joint: viscous (N m s/rad) and Coulomb (N m).
VISCOUS = np.array([0.35, 0.40, 0.30, 0.35, 0.15, 0.18, 0.12])
COULOMB = np.array([0.45, 0.50, 0.35, 0.40, 0.20, 0.18, 0.15])
FINGER_OPEN = 0.035  # m, each finger


def rpy_matrix(rpy):
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])


def stl_vertices(path):
    """Vertices of a binary or ASCII STL file (m)."""
    data = open(path, "rb").read()
    if data[:5] == b"solid" and b"facet" in data[:400]:
        pts = [list(map(float, line.split()[1:4])) for line in data.decode().splitlines() if line.strip().startswith("vertex")]
        return np.array(pts)
    n = int.from_bytes(data[80:84], "little")
    tri = np.frombuffer(data[84:84 + 50 * n], dtype=np.dtype([("n", "<3f4"), ("v", "<9f4"), ("a", "<u2")]))
    return tri["v"].reshape(-1, 3).astype(float)


def link_points(link):
    """Points of a link's collision geometry in its frame."""
    pts = []
    for c in link.findall("collision"):
        o = c.find("origin")
        xyz = np.array(list(map(float, o.get("xyz", "0 0 0").split()))) if o is not None else np.zeros(3)
        rpy = np.array(list(map(float, o.get("rpy", "0 0 0").split()))) if o is not None else np.zeros(3)
        g = c.find("geometry")[0]
        if g.tag == "mesh":
            rel = g.get("filename").split("package://")[1]
            v = stl_vertices(os.path.join(PKG, rel))
        elif g.tag == "box":
            s = np.array(list(map(float, g.get("size").split()))) / 2
            v = np.array([[a * s[0], b * s[1], c_ * s[2]] for a in (-1, 1) for b in (-1, 1) for c_ in (-1, 1)])
        else:
            continue
        pts.append(v @ rpy_matrix(rpy).T + xyz)
    return np.vstack(pts) if pts else None


def hull_inertia(points):
    """Volume, centroid and inertia about the centroid of the uniform unit-density solid
    bounded by the convex hull of `points` (tetrahedra from an interior point)."""
    hull = ConvexHull(points)
    o = points[hull.vertices].mean(axis=0)
    vol, first, second = 0.0, np.zeros(3), np.zeros((3, 3))
    for s in hull.simplices:
        a, b, c = points[s] - o
        v = abs(np.dot(a, np.cross(b, c))) / 6.0
        vol += v
        first += v * (a + b + c) / 4.0
        # Second moment of a tetrahedron with a vertex at the origin: v/20 (Σ x xᵀ + s sᵀ).
        ssum = a + b + c
        second += v / 20.0 * (np.outer(a, a) + np.outer(b, b) + np.outer(c, c) + np.outer(ssum, ssum))
    com = first / vol
    cov = second / vol - np.outer(com, com)  # per unit mass about the centroid
    inertia = np.trace(cov) * np.eye(3) - cov
    return vol, com + o, inertia


def truth_urdf(seed, out_path):
    """The Panda URDF with every link's inertial replaced by its hull solid's (mass scaled);
    returns the masses."""
    rng = np.random.default_rng(seed)
    tree = ET.parse(URDF)
    masses = {}
    for link in tree.getroot().findall("link"):
        inertial = link.find("inertial")
        pts = link_points(link)
        if inertial is None or pts is None:
            continue
        m0 = float(inertial.find("mass").get("value"))
        mass = m0 * rng.uniform(0.8, 1.25)
        _, com, inertia = hull_inertia(pts)
        inertia = inertia * mass
        inertial.find("origin").set("xyz", " ".join(repr(float(x)) for x in com))
        inertial.find("origin").set("rpy", "0 0 0")
        inertial.find("mass").set("value", repr(mass))
        el = inertial.find("inertia")
        for k, (i, j) in {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2), "izz": (2, 2)}.items():
            el.set(k, repr(float(inertia[i, j])))
        masses[link.get("name")] = mass
    tree.write(out_path)
    return masses


class Motion:
    """A smooth excitation of the arm: per joint a constant plus four harmonics of 0.1 Hz,
    within the joint limits, speeds below 1.7 rad/s."""

    def __init__(self, model, seed):
        rng = np.random.default_rng(seed + 100)
        self.w = 2 * np.pi * 0.1
        self.ids = [model.getJointId(j) for j in ARM]
        lo = np.array([model.lowerPositionLimit[model.joints[i].idx_q] for i in self.ids])
        hi = np.array([model.upperPositionLimit[model.joints[i].idx_q] for i in self.ids])
        self.center = (lo + hi) / 2
        span = np.minimum((hi - lo) / 2 * 0.6, 1.2)
        a = rng.normal(size=(7, 4)) / np.arange(1, 5)
        b = rng.normal(size=(7, 4)) / np.arange(1, 5)
        peak = np.abs(a).sum(axis=1) + np.abs(b).sum(axis=1)
        scale = (span / peak)[:, None]
        speed = (np.abs(a) + np.abs(b)) @ (self.w * np.arange(1, 5))
        scale = np.minimum(scale, (1.7 / speed)[:, None])
        self.a, self.b = a * scale, b * scale

    def at(self, t):
        """q, q̇, q̈ of the arm (7 each) at times t."""
        t = np.atleast_1d(t)[:, None, None]
        l = np.arange(1, 5)
        ph = l * self.w * t
        q = self.center + (self.a * np.sin(ph) + self.b * np.cos(ph)).sum(-1)
        qd = (l * self.w * (self.a * np.cos(ph) - self.b * np.sin(ph))).sum(-1)
        qdd = (-(l * self.w) ** 2 * (self.a * np.sin(ph) + self.b * np.cos(ph))).sum(-1)
        return q, qd, qdd


def full_state(model, q_arm, qd_arm, qdd_arm):
    """The model's q, v, a with the fingers held open."""
    q = pin.neutral(model)
    v, a = np.zeros(model.nv), np.zeros(model.nv)
    for k, name in enumerate(ARM):
        j = model.joints[model.getJointId(name)]
        q[j.idx_q], v[j.idx_v], a[j.idx_v] = q_arm[k], qd_arm[k], qdd_arm[k]
    for name in FINGERS:
        q[model.joints[model.getJointId(name)].idx_q] = FINGER_OPEN
    return q, v, a


def arm_torques(model, data, q, qd, qdd, viscous=VISCOUS, coulomb=COULOMB):
    """Arm joint torques (m × 7): pinocchio's RNEA plus friction."""
    out = np.zeros_like(q)
    idx = [model.joints[model.getJointId(j)].idx_v for j in ARM]
    for k in range(len(q)):
        qf, vf, af = full_state(model, q[k], qd[k], qdd[k])
        tau = pin.rnea(model, data, qf, vf, af)
        out[k] = tau[idx] + viscous * qd[k] + coulomb * np.sign(qd[k])
    return out


def experiment(seed, duration=40.0, rate=1000.0, noise=0.08, gap=(14.0, 14.5), drop=0.02, workdir="."):
    """Simulated logs of one experiment: truth URDF, times kept, true states and logged torques.
    `gap` (s, s) is removed whole; `drop` is the fraction of other samples dropped at random."""
    truth = os.path.join(workdir, "panda_truth.urdf")
    masses = truth_urdf(seed, truth)
    model = pin.buildModelFromUrdf(truth)
    data = model.createData()
    rng = np.random.default_rng(seed + 200)
    t = np.arange(int(duration * rate)) / rate
    keep = np.ones(len(t), bool)
    if gap is not None:
        keep &= ~((t >= gap[0]) & (t < gap[1]))
    keep &= rng.uniform(size=len(t)) >= drop
    t = t[keep]
    motion = Motion(model, seed)
    q, qd, qdd = motion.at(t)
    tau_true = arm_torques(model, data, q, qd, qdd)
    tau = tau_true + rng.normal(scale=noise, size=tau_true.shape)
    return dict(t=t, q=q, qd=qd, qdd=qdd, tau=tau, tau_true=tau_true, truth_urdf=truth, masses=masses)


def logged(exp, seed, q_noise=1e-5, qd_noise=2e-3):
    """What the robot logs: q and q̇ with small sensor noise (no q̈)."""
    rng = np.random.default_rng(seed + 300)
    return (exp["q"] + rng.normal(scale=q_noise, size=exp["q"].shape),
            exp["qd"] + rng.normal(scale=qd_noise, size=exp["qd"].shape))


# Joints as the bag lists them: shuffled, the fingers, and a joint the robot does not have.
BAG_ORDER = ["panda_joint4", "panda_finger_joint2", "panda_joint1", "panda_joint7", "camera_pan",
             "panda_joint2", "panda_joint6", "panda_finger_joint1", "panda_joint3", "panda_joint5"]


def bag_rows(exp, q, qd):
    """Per sample: names, positions, velocities, efforts in BAG_ORDER (fingers still and their
    effort zero, as franka_gripper publishes)."""
    for k in range(len(exp["t"])):
        pos, vel, eff = [], [], []
        for name in BAG_ORDER:
            if name in ARM:
                j = ARM.index(name)
                pos.append(q[k, j]); vel.append(qd[k, j]); eff.append(exp["tau"][k, j])
            elif name in FINGERS:
                pos.append(FINGER_OPEN); vel.append(0.0); eff.append(0.0)
            else:
                pos.append(0.3); vel.append(0.0); eff.append(0.0)
        yield pos, vel, eff


def write_bag(path, exp, q, qd, storage="mcap", t0_ns=1_760_000_000_000_000_000):
    """A rosbag2 directory with sensor_msgs/JointState on /joint_states, header stamps at the
    sampling times, log times 0.1-0.5 ms later."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    store = get_typestore(Stores.ROS2_HUMBLE)
    JointState = store.types["sensor_msgs/msg/JointState"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    rng = np.random.default_rng(7)
    with Writer(path, version=8, storage_plugin=plugin) as w:
        conn = w.add_connection("/joint_states", JointState.__msgtype__, typestore=store)
        for k, (pos, vel, eff) in enumerate(bag_rows(exp, q, qd)):
            stamp = t0_ns + int(round(exp["t"][k] * 1e9))
            msg = JointState(
                header=Header(stamp=Time(sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id=""),
                name=list(BAG_ORDER),
                position=np.array(pos), velocity=np.array(vel), effort=np.array(eff))
            log = stamp + int(rng.integers(100_000, 500_000))
            w.write(conn, log, store.serialize_cdr(msg, JointState.__msgtype__))


def write_csv(path, exp, q, qd):
    """Columns named by joint in bag order, no accelerations."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t"] + [f"{g}_{n}" for g in ("q", "dq", "tau") for n in BAG_ORDER])
        for k, (pos, vel, eff) in enumerate(bag_rows(exp, q, qd)):
            w.writerow([repr(float(exp["t"][k]))] + [repr(float(x)) for x in (*pos, *vel, *eff)])
