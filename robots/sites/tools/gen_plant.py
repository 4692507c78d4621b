#!/usr/bin/env python3
"""Generates robots/sites/plant.yaml (MoveIt PlanningScene) and robots/sites/plant_lift.yaml
(MoveIt MotionPlanRequest) for the crane in robots/crane/crane.urdf, and checks them
(standard library only):

    python3 robots/sites/tools/gen_plant.py           # write + check
    python3 robots/sites/tools/gen_plant.py --check   # check only

Checks (box level: cylinders are replaced by their bounding boxes, so every "clear" is conservative):
  * no two scene primitives overlap (touching is allowed), all inside the 80 x 80 m site;
  * nothing inside the crane's keep-clear zone (tail swing 4.09 m + base travel 1.41 m + 2 m);
  * start and goal: load centred over the pick / set-down spot with the intended gap, no contact
    with the scene, no self-collision outside the SRDF/adjacent pairs;
  * a piecewise-linear joint-space path start -> goal (README "reference path") is clear at
    every 2 cm / 0.1 deg step, which shows the problem is solvable.
"""
import math
import os
import sys
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
SITES = os.path.dirname(HERE)
ROBOTS = os.path.dirname(SITES)
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.join(ROBOTS, "crane", "tools"))
import crane_fk as ck  # noqa: E402

URDF = os.path.join(ROBOTS, "crane", "crane.urdf")
SRDF = os.path.join(ROBOTS, "crane", "crane.srdf")

Q_IDENT = (0.0, 0.0, 0.0, 1.0)
S45 = math.sqrt(0.5)
Q_ALONG_X = (0.0, S45, 0.0, S45)  # cylinder axis (z) turned onto world x


def box(dims, pos, q=Q_IDENT):
    return ("box", tuple(dims), tuple(pos), q)


def cyl(height, radius, pos, q=Q_IDENT):
    return ("cylinder", (height, radius), tuple(pos), q)


# ---------------------------------------------------------------- the site
PICK = (0.0, -17.0)          # centre of the load at pick-up (on the trailer bed)
SET_DOWN = (0.0, 27.0)       # centre of the load at set-down (on the foundation)
TRAILER_BED_TOP = 1.1
FOUNDATION_TOP = 0.6
GAP = 0.3                    # load bottom above its support at start and goal


def site():
    objs = []  # (id, [primitives])
    # Pick-up: low-bed trailer along the radial direction, tractor at its far end.
    objs.append(("trailer_bed", [box((2.6, 12.0, TRAILER_BED_TOP), (PICK[0], PICK[1], TRAILER_BED_TOP / 2))]))
    objs.append(("truck_tractor", [box((2.6, 3.0, 3.2), (0.0, -25.0, 1.6))]))
    # Set-down: concrete foundation.
    objs.append(("setdown_foundation", [box((3.0, 5.0, FOUNDATION_TOP), (SET_DOWN[0], SET_DOWN[1], FOUNDATION_TOP / 2))]))
    # Pipe rack, east-west, between the crane and the set-down spot: 13 bents every 6 m.
    for k in range(13):
        x = -36.0 + 6.0 * k
        objs.append(("pipe_rack_bent_%02d" % k, [
            box((0.4, 0.4, 8.0), (x, 12.0, 4.0)),   # south column
            box((0.4, 0.4, 8.0), (x, 18.0, 4.0)),   # north column
            box((0.3, 5.6, 0.4), (x, 15.0, 4.8)),   # tier 1 beam, top at 5.0
            box((0.3, 5.6, 0.4), (x, 15.0, 7.8)),   # tier 2 beam, top at 8.0
        ]))
    pipes = [(13.0, 0.30, 5.0), (14.2, 0.40, 5.0), (15.4, 0.25, 5.0), (16.8, 0.50, 5.0),
             (13.2, 0.60, 8.0), (14.8, 0.30, 8.0), (16.0, 0.35, 8.0), (17.2, 0.20, 8.0)]
    for k, (y, r, tier_top) in enumerate(pipes):
        # 5 cm pipe shoes between pipe and beam.
        objs.append(("pipe_%d" % (k + 1), [cyl(72.0, r, (0.0, y, tier_top + 0.05 + r), Q_ALONG_X)]))
    # Tank farm (east).
    objs.append(("tank_1", [cyl(14.0, 6.0, (22.0, -8.0, 7.0))]))
    objs.append(("tank_2", [cyl(14.0, 6.0, (22.0, -24.0, 7.0))]))
    objs.append(("tank_3", [cyl(12.0, 4.0, (33.0, 2.0, 6.0))]))
    # Columns (west).
    objs.append(("distillation_column", [cyl(42.0, 1.8, (-16.0, 4.0, 21.0))]))
    objs.append(("stripper_column", [cyl(30.0, 1.2, (-16.0, -5.0, 15.0))]))
    # Buildings.
    objs.append(("control_building", [box((12.0, 8.0, 5.0), (-27.0, -27.0, 2.5))]))
    objs.append(("substation", [box((10.0, 8.0, 4.0), (-28.0, -12.0, 2.0))]))
    objs.append(("warehouse", [box((20.0, 10.0, 9.0), (-24.0, 32.0, 4.5))]))
    objs.append(("workshop", [box((14.0, 10.0, 7.0), (26.0, 30.0, 3.5))]))
    # Existing process structure (steel frame, 7.6 x 7.6 m, 15 m high) east of the set-down spot.
    prims = []
    xs, ys = (4.2, 11.8), (22.2, 26.0, 29.8)
    for x in xs:
        for y in ys:
            prims.append(box((0.4, 0.4, 15.0), (x, y, 7.5)))
    for top in (5.0, 10.0, 15.0):
        z = top - 0.2
        for x in xs:  # beams along y, between column faces
            prims.append(box((0.3, 3.4, 0.4), (x, 24.1, z)))
            prims.append(box((0.3, 3.4, 0.4), (x, 27.9, z)))
        for y in ys:  # beams along x
            prims.append(box((7.2, 0.3, 0.4), (8.0, y, z)))
    prims.append(box((7.2, 7.2, 0.1), (8.0, 26.0, 10.05)))  # grating on the 10 m level
    objs.append(("process_structure", prims))
    objs.append(("process_vessel", [cyl(8.0, 1.2, (8.0, 24.1, 14.1))]))
    return objs


# ---------------------------------------------------------------- crane placement
def crane_constants(model):
    """Numbers the IK needs, read back from the URDF through FK."""
    q0 = dict(base_x=0, base_y=0, base_yaw=0, slew=0, luff=0.0, telescope_1=0.0, hoist=1.0)
    p = model.fk(q0)
    pivot = p["boom_base"]
    rope = p["hoist_frame"]
    hook = p["load"]
    load_prims = model.links["load"]
    skid = [pr for pr in load_prims if pr["name"] == "skid"][0]
    skid_bottom = skid["local"][2][3] - skid["half"][2]  # in the load frame
    return dict(pivot_x=pivot[0][3], pivot_z=pivot[2][3],
                axial=rope[0][3] - pivot[0][3], drop=pivot[2][3] - rope[2][3],
                hook_below_rope=(rope[2][3] - 1.0) - hook[2][3],  # at hoist = 1
                skid_bottom=skid_bottom)


def place(c, target_xy, bottom_z, tele):
    """Joint values putting the skid's centre over target_xy with its bottom at bottom_z,
    telescope stroke tele, base at 0. Boom length along the axis = c.axial + 3 tele."""
    slew = math.atan2(target_xy[1], target_xy[0])
    radius = math.hypot(*target_xy)
    a, b = c["axial"] + 3 * tele, c["drop"]  # rope point (a, -b) in the boom frame
    # horizontal: pivot_x + a cos t + b sin t = radius
    rho = math.hypot(a, b)
    phi = math.atan2(b, a)
    luff = phi + math.acos((radius - c["pivot_x"]) / rho)
    rope_z = c["pivot_z"] + a * math.sin(luff) - b * math.cos(luff)
    hoist = rope_z - c["hook_below_rope"] + c["skid_bottom"] - bottom_z
    return dict(base_x=0.0, base_y=0.0, base_yaw=0.0, slew=slew, luff=luff, telescope_1=tele, hoist=hoist), rope_z


START_TELE, GOAL_TELE = 5.0, 8.5
VIA_LUFF, VIA_HOIST = math.radians(70.0), 3.0


def reference_path(start, goal):
    """Waypoints of a collision-free path (checked below)."""
    w1 = dict(start, hoist=VIA_HOIST)                    # hoist up
    w2 = dict(w1, luff=VIA_LUFF)                         # luff up: load comes in, over the crane side
    w3 = dict(w2, slew=goal["slew"])                     # slew through east (slew = 0) to north
    w4 = dict(w3, telescope_1=goal["telescope_1"])       # telescope out
    w5 = dict(w4, luff=goal["luff"])                     # luff down over the pipe rack
    return [("start", start), ("hoist up", w1), ("luff up", w2), ("slew", w3), ("telescope out", w4),
            ("luff down", w5), ("lower = goal", goal)]


# ---------------------------------------------------------------- checking
def prim_obb(p):
    kind, dims, pos, q = p
    x, y, z, w = q
    rot = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
           [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
           [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    axes = [tuple(rot[i][k] for i in range(3)) for k in range(3)]
    half = tuple(d / 2 for d in dims) if kind == "box" else (dims[1], dims[1], dims[0] / 2)
    return pos, axes, half


def exempt_pairs(model):
    pairs = set()
    for a in ET.parse(SRDF).getroot().findall("disable_collisions"):
        pairs.add(frozenset((a.get("link1"), a.get("link2"))))
    for j in model.joints:
        if model.links[j["parent"]] and model.links[j["child"]]:
            pairs.add(frozenset((j["parent"], j["child"])))
    return pairs


def check_state(model, scene_obbs, exempt, q, want_clearance=False):
    """Returns (ok, min clearance to the scene or None, first problem)."""
    boxes = model.obbs(q)
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            a, b = boxes[i], boxes[j]
            if a[0] == b[0] or frozenset((a[0], b[0])) in exempt:
                continue
            if ck.obb_overlap(a[2], a[3], a[4], b[2], b[3], b[4]):
                return False, None, "self: %s/%s vs %s/%s" % (a[0], a[1], b[0], b[1])
    best = (1e9, None)
    for a in boxes:
        for oid, (c, ax, h) in scene_obbs:
            if ck.obb_overlap(a[2], a[3], a[4], c, ax, h):
                return False, None, "scene: %s/%s vs %s" % (a[0], a[1], oid)
            if want_clearance:
                cl = ck.obb_clearance(a[2], a[3], a[4], c, ax, h, hi=20.0, tol=1e-3)
                if cl < best[0]:
                    best = (cl, "%s/%s vs %s" % (a[0], a[1], oid))
    return True, best, None


def interpolate(a, b, n):
    return [{k: a[k] + (b[k] - a[k]) * i / n for k in a} for i in range(n + 1)]


def main(write=True):
    model = ck.Model(URDF)
    objs = site()
    c = crane_constants(model)
    start, start_rope = place(c, PICK, TRAILER_BED_TOP + GAP, START_TELE)
    goal, goal_rope = place(c, SET_DOWN, FOUNDATION_TOP + GAP, GOAL_TELE)

    print("crane constants (from the URDF):", {k: round(v, 4) for k, v in c.items()})
    for name, q, rope in (("start", start, start_rope), ("goal", goal, goal_rope)):
        print("%-5s " % name + "  ".join("%s=%.6f" % (k, v) for k, v in q.items()),
              " | luff %.2f deg, boom %.2f m, rope point z %.3f" % (math.degrees(q["luff"]), c["axial"] + 3 * q["telescope_1"], rope))

    # scene primitives: overlap, site bounds, keep-clear zone
    scene = []
    for oid, prims in objs:
        for k, p in enumerate(prims):
            scene.append(("%s/%d" % (oid, k) if len(prims) > 1 else oid, prim_obb(p)))
    n_over = 0
    for i in range(len(scene)):
        for j in range(i + 1, len(scene)):
            (ia, (ca, aa, ha)), (ib, (cb, ab, hb)) = scene[i], scene[j]
            if ck.obb_overlap(ca, aa, ha, cb, ab, hb):
                n_over += 1
                print("  OVERLAP", ia, ib)
    print("scene: %d objects, %d primitives, %d overlapping pairs" % (len(objs), len(scene), n_over))
    assert n_over == 0
    keep_clear = 4.09 + math.sqrt(2) * 1.0 + 2.0
    zone = ((0, 0, 25), [(1, 0, 0), (0, 1, 0), (0, 0, 1)], (keep_clear, keep_clear, 25))
    for oid, (cc, ax, h) in scene:
        assert not ck.obb_overlap(cc, ax, h, *zone), "inside keep-clear zone: " + oid
        for k in range(3):
            ext = sum(abs(ax[i][k]) * h[i] for i in range(3))
            if k < 2:
                assert -40 <= cc[k] - ext and cc[k] + ext <= 40, "outside the site: " + oid
    print("keep-clear square of half-size %.2f m around the slew axis: empty" % keep_clear)

    exempt = exempt_pairs(model)
    # start / goal placement by FK
    for name, q, target, bottom in (("start", start, PICK, TRAILER_BED_TOP + GAP), ("goal", goal, SET_DOWN, FOUNDATION_TOP + GAP)):
        pose = model.fk(q)["load"]
        skid = [p for p in model.links["load"] if p["name"] == "skid"][0]
        t = ck.mat_mul(pose, skid["local"])
        centre = (t[0][3], t[1][3], t[2][3])
        assert abs(centre[0] - target[0]) < 1e-9 and abs(centre[1] - target[1]) < 1e-9
        assert abs(centre[2] - skid["half"][2] - bottom) < 1e-9
        hf = model.fk(q)["hoist_frame"]
        ok, best, problem = check_state(model, scene, exempt, q, want_clearance=True)
        print("%-5s FK: skid centre (%.6f, %.6f, %.6f), bottom %.3f; rope point (%.3f, %.3f, %.3f); "
              "collision-free: %s; min box clearance %.3f m (%s)"
              % (name, *centre, centre[2] - skid["half"][2], hf[0][3], hf[1][3], hf[2][3], ok, best[0], best[1]))
        assert ok, problem

    # reference path
    path = reference_path(start, goal)
    n_checked = 0
    for (na, a), (nb, b) in zip(path, path[1:]):
        steps = max(1, int(max(abs(b[k] - a[k]) / (0.02 if k in ("hoist", "telescope_1", "base_x", "base_y")
                                                 else math.radians(0.1)) for k in a)))
        for q in interpolate(a, b, steps):
            ok, _, problem = check_state(model, scene, exempt, q)
            assert ok, "%s -> %s: %s at %s" % (na, nb, problem, q)
            n_checked += 1
    print("reference path: %d waypoints, %d states checked, all clear" % (len(path), n_checked))
    for name, q in path:
        print("  %-14s " % name + " ".join("%s=%.4f" % (k, v) for k, v in q.items()))

    if write:
        write_scene(objs, start, model, exempt)
        write_request(start, goal)
    return start, goal


# ---------------------------------------------------------------- YAML writers
def num(v):
    if abs(v - round(v)) < 1e-12:
        return str(int(round(v)))
    return repr(round(v, 12))


def flow(vals):
    return "[" + ", ".join(num(v) for v in vals) + "]"


ACTIVE = ["base_x", "base_y", "base_yaw", "slew", "luff", "telescope_1", "hoist"]


def write_scene(objs, start, model, exempt):
    links = sorted(l for l, p in model.links.items() if p)
    out = ["# GENERATED by robots/sites/tools/gen_plant.py - edit that script, not this file.",
           "# Industrial plant for the crawler crane (robots/crane/crane.urdf); see robots/sites/README.md.",
           "# Metres, z up, ground at z = 0 (no ground object: the tracks stand on it), crane slew axis at the origin.",
           "robot_state:",
           "  joint_state:",
           "    name: [%s]" % ", ".join(ACTIVE),
           "    position: %s" % flow([start[k] for k in ACTIVE]),
           "  multi_dof_joint_state:",
           "    transforms: []",
           "    wrench: []",
           "    twist: []",
           "    joint_names: []",
           "robot_model_name: crawler_crane",
           "fixed_frame_transforms:",
           "  - header:",
           "      frame_id: world",
           "    child_frame_id: world",
           "    transform:",
           "      rotation: [0, 0, 0, 1]",
           "      translation: [0, 0, 0]",
           "allowed_collision_matrix:",
           "  entry_names: [%s]" % ", ".join(links),
           "  entry_values:"]
    for a in links:
        out.append("    - [%s]" % ", ".join("true" if frozenset((a, b)) in exempt else "false" for b in links))
    out += ['name: "plant"', "world:", "  collision_objects:"]
    for oid, prims in objs:
        out += ["    - header:", "        frame_id: world", "      id: %s" % oid, "      primitives:"]
        for kind, dims, pos, q in prims:
            out += ["        - type: %s" % kind, "          dimensions: %s" % flow(dims)]
        out.append("      primitive_poses:")
        for kind, dims, pos, q in prims:
            out += ["        - position: %s" % flow(pos), "          orientation: %s" % flow(q)]
    with open(os.path.join(SITES, "plant.yaml"), "w") as fh:
        fh.write("\n".join(out) + "\n")
    print("wrote plant.yaml")


def write_request(start, goal):
    out = ["# GENERATED by robots/sites/tools/gen_plant.py - edit that script, not this file.",
           "# Lift of a 4 x 2 x 2 m skid from the trailer (pick) over the pipe rack onto the foundation",
           "# (set-down). Active joints only: telescope_2, telescope_3 and hook_pitch are mimic joints.",
           "goal_constraints:",
           "  - joint_constraints:"]
    for k in ACTIVE:
        out += ["      - joint_name: %s" % k, "        position: %s" % num(goal[k])]
    out += ["planner_id: RRTConnect",
            "group_name: crane",
            "num_planning_attempts: 1",
            "allowed_planning_time: 60",
            "max_velocity_scaling_factor: 0",
            "max_acceleration_scaling_factor: 0",
            "workspace_parameters:",
            "  header:",
            '    frame_id: "world"',
            "  min_corner: [-40, -40, 0]",
            "  max_corner: [40, 40, 60]",
            "start_state:",
            "  joint_state:",
            "    name: [%s]" % ", ".join(ACTIVE),
            "    position: %s" % flow([start[k] for k in ACTIVE]),
            "    header:",
            "      frame_id: world"]
    with open(os.path.join(SITES, "plant_lift.yaml"), "w") as fh:
        fh.write("\n".join(out) + "\n")
    print("wrote plant_lift.yaml")


if __name__ == "__main__":
    main(write="--check" not in sys.argv)
