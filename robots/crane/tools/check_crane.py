#!/usr/bin/env python3
"""Sanity checks of crane.urdf / crane.srdf (standard library only).

    python3 robots/crane/tools/check_crane.py

1. the hoist frame stays vertical (z axis = world z) over random configurations;
2. the boom reach table (rope point radius and height from luff angle and telescope stroke);
3. the hook block never touches the boom or sheave head, even at the shortest rope and steepest boom;
4. nested sections lie inside each other at zero extension and keep a real overlap at full stroke;
5. which non-exempt link pairs can self-collide (expected: load vs boom at steep luff / short rope,
   load vs carrier or superstructure when the load is lowered close to the crane).
"""
import math
import os
import random
import sys
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, HERE)
import crane_fk as ck  # noqa: E402

URDF = os.path.join(os.path.dirname(HERE), "crane.urdf")
SRDF = os.path.join(os.path.dirname(HERE), "crane.srdf")


def limits(model):
    lim = {}
    for j in model.joints:
        if j["name"] in model.active:
            lo = j["lower"] if j["lower"] is not None else -math.pi
            hi = j["upper"] if j["upper"] is not None else math.pi
            lim[j["name"]] = (lo, hi)
    return lim


def random_q(lim, rng):
    return {k: rng.uniform(*v) for k, v in lim.items()}


def exempt_pairs(model):
    pairs = set()
    for a in ET.parse(SRDF).getroot().findall("disable_collisions"):
        pairs.add(frozenset((a.get("link1"), a.get("link2"))))
    for j in model.joints:
        if model.links[j["parent"]] and model.links[j["child"]]:
            pairs.add(frozenset((j["parent"], j["child"])))
    return pairs


def main():
    m = ck.Model(URDF)
    lim = limits(m)
    print("active joints:", m.active)
    for k in m.active:
        print("  %-12s [%9.4f, %9.4f]" % (k, *lim[k]))
    rng = random.Random(1)

    # 1. vertical hoist frame
    worst = 0.0
    for _ in range(2000):
        q = random_q(lim, rng)
        t = m.fk(q)["hoist_frame"]
        yaw = q["base_yaw"] + q["slew"]
        ref = ck.axis_angle((0, 0, 1), yaw)
        err = max(abs(t[i][j] - ref[i][j]) for i in range(3) for j in range(3))
        worst = max(worst, err)
    print("\n1. hoist_frame orientation vs Rz(base_yaw + slew), max |dR| over 2000 samples: %.2e" % worst)
    assert worst < 1e-9

    # 2. reach table
    print("\n2. rope point (where the rope leaves the sheaves), base at 0, slew 0:")
    print("   luff[deg] tele[m] boom[m]  radius[m] height[m]")
    for luff in (0, 30, 45, 60, 80):
        for tele in (0.0, 9.3):
            q = dict(base_x=0, base_y=0, base_yaw=0, slew=0, luff=math.radians(luff), telescope_1=tele, hoist=1.0)
            p = m.fk(q)["hoist_frame"]
            print("   %8d %7.1f %7.1f  %9.3f %9.3f" % (luff, tele, 12.0 + 3 * tele, p[0][3], p[2][3]))

    # 3. hook block vs boom and sheave head
    worst = (1e9, None)
    boom_links = ("boom_base", "boom_section_1", "boom_section_2", "boom_section_3", "sheave_head")
    for luff_deg in [x * 0.5 for x in range(0, 161)]:
        for tele in (0.0, 4.65, 9.3):
            q = dict(base_x=0, base_y=0, base_yaw=0, slew=0, luff=math.radians(luff_deg), telescope_1=tele, hoist=1.0)
            boxes = m.obbs(q)
            hook = [b for b in boxes if b[0] == "hook_block"]
            for b in boxes:
                if b[0] in boom_links:
                    for h in hook:
                        c = ck.obb_clearance(h[2], h[3], h[4], b[2], b[3], b[4])
                        if c < worst[0]:
                            worst = (c, (luff_deg, tele, b[0], h[1]))
    print("\n3. hook block vs boom/sheave head at the shortest rope (1 m), luff 0..80 deg:")
    print("   min clearance %.3f m at luff %.1f deg, tele %.2f m, %s vs %s" % (worst[0], *worst[1]))
    assert worst[0] > 0.05

    # 4. nesting
    print("\n4. telescopic sections (boom_base frame, axial extent; cross-section half sizes):")
    for tele in (0.0, 9.3):
        q = dict(base_x=0, base_y=0, base_yaw=0, slew=0, luff=0.0, telescope_1=tele, hoist=1.0)
        poses = m.fk(q)
        x0 = poses["boom_base"][0][3]
        ext = []
        for l in boom_links:
            for p in m.links[l]:
                t = ck.mat_mul(poses[l], p["local"])
                c = t[0][3] - x0
                ext.append((l, c - p["half"][0], c + p["half"][0], p["half"][1], p["half"][2]))
        print("   telescope = %.1f m:" % tele)
        for l, a, b, hy, hz in ext:
            print("     %-15s x %7.2f .. %7.2f   |y| <= %.2f  |z| <= %.2f" % (l, a, b, hy, hz))
        if tele > 0:
            for (la, a0, a1, _, _), (lb, b0, b1, _, _) in zip(ext[:3], ext[1:4]):
                print("     overlap %s / %s: %.2f m" % (la, lb, a1 - b0))

    # 5. self-collision census
    exempt = exempt_pairs(m)
    hits = {}
    n = 20000
    for _ in range(n):
        q = random_q(lim, rng)
        boxes = [b for b in m.obbs(q)]
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                a, b = boxes[i], boxes[j]
                if a[0] == b[0] or frozenset((a[0], b[0])) in exempt:
                    continue
                if ck.obb_overlap(a[2], a[3], a[4], b[2], b[3], b[4]):
                    key = tuple(sorted((a[0], b[0])))
                    hits.setdefault(key, []).append(q)
    print("\n5. self-collision census over %d uniform samples (box-level, conservative for slings):" % n)
    for key, qs in sorted(hits.items(), key=lambda kv: -len(kv[1])):
        luffs = [math.degrees(q["luff"]) for q in qs]
        hoists = [q["hoist"] for q in qs]
        print("   %-32s %5.1f%%  luff %5.1f..%5.1f deg, hoist %5.2f..%5.2f m"
              % (" / ".join(key), 100.0 * len({id(q) for q in qs}) / n, min(luffs), max(luffs), min(hoists), max(hoists)))
    print("\nall checks passed")


if __name__ == "__main__":
    main()
