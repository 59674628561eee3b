"""Peer for the identification benchmark: the paper's problem solved the way a Python user
would, timed on the same data in the same run as physid.

- data: 10,000 samples of the simulated shell experiment (physid simulate --csv);
- regressor: pinocchio's computeJointTorqueRegressor for the links (link-only URDF exported by
  physid), the rotor columns in numpy from the rotors' placements in physid's URDF export
  (mimic joints, gear ratio = multiplier), friction columns in numpy;
- normal equations in numpy, then CVXPY + Clarabel with the 'ellipsoid' constraints
  (scripts/check_cvxpy.py's formulation).

Prints both times and the ratio, and checks that both reach the same optimum (objective to
1e-6 relative): the same problem, solved twice. Exits non-zero if not.

With `--kuka`, the same on real data: the KUKA LWR4+ URDF and its logged runs 1 and 2
(10,054 samples of CSV, `identify`'s default `ellipsoid` set with each body's bound from its
URDF geometry), pinocchio's regressor plus viscous and Coulomb columns; the peer's time covers
reading the CSVs, the regressor, the normal equations and the solve (not Python's start-up and
imports), physid's the whole `identify` command.
"""
import functools
import json
import os
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from check_cvxpy import solve
from physid_common import PIN_FROM_PAPER, ROOT, arguments, physid_bin, positive_int, run


def rpy_matrix(r, p, y):
    return pin.rpy.rpyToMatrix(r, p, y)


def axis_rotation(axis, angle):
    return pin.AngleAxis(angle, np.asarray(axis)).toRotationMatrix()


def k_form(u_ang, u_lin, w_ang, w_lin):
    """Coefficients of u' I(pi) w in the paper's parameter order (angular-first motions)."""
    a, b = u_ang, w_ang
    hc = np.cross(w_lin, u_ang) + np.cross(u_lin, w_ang)
    return np.array([u_lin @ w_lin, *hc, a[0] * b[0], a[0] * b[1] + a[1] * b[0], a[0] * b[2] + a[2] * b[0],
                     a[1] * b[1], a[1] * b[2] + a[2] * b[1], a[2] * b[2]])


def cross_motion(v_ang, v_lin, s_ang, s_lin):
    return np.cross(v_ang, s_ang), np.cross(v_ang, s_lin) + np.cross(v_lin, s_ang)


def rotors_from_urdf(path):
    """(parent link, origin SE3, axis, gear ratio, driven joint) of each mimic joint."""
    out = []
    for j in ET.parse(path).getroot().iter("joint"):
        mimic = j.find("mimic")
        if mimic is None:
            continue
        o = j.find("origin")
        xyz = [float(x) for x in o.get("xyz", "0 0 0").split()]
        rpy = [float(x) for x in o.get("rpy", "0 0 0").split()]
        axis = np.array([float(x) for x in j.find("axis").get("xyz").split()])
        out.append((j.find("parent").get("link"), pin.SE3(rpy_matrix(*rpy), np.array(xyz)), axis,
                    float(mimic.get("multiplier", "1")), mimic.get("joint")))
    return out


def regressor_rows(model, data, rotors, link_of, q, v, a, n_rot_cols):
    """Full 3 x 66 regressor of one sample, paper order: links, rotors, viscous, Coulomb."""
    n = model.nv
    y_links = pin.computeJointTorqueRegressor(model, data, q, v, a)
    y = np.zeros((n, 10 * n + n_rot_cols + 2 * n))
    y[:, :10 * n] = y_links[:, paper_order(n)]
    pin.forwardKinematics(model, data, q, v, a)
    g = model.gravity.linear
    for r, (parent_link, placement, axis, gear, driven) in enumerate(rotors):
        k = model.getJointId(driven) - 1
        p = link_of[parent_link]  # pinocchio joint index of the parent body (0: universe)
        m_r = placement * pin.SE3(axis_rotation(axis, gear * q[k]), np.zeros(3))
        if p == 0:
            vp_ang, vp_lin = np.zeros(3), np.zeros(3)
            ap = pin.Motion(-g, np.zeros(3))
        else:
            vp = data.v[p]
            vp_ang, vp_lin = vp.angular, vp.linear
            ap = pin.Motion(data.a[p].linear - data.oMi[p].rotation.T @ g, data.a[p].angular)
        vr = m_r.actInv(pin.Motion(vp_lin, vp_ang))
        s_rot = gear * axis
        vr_ang, vr_lin = vr.angular + s_rot * v[k], vr.linear
        ar = m_r.actInv(ap)
        c_ang, c_lin = cross_motion(vr_ang, vr_lin, s_rot * v[k], np.zeros(3))
        ar_ang, ar_lin = ar.angular + s_rot * a[k] + c_ang, ar.linear + c_lin
        cols = slice(10 * n + 10 * r, 10 * n + 10 * r + 10)

        def block(s_ang, s_lin):
            x_ang, x_lin = cross_motion(vr_ang, vr_lin, s_ang, s_lin)
            return k_form(s_ang, s_lin, ar_ang, ar_lin) - k_form(x_ang, x_lin, vr_ang, vr_lin)

        y[k, cols] = block(s_rot, np.zeros(3))
        om_r = (data.oMi[p] if p > 0 else pin.SE3.Identity()) * m_r
        j = p
        while j > 0:
            s_j = data.oMi[j].act(pin.Motion(np.zeros(3), joint_axes[j - 1]))
            s_r = om_r.actInv(s_j)
            y[j - 1, cols] = block(s_r.angular, s_r.linear)
            j = model.parents[j]
    y[np.arange(n), 10 * n + n_rot_cols + np.arange(n)] = v
    y[np.arange(n), 10 * n + n_rot_cols + n + np.arange(n)] = np.sign(v)
    return y


joint_axes = []


def rebuilt_problem(problem, y, tau, samples):
    """physid's exported problem (constraint set, ellipsoids, prior weight w) with H, g, c
    rebuilt from the peer's own regressor and torques, physid's prior recovered from its
    exported g."""
    w = problem["w"]
    h_np = y.T @ y / samples + w * np.eye(y.shape[1])
    theta_prior = (np.array(problem["g"]) - y.T @ tau / samples) / w
    return dict(problem, H=h_np.tolist(), g=(y.T @ tau / samples + w * theta_prior).tolist(),
                c=float(tau @ tau / samples + w * theta_prior @ theta_prior))


def solve_like_physid(problem, y, tau, samples):
    """[`rebuilt_problem`] solved by CVXPY + Clarabel: (objective, status, solve time)."""
    problem_py = rebuilt_problem(problem, y, tau, samples)
    t1 = time.perf_counter()
    value, status = solve(problem_py, "CLARABEL")
    return value, status, time.perf_counter() - t1


@functools.lru_cache(maxsize=None)
def paper_order(n):
    """Columns of pinocchio's regressor of `n` bodies in the paper's parameter order."""
    return np.concatenate([10 * i + np.array(PIN_FROM_PAPER) for i in range(n)])


def arm_rows(model, data, q, v, a):
    """One sample's regressor of an arm without rotors, paper order: pinocchio's link columns,
    then viscous and Coulomb friction."""
    n = model.nv
    y = np.zeros((n, 12 * n))
    y[:, :10 * n] = pin.computeJointTorqueRegressor(model, data, q, v, a)[:, paper_order(n)]
    y[np.arange(n), 10 * n + np.arange(n)] = v
    y[np.arange(n), 11 * n + np.arange(n)] = np.sign(v)
    return y


def seconds_since_process_start():
    """Wall time since this Python process started (Linux /proc; interpreter start-up and
    imports included)."""
    with open("/proc/self/stat") as f:
        start_ticks = int(f.read().rsplit(")", 1)[1].split()[19])
    with open("/proc/uptime") as f:
        uptime = float(f.read().split()[0])
    return uptime - start_ticks / os.sysconf("SC_CLK_TCK")


def kuka(binary):
    """The comparison on the real KUKA logs (see the module docs)."""
    from physid_common import KUKA_URDF
    runs = [os.path.join(ROOT, "data", "kuka_lwr4", f"measurements_{i}.csv") for i in (1, 2)]
    with tempfile.TemporaryDirectory() as d:
        problem_path = os.path.join(d, "problem.json")
        base = ["identify", "--robot", KUKA_URDF, "--data", *runs, "--constraints", "ellipsoid", "--json"]
        t_before_physid = time.perf_counter()
        ours = json.loads(run(binary, *base, "--export-problem", problem_path))
        with open(problem_path) as f:
            problem = json.load(f)
        t0 = time.perf_counter()
        run(binary, *base)
        t_physid_cmd = time.perf_counter() - t0
        t_physid_runs = time.perf_counter() - t_before_physid

        t0 = time.perf_counter()
        model = pin.buildModelFromUrdf(KUKA_URDF)
        pdata = model.createData()
        n = model.nv
        ys, taus = [], []
        for path in runs:
            with open(path) as f:
                header = f.readline().strip().split(",")
            cols = lambda p: [header.index(f"{p}{j + 1}") for j in range(n)]
            data_np = np.loadtxt(path, delimiter=",", skiprows=1)
            for s in data_np:
                q, v, a, tau = s[cols("q")], s[cols("dq")], s[cols("ddq")], s[cols("tau")]
                ys.append(arm_rows(model, pdata, q, v, a))
                taus.append(tau)
        y, tau = np.vstack(ys), np.concatenate(taus)
        samples = len(taus)
        value, status, t_solve = solve_like_physid(problem, y, tau, samples)
        t_peer = time.perf_counter() - t0
        t_peer_process = seconds_since_process_start() - t_physid_runs
        ref = problem["physid"]["objective"]
        err = abs(value - ref) / max(1.0, abs(ref))
        print(f"KUKA LWR4+ real logs, runs 1 + 2 ({samples} samples), 'ellipsoid' from the URDF geometry:")
        print(f"  peer (CSV read, pinocchio regressor, numpy, CVXPY/Clarabel): {t_peer * 1e3:.0f} ms (solve {t_solve * 1e3:.0f} ms, {status})")
        print(f"  physid identify, whole command: {t_physid_cmd * 1e3:.0f} ms; in-library end to end {ours['end_to_end_seconds'] * 1e3:.1f} ms")
        print(f"  peer as a whole process (interpreter start-up and imports included): {t_peer_process * 1e3:.0f} ms")
        print(f"ratio peer / physid, whole processes: {t_peer_process / t_physid_cmd:.1f}x; peer's work alone / physid whole command: "
              f"{t_peer / t_physid_cmd:.1f}x; in-library: {t_peer / ours['end_to_end_seconds']:.0f}x")
        print(f"same optimum: physid {ref:.9f}, peer {value:.9f}, rel. diff {err:.1e}")
        ok = err < 1e-6
        print(f"peer_pinocchio_cvxpy: {1 if ok else 0} passed, {0 if ok else 1} failed")
        sys.exit(0 if ok else 1)


def main():
    args = arguments(
        __doc__,
        (["--samples"], dict(type=positive_int, default=10000,
                             help="samples of the shell experiment (default 10000)")),
        (["--kuka"], dict(action="store_true", help="the real KUKA runs 1 and 2 instead")))
    binary = physid_bin(args.physid)
    if args.kuka:
        return kuka(binary)
    samples = args.samples
    scenario = os.path.join(ROOT, "scenarios", "cheetah3_shell.toml")
    with tempfile.TemporaryDirectory() as d:
        csv_path, mcap = os.path.join(d, "shell.csv"), os.path.join(d, "shell.mcap")
        run(binary, "simulate", scenario, "--out", mcap, "--csv", csv_path, "--duration", str(samples / 1000 + 0.001))
        full_urdf, link_urdf = os.path.join(d, "leg.urdf"), os.path.join(d, "links.urdf")
        run(binary, "export", "--robot", "cheetah3", "--urdf", full_urdf)
        run(binary, "export", "--robot", "cheetah3", "--no-rotors", "--urdf", link_urdf)
        problem_path = os.path.join(d, "problem.json")
        out = run(binary, "identify", "--data", csv_path, "--robot", "cheetah3", "--constraints", "ellipsoid",
                  "--train", f"0:{samples}", "--export-problem", problem_path, "--json")
        ours = json.loads(out)
        with open(problem_path) as f:
            problem = json.load(f)
        # The physid time, end to end as a user sees it: the whole identify command.
        t0 = time.perf_counter()
        run(binary, "identify", "--data", csv_path, "--robot", "cheetah3", "--constraints", "ellipsoid", "--train", f"0:{samples}", "--json")
        t_physid_cmd = time.perf_counter() - t0

        data_np = np.loadtxt(csv_path, delimiter=",", skiprows=1)[:samples]
        model = pin.buildModelFromUrdf(link_urdf)
        pdata = model.createData()
        for jt in ET.parse(link_urdf).getroot().iter("joint"):
            joint_axes.append(np.array([float(x) for x in jt.find("axis").get("xyz").split()]))
        link_of = {"base": 0}
        for i, name in enumerate(model.names[1:], start=1):
            link_of[model.frames[model.getFrameId(name)].name] = i
        for fr in model.frames:
            if fr.name in [l.get("name") for l in ET.parse(link_urdf).getroot().iter("link")]:
                link_of[fr.name] = fr.parentJoint
        rotors = rotors_from_urdf(full_urdf)
        n = model.nv
        t0 = time.perf_counter()
        rows = []
        for s in data_np:
            q, v, a, tau = s[1:1 + n], s[1 + n:1 + 2 * n], s[1 + 2 * n:1 + 3 * n], s[1 + 3 * n:1 + 4 * n]
            rows.append((regressor_rows(model, pdata, rotors, link_of, q, v, a, 10 * len(rotors)), tau))
        t_reg = time.perf_counter() - t0
        y = np.vstack([r[0] for r in rows])
        tau = np.concatenate([r[1] for r in rows])
        # Same prior as physid (the model's parameters): recovered from the exported g.
        value, status, t_solve = solve_like_physid(problem, y, tau, samples)
        t_peer = time.perf_counter() - t0
        t_asm = t_peer - t_solve
        ref = problem["physid"]["objective"]
        err = abs(value - ref) / max(1.0, abs(ref))
        print(f"peer (pinocchio regressor + numpy rotors/friction + CVXPY/Clarabel), {samples} samples:")
        print(f"  regressor {t_reg * 1e3:.0f} ms, assembly total {t_asm * 1e3:.0f} ms, CVXPY solve {t_solve * 1e3:.0f} ms ({status}), end to end {t_peer * 1e3:.0f} ms")
        print(f"physid identify command (process start, CSV read, regressor, assembly, solve): {t_physid_cmd * 1e3:.0f} ms; in-library end to end {ours['end_to_end_seconds'] * 1e3:.1f} ms")
        print(f"ratio peer / physid: {t_peer / ours['end_to_end_seconds']:.0f}x (in-library), {t_peer / t_physid_cmd:.0f}x (whole command)")
        print(f"same optimum: physid {ref:.9f}, peer {value:.9f}, rel. diff {err:.1e}")
        ok = err < 1e-6
        print(f"peer_pinocchio_cvxpy: {1 if ok else 0} passed, {0 if ok else 1} failed")
        sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
