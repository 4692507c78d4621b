#!/usr/bin/env python3
"""The README's Python example: the crane's lift through the plant (robots/), checked along the
straight line from pick to set-down, then planned with a 0.25 m clearance.

    PYTHONPATH=build/python python3 examples/python/crane_lift.py   (from the repository root)
"""
import pathlib

import numpy as np
import rastercheck

root = pathlib.Path(__file__).resolve().parents[2]
lift = rastercheck.load(root / "robots/crane/crane.urdf", srdf=root / "robots/crane/crane.srdf",
                        scene=root / "robots/sites/plant.yaml", request=root / "robots/sites/plant_lift.yaml")
checker = rastercheck.Checker(lift, padding=0.25)  # mode="safe", backend="auto", threads=0
t = np.linspace(0, 1, 11)[:, None]
q = (1 - t) * lift.start + t * lift.goal           # (11, 7) float64, lift.coordinate_names order
valid = checker.check(q)                           # bool, shape (11,)
print(lift.coordinate_names, valid, sep="\n")
print(checker.contacts(q[np.argmin(valid)])[0]["description"])
path, result = rastercheck.plan(lift, padding=0.25, seed=1)  # BatchRRTConnect, certified edges
np.set_printoptions(precision=2, suppress=True)
print(result, path, sep="\n")
