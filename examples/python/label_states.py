#!/usr/bin/env python3
"""Labels 10^5 random Panda configurations in a MotionBenchMaker bookshelf as valid or colliding, in
one call: the kind of data set a learned planner trains on.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/label_states.py [N] [--out labels.npz]
"""
import argparse
import time

import numpy as np

import rastercheck
from common import panda_files

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("n", type=int, nargs="?", default=100_000, help="states to label (default 10^5)")
parser.add_argument("--threads", type=int, default=0, help="worker threads (0 = all cores)")
parser.add_argument("--out", help="save states and labels to this .npz file")
args = parser.parse_args()

urdf, srdf, scene, _ = panda_files()
problem = rastercheck.load(urdf, srdf=srdf, scene=scene)
checker = rastercheck.Checker(problem, threads=args.threads)
rng = np.random.default_rng(0)
q = rng.uniform(problem.lower, problem.upper, size=(args.n, problem.dof))  # (N, dof) float64, C order

start = time.perf_counter()
valid = checker.check(q)  # bool, shape (N,)
seconds = time.perf_counter() - start
print(f"{problem}\nbackend {checker.backend}, mode {checker.mode}")
print(f"labelled {args.n} states in {seconds:.3f} s ({args.n / seconds:,.0f} states/s): "
      f"{valid.sum()} valid, {args.n - valid.sum()} colliding")
first = int(np.argmin(valid))
if not valid[first]:
    print(f"state {first} collides:", "; ".join(c["description"] for c in checker.contacts(q[first])))
if args.out:
    np.savez_compressed(args.out, q=q, valid=valid, coordinates=problem.coordinate_names)
    print("saved", args.out)
