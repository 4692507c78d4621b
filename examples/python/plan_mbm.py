#!/usr/bin/env python3
"""Plans a MotionBenchMaker problem (the Panda reaching into a bookshelf) with BatchRRTConnect and
certified edges, then re-checks the path densely.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/plan_mbm.py [scenario] [index]
"""
import argparse

import numpy as np

import rastercheck
from common import panda_files

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("scenario", nargs="?", default="bookshelf_small",
                    help="bookshelf_small, bookshelf_tall, bookshelf_thin, box, cage, table_pick, table_under_pick")
parser.add_argument("index", type=int, nargs="?", default=1, help="problem number (1 to 100)")
parser.add_argument("--planner", default="batchrrtconnect", help=f"one of {', '.join(rastercheck.planners())}")
parser.add_argument("--time-limit", type=float, default=10.0)
parser.add_argument("--seed", type=int, default=1)
args = parser.parse_args()

urdf, srdf, scene, request = panda_files(args.scenario, args.index)
problem = rastercheck.load(urdf, srdf=srdf, scene=scene, request=request)
path, result = rastercheck.plan(problem, planner=args.planner, time_limit=args.time_limit, seed=args.seed)
print(problem)
print(f"{result.planner}: solved={result.solved} in {1000 * result.time:.1f} ms "
      f"(+{1000 * result.simplify_time:.1f} ms simplifying), {result.states_checked} states checked")
if result.solved:
    np.set_printoptions(precision=3, suppress=True)
    print(f"path: {len(path)} states, length {result.length:.3f}\n{path}")
    checker = rastercheck.Checker(problem, mode="exact")
    t = np.linspace(0, 1, 100)[:, None]
    dense = np.concatenate([(1 - t) * a + t * b for a, b in zip(path[:-1], path[1:])])
    print(f"re-checked at {len(dense)} states by the exact oracle: "
          f"{'collision-free' if checker.check(dense).all() else 'COLLIDES'}; "
          f"edges certified: {bool(checker.check_motions(path[:-1], path[1:]).all())}")
