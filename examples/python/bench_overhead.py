#!/usr/bin/env python3
"""The two overheads of the Python module (issue 29's targets), on the Panda in a MotionBenchMaker
bookshelf: Checker.check on 10^5 random states against the C++ Checker::check on the same array
(a loop in C++ over the same checker, Checker._cpp_seconds), and one state per call against the C++
call on one state. Repeated rounds interleave the two; medians of wall-clock and of CPU time are
printed (CPU time: what the process itself spent, steadier on a shared machine).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/bench_overhead.py [--threads 1] [--rounds 7]
"""
import argparse
import statistics
import time

import numpy as np

import rastercheck
from common import panda_files

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--states", type=int, default=100_000)
parser.add_argument("--threads", type=int, default=1, help="worker threads of the batch (default 1)")
parser.add_argument("--rounds", type=int, default=7)
parser.add_argument("--calls", type=int, default=20_000, help="single-state calls per round")
args = parser.parse_args()

urdf, srdf, scene, request = panda_files()
problem = rastercheck.load(urdf, srdf=srdf, scene=scene, request=request)
checker = rastercheck.Checker(problem, threads=args.threads)
q = np.random.default_rng(0).uniform(problem.lower, problem.upper, size=(args.states, problem.dof))
one = problem.start  # a valid state: the verdict takes every pair's cull or proof

checker.check(q[:1000])  # warm the pools


def timed(work, calls):
    """Seconds per call, (wall clock, CPU time of the process): on a busy machine the CPU time still
    counts only this process's own work."""
    wall, cpu = time.perf_counter(), time.process_time()
    work()
    return (time.perf_counter() - wall) / calls, (time.process_time() - cpu) / calls


def python_loop():
    check = checker.check
    for _ in range(args.calls):
        check(one)


rounds = {"batch_py": [], "batch_cpp": [], "single_py": [], "single_cpp": []}
for _ in range(args.rounds):
    rounds["batch_cpp"].append(timed(lambda: checker._cpp_seconds(q, 1), 1))
    rounds["batch_py"].append(timed(lambda: checker.check(q), 1))
    rounds["single_cpp"].append(timed(lambda: checker._cpp_seconds(one, args.calls), args.calls))
    rounds["single_py"].append(timed(python_loop, args.calls))

print(f"{problem}, backend {checker.backend}, {args.threads} thread(s), median of {args.rounds} rounds")
for clock, k in (("wall", 0), ("cpu", 1)):
    median = {key: statistics.median(r[k] for r in values) for key, values in rounds.items()}
    py, cpp = median["batch_py"], median["batch_cpp"]
    print(f"{clock}: batch of {args.states}: Python {args.states / py:,.0f} states/s, C++ {args.states / cpp:,.0f} "
          f"states/s, Python takes {100 * (py / cpp - 1):+.2f} % time; one state: Python "
          f"{1e6 * median['single_py']:.2f} us per call, C++ {1e6 * median['single_cpp']:.2f} us, overhead "
          f"{1e6 * (median['single_py'] - median['single_cpp']):.2f} us")
