"""Identify a robot's inertial parameters from arrays you already have (here: a smooth motion of
the KUKA LWR4+ and its torques with 0.2 N m of noise), under the physically-consistent set.

usage: python python/examples/identify_from_arrays.py   (from the repository root)
"""
import numpy as np
import physid

robot = physid.Robot("data/kuka_lwr4/kuka_lwr4.urdf")
t = np.arange(5000) / 1000.0
w = 2 * np.pi * np.array([0.3, 0.5, 0.7, 0.4, 0.6, 0.8, 0.9])
q, qd, qdd = np.sin(w * t[:, None]), w * np.cos(w * t[:, None]), -(w**2) * np.sin(w * t[:, None])
tau = robot.inverse_dynamics(q, qd, qdd) + np.random.default_rng(0).normal(scale=0.2, size=q.shape)

fit = physid.identify_arrays(robot, q, qd, qdd, tau, rate=1000.0, constraints="consistent")
print(fit)   # an Identification, as physid.identify returns for a file: theta, bodies(), write_urdf(), …
# The torques were made by the description itself: the data determine what moves the joints,
# not every mass near the base (compare torques, and see `physid identify`'s identifiability).
described = {b["name"]: b["mass"] for b in robot.describe()["bodies"]}
for body in fit.bodies().itertuples():
    print(f"{body.name:<14} m = {body.m:7.3f} kg (description {described[body.name]:.3f})")
rms = np.sqrt(np.mean((robot.regressor(q, qd, qdd) @ fit.theta[: len(robot.parameter_names)] - tau) ** 2))
print(f"torque RMS of the fit: {rms:.3f} N m (noise 0.2)")
