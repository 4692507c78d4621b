#!/usr/bin/env python3
"""The two overheads of the Python module (issue 29's targets), on the Panda in a MotionBenchMaker
bookshelf: Checker.check on 10^5 random states against the C++ Checker::check on the same array
(timed in C++ by the same checker, Checker._cpp_seconds), and one state per call against the C++
call on one state. Repeated rounds interleave the two; medians are printed.

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
batch_py, batch_cpp, single_py, single_cpp = [], [], [], []
for _ in range(args.rounds):
    batch_cpp.append(checker._cpp_seconds(q, 1))
    start = time.perf_counter()
    checker.check(q)
    batch_py.append(time.perf_counter() - start)

    single_cpp.append(checker._cpp_seconds(one, args.calls))
    check = checker.check
    start = time.perf_counter()
    for _ in range(args.calls):
        check(one)
    single_py.append((time.perf_counter() - start) / args.calls)

py, cpp = statistics.median(batch_py), statistics.median(batch_cpp)
print(f"{problem}, backend {checker.backend}, {args.threads} thread(s), median of {args.rounds} rounds")
print(f"batch of {args.states}: Python {args.states / py:,.0f} states/s, C++ {args.states / cpp:,.0f} states/s, "
      f"Python takes {100 * (py / cpp - 1):+.2f} % time")
py, cpp = statistics.median(single_py), statistics.median(single_cpp)
print(f"one state: Python {1e6 * py:.2f} us per call, C++ {1e6 * cpp:.2f} us, overhead {1e6 * (py - cpp):.2f} us")
