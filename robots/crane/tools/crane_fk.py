#!/usr/bin/env python3
"""Forward kinematics and box-level checks for crane.urdf (standard library only).

Used as a module by check_crane.py and robots/sites/tools/gen_plant.py. It reads the URDF itself
(links, joints, mimic, collision primitives), so it checks the file, not the generator's numbers.

Collision test: every primitive is replaced by its oriented bounding box (a box is exact, a
cylinder or sphere becomes the box around it), and two boxes are tested with the separating-axis
theorem. Hence "no overlap" here is conservative: the real primitives are at least as far apart.
"""
import math
import xml.etree.ElementTree as ET


# ---------------------------------------------------------------- small 4x4 / 3x3 algebra
def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def identity():
    return [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]


def rpy_matrix(r, p, y):
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr]]


def transform(xyz, rot):
    t = identity()
    for i in range(3):
        for j in range(3):
            t[i][j] = rot[i][j]
        t[i][3] = xyz[i]
    return t


def axis_angle(axis, angle):
    x, y, z = axis
    n = math.sqrt(x * x + y * y + z * z)
    x, y, z = x / n, y / n, z / n
    c, s = math.cos(angle), math.sin(angle)
    C = 1 - c
    return [[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
            [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
            [z * x * C - y * s, z * y * C + x * s, c + z * z * C]]


def parse_vec(s, default):
    return tuple(float(v) for v in s.split()) if s is not None else default


# ---------------------------------------------------------------- model
class Model:
    def __init__(self, path):
        root = ET.parse(path).getroot()
        self.links = {}
        for link in root.findall("link"):
            prims = []
            for col in link.findall("collision"):
                o = col.find("origin")
                xyz = parse_vec(o.get("xyz") if o is not None else None, (0.0, 0.0, 0.0))
                rpy = parse_vec(o.get("rpy") if o is not None else None, (0.0, 0.0, 0.0))
                g = col.find("geometry")[0]
                if g.tag == "box":
                    half = tuple(v / 2 for v in parse_vec(g.get("size"), None))
                elif g.tag == "cylinder":
                    r, l = float(g.get("radius")), float(g.get("length"))
                    half = (r, r, l / 2)
                elif g.tag == "sphere":
                    r = float(g.get("radius"))
                    half = (r, r, r)
                else:
                    raise ValueError("unsupported geometry " + g.tag)
                prims.append(dict(name=col.get("name"), kind=g.tag, half=half,
                                  local=transform(xyz, rpy_matrix(*rpy))))
            self.links[link.get("name")] = prims
        self.joints = []
        children = set()
        for j in root.findall("joint"):
            o = j.find("origin")
            xyz = parse_vec(o.get("xyz") if o is not None else None, (0.0, 0.0, 0.0))
            rpy = parse_vec(o.get("rpy") if o is not None else None, (0.0, 0.0, 0.0))
            ax = j.find("axis")
            lim = j.find("limit")
            mim = j.find("mimic")
            jd = dict(name=j.get("name"), type=j.get("type"), parent=j.find("parent").get("link"),
                      child=j.find("child").get("link"), origin=transform(xyz, rpy_matrix(*rpy)),
                      axis=parse_vec(ax.get("xyz") if ax is not None else None, (1.0, 0.0, 0.0)),
                      lower=float(lim.get("lower")) if lim is not None and lim.get("lower") else None,
                      upper=float(lim.get("upper")) if lim is not None and lim.get("upper") else None,
                      mimic=None)
            if mim is not None:
                jd["mimic"] = (mim.get("joint"), float(mim.get("multiplier", 1)), float(mim.get("offset", 0)))
            self.joints.append(jd)
            children.add(jd["child"])
        roots = [l for l in self.links if l not in children]
        assert len(roots) == 1, roots
        self.root = roots[0]
        by_name = {j["name"]: j for j in self.joints}
        for j in self.joints:
            if j["mimic"] is not None:
                src = by_name[j["mimic"][0]]
                assert src["mimic"] is None, "mimic of a mimic: " + j["name"]
        self.active = [j["name"] for j in self.joints if j["type"] != "fixed" and j["mimic"] is None]
        # topological order
        order, frontier = [], [self.root]
        while frontier:
            l = frontier.pop(0)
            for j in self.joints:
                if j["parent"] == l:
                    order.append(j)
                    frontier.append(j["child"])
        self.order = order

    def fk(self, q):
        """q: dict active joint -> value. Returns dict link -> 4x4 world pose."""
        vals = dict(q)
        for j in self.joints:
            if j["mimic"] is not None:
                src, m, off = j["mimic"]
                vals[j["name"]] = m * q[src] + off
        poses = {self.root: identity()}
        for j in self.order:
            t = mat_mul(poses[j["parent"]], j["origin"])
            v = vals.get(j["name"], 0.0)
            if j["type"] in ("revolute", "continuous"):
                t = mat_mul(t, transform((0, 0, 0), axis_angle(j["axis"], v)))
            elif j["type"] == "prismatic":
                a = j["axis"]
                t = mat_mul(t, transform(tuple(v * c for c in a), axis_angle((0, 0, 1), 0.0)))
            poses[j["child"]] = t
        return poses

    def obbs(self, q, inflate=0.0):
        """World OBBs of every collision primitive: list of (link, prim name, centre, axes, half)."""
        poses = self.fk(q)
        out = []
        for link, prims in self.links.items():
            for p in prims:
                t = mat_mul(poses[link], p["local"])
                centre = tuple(t[i][3] for i in range(3))
                axes = [tuple(t[i][k] for i in range(3)) for k in range(3)]
                out.append((link, p["name"], centre, axes, tuple(h + inflate for h in p["half"])))
        return out


# ---------------------------------------------------------------- OBB overlap (SAT)
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def obb_overlap(c1, a1, h1, c2, a2, h2, eps=1e-9):
    """True when the closed boxes overlap with positive depth (touching faces do not count)."""
    d = tuple(c2[i] - c1[i] for i in range(3))
    axes = list(a1) + list(a2)
    for u in a1:
        for v in a2:
            w = cross(u, v)
            n = math.sqrt(dot(w, w))
            if n > 1e-9:
                axes.append(tuple(x / n for x in w))
    for ax in axes:
        r1 = sum(h1[k] * abs(dot(a1[k], ax)) for k in range(3))
        r2 = sum(h2[k] * abs(dot(a2[k], ax)) for k in range(3))
        if abs(dot(d, ax)) >= r1 + r2 - eps:
            return False
    return True


def obb_clearance(c1, a1, h1, c2, a2, h2, hi=5.0, tol=1e-3):
    """Largest margin m (up to hi) such that the boxes inflated by m/2 each still do not overlap:
    a lower bound on the distance between the boxes (exact when the closest features are faces)."""
    if obb_overlap(c1, a1, h1, c2, a2, h2):
        return 0.0
    lo, up = 0.0, hi
    while up - lo > tol:
        m = (lo + up) / 2
        g = m / 2
        if obb_overlap(c1, a1, tuple(x + g for x in h1), c2, a2, tuple(x + g for x in h2)):
            up = m
        else:
            lo = m
    return lo
