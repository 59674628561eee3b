"""The excitation design's peer: a Fourier excitation of the same objective optimized with SciPy
over pinocchio's regressor, as a Python user would write it (FIGAROH designs this way too).

Takes a scenario written by `physid excite` (its Fourier form, harmonics, fundamental, offsets
and the limits kept, given as the design's JSON) and designs anew, independently of physid:

- the regressor `Y(q, q̇, q̈)` is pinocchio's joint-torque regressor of the URDF, then a
  viscous (q̇) and a Coulomb (sign q̇) column per joint;
- the identifiable basis from `40 p` random states inside the limits: columns scaled to unit
  norm (`D`; a column zero up to round-off gets no weight), eigenvectors `V` of `D YᵀY D` above `1e-9` of the largest;
- the objective `log det F / r`, `F = Vᵀ D (Σ_k Y_kᵀ Y_k / K) D V` over `K = 200` samples of one
  period (the periodic motion, as physid's design evaluates it);
- SLSQP (finite-difference gradients) under the position, speed, acceleration and jerk limits,
  linear in the coefficients at 100 points of a period, from one random start scaled into them;
  the optimum then scaled per joint into the limits on 4,000 points of a period.

Writes the scenario with its coefficients in place of physid's, for `physid excite --score`
to evaluate both motions the same way.
"""
import json
import os
import re
import time

import numpy as np
import pinocchio as pin
import scipy.optimize as so

from physid_common import arguments, positive_int

POINTS = 100  # limit points per period in the optimization
EPS = 1e-3  # finite-difference step (rad/s² of each coefficient)


def scenario_fourier(text):
    """(urdf path, harmonics, f0, offsets) of a scenario written by `physid excite`."""
    urdf = re.search(r'(?m)^urdf\s*=\s*"(.*)"', text).group(1)
    harmonics = int(re.search(r"(?m)^harmonics\s*=\s*(\d+)", text).group(1))
    f0 = float(re.search(r"(?m)^base_frequency\s*=\s*([0-9.eE+-]+)", text).group(1))
    offset = json.loads(re.search(r"(?m)^offset\s*=\s*(\[.*\])", text).group(1))
    return urdf, harmonics, f0, np.array(offset)


class Fourier:
    """q_j(t) = o_j + Σ_l a_jl sin(ω_l t) + b_jl (cos(ω_l t) − 1), and its derivatives on `t`;
    the coefficients as x = [a (joints × harmonics), b (joints × harmonics)], row-major."""

    def __init__(self, f0, harmonics, offset, t):
        self.n, self.L, self.o = len(offset), harmonics, offset
        w = 2 * np.pi * f0 * np.arange(1, harmonics + 1)
        s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
        # Per derivative order, the (samples × harmonics) maps of a and of b.
        self.maps = [(s, c - 1), (c * w, -s * w), (-s * w**2, -c * w**2), (-c * w**3, s * w**3)]

    def derivatives(self, x):
        """[q, q̇, q̈, q⃛], each (samples × joints)."""
        a, b = x[: self.n * self.L].reshape(self.n, self.L), x[self.n * self.L:].reshape(self.n, self.L)
        out = [ma @ a.T + mb @ b.T for ma, mb in self.maps]
        out[0] = out[0] + self.o
        return out

    def limit_rows(self, ranges, bounds):
        """G with `1 − G x ≥ 0` ⇔ every sample within its limits: `±(q − o)/range_±` and
        `±rate/bound` per joint and sample (the limits are linear in the coefficients)."""
        rows = []
        for k, (ma, mb) in enumerate(self.maps):
            for j in range(self.n):
                block = np.zeros((len(ma), 2 * self.n * self.L))
                block[:, j * self.L:(j + 1) * self.L] = ma
                block[:, (self.n + j) * self.L:(self.n + j + 1) * self.L] = mb
                up, down = (ranges[0][j], ranges[1][j]) if k == 0 else (bounds[k - 1][j],) * 2
                rows += [block / up, -block / down]
        return np.vstack(rows)


def regressor(model, data, q, qd, qdd):
    y = pin.computeJointTorqueRegressor(model, data, q, qd, qdd)
    return np.hstack([y, np.diag(qd), np.diag(np.sign(qd))])


def stacked(model, data, q, qd, qdd):
    return np.vstack([regressor(model, data, q[k], qd[k], qdd[k]) for k in range(len(q))])


def basis(model, data, limits, rng):
    lo, hi = np.array(limits["lower"]), np.array(limits["upper"])
    v, a = np.array(limits["velocity"]), np.array(limits["acceleration"])
    p = regressor(model, data, lo * 0, lo * 0, lo * 0).shape[1]
    k = 40 * p
    q = rng.uniform(lo, hi, (k, len(lo)))
    ys = stacked(model, data, q, rng.uniform(-v, v, q.shape), rng.uniform(-a, a, q.shape))
    norms = np.linalg.norm(ys, axis=0)
    # A column no state excites (zero up to round-off) gets no weight, as in physid's basis.
    d = np.where(norms > 1e-9 * norms.max(), 1 / np.maximum(norms, 1e-300), 0.0)
    lam, vec = np.linalg.eigh((ys * d).T @ (ys * d))
    return d, vec[:, lam > 1e-9 * lam.max()]


def into_limits(fourier, x, ranges, bounds, harmonics):
    """x with each joint's coefficients scaled by the largest factor (at most 1) that keeps it
    within every limit on `fourier`'s points."""
    q, *rates = fourier.derivatives(x)
    dev = q - fourier.o
    ratios = [np.maximum(dev.max(0) / ranges[0], -dev.min(0) / ranges[1])]
    ratios += [np.abs(r).max(0) / b for b, r in zip(bounds, rates)]
    scale = 1 / np.maximum(np.max(ratios, 0), 1.0)
    return x * np.tile(np.repeat(scale, harmonics), 2)


def main():
    args = arguments(
        __doc__,
        (["scenario"], dict(metavar="SCENARIO.toml", help="the scenario physid excite wrote")),
        (["design_json"], dict(metavar="DESIGN.json",
                               help="`physid excite --json` of the run that wrote it (its limits)")),
        (["out"], dict(metavar="OUT.toml", help="where the peer's scenario is written")),
        (["--seed"], dict(type=int, default=1, help="the random start's seed (default 1)")),
        (["--maxiter"], dict(type=positive_int, default=300, help="SLSQP iterations (default 300)")), binary=False)
    seed, maxiter = args.seed, args.maxiter
    scenario, design_json, out = args.scenario, args.design_json, args.out
    t0 = time.perf_counter()
    with open(scenario) as f:
        text = f.read()
    with open(design_json) as f:
        limits = json.load(f)["design"]["limits"]
    urdf, harmonics, f0, offset = scenario_fourier(text)
    urdf = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(scenario)), urdf))
    model = pin.buildModelFromUrdf(urdf)
    data = model.createData()
    rng = np.random.default_rng(seed)
    d, v = basis(model, data, limits, rng)
    n, period = len(offset), 1 / f0
    info = Fourier(f0, harmonics, offset, np.arange(200) * period / 200)
    grid = Fourier(f0, harmonics, offset, np.arange(POINTS) * period / POINTS)
    fine = Fourier(f0, harmonics, offset, np.arange(4000) * period / 4000)
    ranges = (np.array(limits["upper"]) - offset, offset - np.array(limits["lower"]))
    bounds = [np.array(limits[k]) for k in ("velocity", "acceleration", "jerk")]

    def objective(x):
        q, qd, qdd, _ = info.derivatives(x)
        z = stacked(model, data, q, qd, qdd) * d @ v
        sign, logdet = np.linalg.slogdet(z.T @ z / len(q))
        return -logdet / v.shape[1] if sign > 0 else 1e3

    g = grid.limit_rows(ranges, bounds)
    x0 = rng.normal(size=2 * n * harmonics) / np.tile(np.arange(1, harmonics + 1), 2 * n)
    x0 = 0.95 * into_limits(grid, 1e3 * x0, ranges, bounds, harmonics)
    start = -objective(x0)
    # Optimized in units of acceleration (a_jl ω_l², b_jl ω_l²), so that every variable moves the
    # limits alike (in radians the fifth harmonic's jerk is 125 times the first's); the finite
    # differences take steps of EPS there, wide enough to see through the sign(q̇) columns.
    u = np.tile(1 / (2 * np.pi * f0 * np.arange(1, harmonics + 1)) ** 2, 2 * n)
    res = so.minimize(lambda y: objective(y * u), x0 / u, method="SLSQP",
                      constraints=[{"type": "ineq", "fun": lambda y: 1 - g @ (y * u), "jac": lambda _: -g * u}],
                      options={"maxiter": maxiter, "ftol": 1e-10, "eps": EPS})
    # Limits hold at POINTS per period; between them the optimum may cross by a few percent.
    x = into_limits(fine, res.x * u, ranges, bounds, harmonics)
    a, b = x[: n * harmonics].reshape(n, harmonics), x[n * harmonics:].reshape(n, harmonics)
    coeffs = f"sin = {json.dumps(a.tolist())}\ncos = {json.dumps(b.tolist())}\n"
    text = re.sub(r"(?ms)^sin = .*?^cos = [^\n]*\n", lambda _: coeffs, text)
    with open(out, "w") as f:
        f.write(text)
    print(json.dumps({"d_optimal": -objective(x), "optimizer": -res.fun, "start": start,
                      "iterations": int(res.nit), "evaluations": int(res.nfev),
                      "message": res.message, "seconds": time.perf_counter() - t0}))


if __name__ == "__main__":
    main()
