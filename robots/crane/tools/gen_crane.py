#!/usr/bin/env python3
"""Generates robots/crane/crane.urdf and robots/crane/crane.srdf (standard library only).

    python3 robots/crane/tools/gen_crane.py

All dimensions are in metres and radians; every number lives in this file so the model can be
re-dimensioned in one place. See robots/crane/README.md for the meaning of each frame.

Rule kept throughout: the primitives of one link never overlap each other (they may share a face).
A link's primitives are merged into one component, and a parity (inside/outside) test over a merged
mesh would read a point inside two overlapping primitives as "outside".
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
CRANE_DIR = os.path.dirname(HERE)

PI = math.pi

# ---------------------------------------------------------------- kinematic parameters
BASE_XY_RANGE = 1.0             # base_x, base_y in [-1, 1] m (repositioning on crane mats)
BASE_YAW_RANGE = PI / 12        # base_yaw in [-15 deg, +15 deg]
SLEW_HEIGHT = 1.4               # slew bearing top above ground (carrier frame z)
LUFF_PIVOT = (-1.8, 0.0, 1.9)   # boom foot pin in the superstructure frame (3.3 m above ground)
LUFF_MAX = math.radians(80.0)   # luff in [0, 80 deg]
TELE_MAX = 9.3                  # each telescope stroke in [0, 9.3] m -> boom 12.0 .. 39.9 m
HOIST_MIN, HOIST_MAX = 1.0, 35.0

# Boom sections: (link, joint origin x in the parent section frame, length, half width y,
# half height z). A section frame sits at the section's rear end on the boom axis; the base
# section's frame is the luff pivot and the base reaches 0.5 m behind it (heel).
BOOM_BASE = dict(x0=-0.5, length=11.4, hy=0.50, hz=0.60)
SECTIONS = [
    ("boom_section_1", "telescope_1", 0.0, 11.0, 0.44, 0.53),
    ("boom_section_2", "telescope_2", 0.3, 10.8, 0.38, 0.46),
    ("boom_section_3", "telescope_3", 0.3, 10.6, 0.32, 0.39),
]
# Sheave head, in the sheave_head frame (origin = centre of section 3's front face).
HEAD = dict(x=(0.0, 0.8), hy=0.32, z=(-0.9, 0.39))
# Rope point: where the hoist rope leaves the main sheaves (front-bottom edge of the head).
ROPE_POINT = (0.8, 0.0, -0.9)

# Hook block (hook_block frame = rope end, z down is negative).
HOOK_SHEAVES = dict(size=(0.7, 0.5, 1.0), z_top=0.0)
HOOK = dict(size=(0.3, 0.2, 0.5))
HOOK_POINT_Z = -1.5             # bottom of the hook: where the rigging hangs
# Load (frame = hook point). A 4 x 2 x 2 m heat-exchanger skid on four slings, 2 m of rigging.
LOAD_SIZE = (4.0, 2.0, 2.0)
RIGGING_HEIGHT = 2.0
LUG = (1.8, 0.8)                # lifting lugs on the top face, inboard of the corners
SLING_RADIUS = 0.04


def f(v):
    s = "%.6f" % v
    s = s.rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def vec(v):
    return " ".join(f(x) for x in v)


class Prim:
    def __init__(self, kind, dims, xyz, rpy=(0, 0, 0)):
        self.kind, self.dims, self.xyz, self.rpy = kind, dims, xyz, rpy

    def geometry(self):
        if self.kind == "box":
            return '<box size="%s"/>' % vec(self.dims)
        if self.kind == "cylinder":
            return '<cylinder radius="%s" length="%s"/>' % (f(self.dims[0]), f(self.dims[1]))
        return '<sphere radius="%s"/>' % f(self.dims[0])


def box_span(x, y, z):
    """Box from coordinate spans (lo, hi) on each axis."""
    return Prim("box", (x[1] - x[0], y[1] - y[0], z[1] - z[0]),
                ((x[0] + x[1]) / 2, (y[0] + y[1]) / 2, (z[0] + z[1]) / 2))


def cylinder_between(a, b, radius):
    d = [b[i] - a[i] for i in range(3)]
    length = math.sqrt(sum(c * c for c in d))
    u = [c / length for c in d]
    pitch = math.acos(max(-1.0, min(1.0, u[2])))
    yaw = math.atan2(u[1], u[0])
    mid = tuple((a[i] + b[i]) / 2 for i in range(3))
    return Prim("cylinder", (radius, length), mid, (0.0, pitch, yaw))


# ---------------------------------------------------------------- link geometry
def carrier_geometry():
    # Frame: on the ground, on the slew axis; x along the tracks.
    return [
        ("track_left", "black", box_span((-3.5, 3.5), (1.6, 2.5), (0.0, 1.2))),
        ("track_right", "black", box_span((-3.5, 3.5), (-2.5, -1.6), (0.0, 1.2))),
        ("car_body", "yellow", box_span((-1.8, 1.8), (-1.6, 1.6), (0.5, 1.2))),
        ("slew_bearing", "grey", Prim("cylinder", (1.3, SLEW_HEIGHT - 1.2), (0, 0, (1.2 + SLEW_HEIGHT) / 2))),
    ]


def superstructure_geometry():
    # Frame: top of the slew bearing, on the slew axis; x towards the boom.
    return [
        ("deck", "yellow", box_span((-3.0, 2.6), (-1.5, 1.5), (0.0, 0.4))),
        ("counterweight", "grey", box_span((-3.8, -3.0), (-1.5, 1.5), (0.0, 1.4))),
        ("house", "yellow", box_span((-3.0, 0.6), (-1.5, -0.75), (0.4, 2.0))),
        ("cab", "glass", box_span((0.8, 2.4), (0.7, 1.5), (0.4, 2.2))),
        ("boom_rest", "yellow", box_span((-2.6, -1.0), (-0.5, 0.5), (0.4, 1.0))),
    ]


def boom_base_geometry():
    b = BOOM_BASE
    return [("boom_base", "yellow", box_span((b["x0"], b["x0"] + b["length"]), (-b["hy"], b["hy"]), (-b["hz"], b["hz"])))]


def section_geometry(length, hy, hz):
    return [("section", "yellow", box_span((0.0, length), (-hy, hy), (-hz, hz)))]


def head_geometry():
    h = HEAD
    return [("sheave_head", "grey", box_span(h["x"], (-h["hy"], h["hy"]), h["z"]))]


def hook_geometry():
    sx, sy, sz = HOOK_SHEAVES["size"]
    hx, hy, hz = HOOK["size"]
    return [
        ("hook_sheaves", "orange", box_span((-sx / 2, sx / 2), (-sy / 2, sy / 2), (-sz, 0.0))),
        ("hook", "grey", box_span((-hx / 2, hx / 2), (-hy / 2, hy / 2), (-sz - hz, -sz))),
    ]


def load_geometry():
    lx, ly, lz = LOAD_SIZE
    top = -RIGGING_HEIGHT
    prims = [("skid", "blue", box_span((-lx / 2, lx / 2), (-ly / 2, ly / 2), (top - lz, top)))]
    # Slings from the hook point to the lugs, stopped short at both ends so that they overlap
    # neither each other nor the skid (see the rule at the top of this file).
    for sx in (1, -1):
        for sy in (1, -1):
            lug = (sx * LUG[0], sy * LUG[1], top)
            n = math.sqrt(lug[0] ** 2 + lug[1] ** 2 + lug[2] ** 2)
            u = [c / n for c in lug]
            a = tuple(0.15 * c for c in u)                # 0.15 m below the hook point
            b = tuple(lug[i] - 0.10 * u[i] for i in range(3))  # 0.10 m above the lug
            prims.append(("sling_%s%s" % ("f" if sx > 0 else "r", "l" if sy > 0 else "r"), "white",
                          cylinder_between(a, b, SLING_RADIUS)))
    return prims


# ---------------------------------------------------------------- kinematic tree
# (name, type, parent, child, xyz, axis, (lower, upper), effort, velocity, mimic)
def joints():
    j = []
    j.append(("base_x", "prismatic", "world", "base_x_link", (0, 0, 0), (1, 0, 0),
              (-BASE_XY_RANGE, BASE_XY_RANGE), 5.0e5, 0.3, None))
    j.append(("base_y", "prismatic", "base_x_link", "base_y_link", (0, 0, 0), (0, 1, 0),
              (-BASE_XY_RANGE, BASE_XY_RANGE), 5.0e5, 0.3, None))
    j.append(("base_yaw", "revolute", "base_y_link", "carrier", (0, 0, 0), (0, 0, 1),
              (-BASE_YAW_RANGE, BASE_YAW_RANGE), 1.0e6, 0.1, None))
    j.append(("slew", "continuous", "carrier", "superstructure", (0, 0, SLEW_HEIGHT), (0, 0, 1),
              None, 5.0e5, 0.2, None))
    # Boom along +x of boom_base; rotation about -y raises it (positive luff = boom up).
    j.append(("luff", "revolute", "superstructure", "boom_base", LUFF_PIVOT, (0, -1, 0),
              (0.0, LUFF_MAX), 5.0e6, 0.05, None))
    parent = "boom_base"
    for k, (link, joint, x0, _, _, _) in enumerate(SECTIONS):
        mimic = None if k == 0 else ("telescope_1", 1.0, 0.0)
        j.append((joint, "prismatic", parent, link, (x0, 0, 0), (1, 0, 0), (0.0, TELE_MAX), 3.0e5, 0.2, mimic))
        parent = link
    j.append(("boom_tip", "fixed", SECTIONS[-1][0], "sheave_head", (SECTIONS[-1][3], 0, 0), None, None, None, None, None))
    # hook_pitch undoes luff (same axis, multiplier -1): hoist_frame stays parallel to the
    # superstructure frame, so its z axis is vertical whatever the boom angle.
    j.append(("hook_pitch", "revolute", "sheave_head", "hoist_frame", ROPE_POINT, (0, -1, 0),
              (-LUFF_MAX, 0.0), 1.0e5, 0.05, ("luff", -1.0, 0.0)))
    j.append(("hoist", "prismatic", "hoist_frame", "hook_block", (0, 0, 0), (0, 0, -1),
              (HOIST_MIN, HOIST_MAX), 6.0e5, 0.5, None))
    j.append(("load_attach", "fixed", "hook_block", "load", (0, 0, HOOK_POINT_Z), None, None, None, None, None))
    return j


LINKS = [
    ("world", []),
    ("base_x_link", []),
    ("base_y_link", []),
    ("carrier", carrier_geometry()),
    ("superstructure", superstructure_geometry()),
    ("boom_base", boom_base_geometry()),
] + [(s[0], section_geometry(s[3], s[4], s[5])) for s in SECTIONS] + [
    ("sheave_head", head_geometry()),
    ("hoist_frame", []),
    ("hook_block", hook_geometry()),
    ("load", load_geometry()),
]

MATERIALS = {
    "yellow": (0.95, 0.75, 0.05, 1), "black": (0.12, 0.12, 0.12, 1), "grey": (0.45, 0.45, 0.48, 1),
    "glass": (0.55, 0.7, 0.8, 1), "orange": (0.95, 0.45, 0.05, 1), "blue": (0.2, 0.35, 0.7, 1),
    "white": (0.9, 0.9, 0.9, 1),
}


def origin(xyz, rpy=(0, 0, 0)):
    return '<origin xyz="%s" rpy="%s"/>' % (vec(xyz), vec(rpy))


def urdf():
    out = ['<?xml version="1.0"?>',
           '<!-- GENERATED by robots/crane/tools/gen_crane.py - edit that script, not this file. -->',
           '<!-- rastercheck crawler crane, 50 t class, telescopic boom 12.0-39.9 m. See README.md. -->',
           '<robot name="crawler_crane">']
    for name, rgba in MATERIALS.items():
        out.append('  <material name="%s"><color rgba="%s"/></material>' % (name, vec(rgba)))
    for link, prims in LINKS:
        if not prims:
            out.append('  <link name="%s"/>' % link)
            continue
        out.append('  <link name="%s">' % link)
        for pname, mat, p in prims:
            out.append('    <visual name="%s">' % pname)
            out.append('      ' + origin(p.xyz, p.rpy))
            out.append('      <geometry>%s</geometry>' % p.geometry())
            out.append('      <material name="%s"/>' % mat)
            out.append('    </visual>')
        for pname, mat, p in prims:
            out.append('    <collision name="%s">' % pname)
            out.append('      ' + origin(p.xyz, p.rpy))
            out.append('      <geometry>%s</geometry>' % p.geometry())
            out.append('    </collision>')
        out.append('  </link>')
    for (name, jtype, parent, child, xyz, axis, lim, effort, vel, mimic) in joints():
        out.append('  <joint name="%s" type="%s">' % (name, jtype))
        out.append('    <parent link="%s"/>' % parent)
        out.append('    <child link="%s"/>' % child)
        out.append('    ' + origin(xyz))
        if axis is not None:
            out.append('    <axis xyz="%s"/>' % vec(axis))
        if effort is not None:
            if lim is None:
                out.append('    <limit effort="%s" velocity="%s"/>' % (f(effort), f(vel)))
            else:
                out.append('    <limit lower="%s" upper="%s" effort="%s" velocity="%s"/>'
                           % (f(lim[0]), f(lim[1]), f(effort), f(vel)))
        if mimic is not None:
            out.append('    <mimic joint="%s" multiplier="%s" offset="%s"/>' % (mimic[0], f(mimic[1]), f(mimic[2])))
        out.append('  </joint>')
    out.append('</robot>')
    return "\n".join(out) + "\n"


# ---------------------------------------------------------------- SRDF
DISABLED = [
    ("carrier", "superstructure", "Adjacent", "slew bearing: superstructure deck sits on the carrier's slew ring"),
    ("superstructure", "boom_base", "Adjacent", "boom foot pinned to the superstructure (luff pivot)"),
    ("boom_base", "boom_section_1", "Adjacent", "telescopic section 1 slides inside the base section"),
    ("boom_section_1", "boom_section_2", "Adjacent", "telescopic section 2 slides inside section 1"),
    ("boom_section_2", "boom_section_3", "Adjacent", "telescopic section 3 slides inside section 2"),
    ("boom_base", "boom_section_2", "Default", "nested: section 2 lies inside the base section at short extension"),
    ("boom_base", "boom_section_3", "Default", "nested: section 3 lies inside the base section at short extension"),
    ("boom_section_1", "boom_section_3", "Default", "nested: section 3 lies inside section 1 at short extension"),
    ("boom_section_3", "sheave_head", "Adjacent", "sheave head welded to the front of section 3"),
    ("hook_block", "load", "Adjacent", "load hangs from the hook by its slings"),
]

# Named configurations over the active joints (the site's start and goal are added by
# robots/sites/tools/gen_plant.py into the site files, not here).
GROUP_STATES = {
    "transport": dict(base_x=0, base_y=0, base_yaw=0, slew=0, luff=0.0, telescope_1=0.0, hoist=HOIST_MIN),
    "ready": dict(base_x=0, base_y=0, base_yaw=0, slew=0, luff=math.radians(60), telescope_1=3.0, hoist=5.0),
}
ACTIVE = ["base_x", "base_y", "base_yaw", "slew", "luff", "telescope_1", "hoist"]


def srdf():
    out = ['<?xml version="1.0"?>',
           '<!-- GENERATED by robots/crane/tools/gen_crane.py - edit that script, not this file. -->',
           '<robot name="crawler_crane">',
           '  <group name="crane">',
           '    <chain base_link="world" tip_link="load"/>',
           '  </group>']
    for name, vals in GROUP_STATES.items():
        out.append('  <group_state name="%s" group="crane">' % name)
        for j in ACTIVE:
            out.append('    <joint name="%s" value="%s"/>' % (j, f(vals[j])))
        out.append('  </group_state>')
    for a, b, reason, why in DISABLED:
        out.append('  <!-- %s -->' % why)
        out.append('  <disable_collisions link1="%s" link2="%s" reason="%s"/>' % (a, b, reason))
    out.append('</robot>')
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    with open(os.path.join(CRANE_DIR, "crane.urdf"), "w") as fh:
        fh.write(urdf())
    with open(os.path.join(CRANE_DIR, "crane.srdf"), "w") as fh:
        fh.write(srdf())
    print("wrote crane.urdf and crane.srdf in", CRANE_DIR)
