#!/usr/bin/env python3
"""Tightens a built-in robot's collision primitives around the robot's published link meshes.

Each link of `panda.urdf` / `fetch.urdf` is a union of boxes, cylinders and spheres that must
cover the link's collision mesh (never thinner than the real robot). This tool samples every
mesh's surface (triangle vertices plus a grid of spacing `--spacing` on each triangle), gives
each sample to the primitive that holds it deepest, and shrinks each primitive, keeping its
kind and orientation, to the smallest one of that kind that holds its own samples at least
`--margin` deep (a box face by face, a cylinder's radius and each end, a sphere's radius). A
primitive never grows. Then it checks the result: every sample must be at least
`--margin` − `--spacing` × 0.58 deep in some primitive (any surface point lies within
0.58 × spacing of a sample of its triangle's grid), and it prints each link's least depth.

The meshes are not part of this repository. They are the robots' collision meshes as
published with their descriptions (franka_description, fetch_description); the URDF naming
them (`--mesh-urdf`) gives each link's mesh file and origin, relative to `--mesh-dir`.

    python3 kinematics/robots/fit_shapes.py kinematics/robots/fetch.urdf \
        --mesh-urdf PATH/fetch.urdf --mesh-dir PATH/meshes --margin 0.0006 \
        --keep r_gripper_finger_link,l_gripper_finger_link --write

(the command that tightened the Fetch's shapes; the finger pads are kept, see docs/robots.md).
The head links have no mesh in that URDF (it models the head as a ball); they were tightened
afterwards around fetch_description's head meshes, which sit at the links' origins:

    python3 kinematics/robots/fit_shapes.py kinematics/robots/fetch.urdf \
        --mesh-urdf PATH/fetch.urdf --mesh-dir PATH/meshes --margin 0.0006 \
        --only head_pan_link,head_tilt_link --mesh head_pan_link=head_pan_link_collision.STL \
        --mesh head_tilt_link=head_tilt_link_collision.STL --write

The Panda's links 6 and 7 and its hand, against the collision meshes VAMP ships (detailed
for those links; its links 1–5 are coarse hulls that this tool cannot measure against):

    python3 kinematics/robots/fit_shapes.py kinematics/robots/panda.urdf \
        --mesh-urdf PATH/panda.urdf --mesh-dir PATH/meshes --margin 0.0006 \
        --only panda_link6,panda_link7,panda_hand --write

Without `--write` it only reports the coverage of the primitives as they are. Needs numpy.
"""

import argparse
import os
import re
import struct
import sys
import xml.etree.ElementTree as ET

import numpy as np

# A surface point lies within this many spacings of a grid sample of its own triangle.
GRID_REACH = 0.58


def rotation(r, p, y):
    """URDF roll-pitch-yaw as a rotation matrix (Rz·Ry·Rx)."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def load_triangles(path):
    """Triangles (n × 3 × 3) of a binary or ASCII STL file or a Wavefront OBJ file."""
    data = open(path, "rb").read()
    if path.lower().endswith(".obj"):
        verts, tris = [], []
        for line in data.decode(errors="ignore").splitlines():
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = [int(t.split("/")[0]) for t in parts[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                tris.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
        return np.array(verts)[np.array(tris)]
    if data[:5] == b"solid" and b"facet" in data[:400]:
        verts = [
            [float(x) for x in line.split()[1:4]]
            for line in data.decode(errors="ignore").splitlines()
            if line.strip().startswith("vertex")
        ]
        return np.array(verts).reshape(-1, 3, 3)
    count = struct.unpack("<I", data[80:84])[0]
    record = np.dtype([("normal", "<3f4"), ("v", "<9f4"), ("attr", "<u2")])
    return np.frombuffer(data[84 : 84 + count * 50], dtype=record)["v"].reshape(-1, 3, 3).astype(float)


def surface_samples(tris, spacing):
    """The triangles' vertices and a barycentric grid of about `spacing` on each."""
    out = [tris.reshape(-1, 3)]
    for a, b, c in tris:
        longest = max(np.linalg.norm(b - a), np.linalg.norm(c - b), np.linalg.norm(a - c))
        n = int(np.ceil(longest / spacing))
        if n <= 1:
            continue
        i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1))
        keep = i + j <= n
        u, w = i[keep] / n, j[keep] / n
        out.append(a * (1 - u - w)[:, None] + b * u[:, None] + c * w[:, None])
    return np.concatenate(out)


def origin_of(element):
    o = element.find("origin")
    if o is None:
        return np.zeros(3), np.zeros(3)
    xyz = np.array([float(x) for x in o.get("xyz", "0 0 0").split()])
    rpy = np.array([float(x) for x in o.get("rpy", "0 0 0").split()])
    return xyz, rpy


def primitives(text):
    """Per link of the URDF `text`: its collision primitives as (kind, xyz, rpy, attributes)."""
    out = {}
    for link in ET.fromstring(text).findall("link"):
        prims = []
        for col in link.findall("collision"):
            xyz, rpy = origin_of(col)
            g = col.find("geometry")[0]
            prims.append((g.tag, xyz, rpy, dict(g.attrib)))
        out[link.get("name")] = prims
    return out


def meshes(urdf, mesh_dir):
    """Per link: the path of its collision mesh and that mesh's origin."""
    out = {}
    for link in ET.parse(urdf).getroot().findall("link"):
        for col in link.findall("collision"):
            m = col.find("geometry/mesh")
            if m is None:
                continue
            xyz, rpy = origin_of(col)
            name = re.sub(r"^package://(meshes/)?", "", m.get("filename"))
            path = os.path.join(mesh_dir, name)
            if "scale" in m.attrib:
                raise SystemExit(f"{link.get('name')}: scaled meshes are not handled")
            out.setdefault(link.get("name"), []).append((path, xyz, rpy))
    return out


def depth(points, prim):
    """How deep each point lies inside the primitive (negative outside)."""
    kind, xyz, rpy, at = prim
    q = (points - xyz) @ rotation(*rpy)
    if kind == "box":
        half = np.array([float(x) for x in at["size"].split()]) / 2
        return (half - np.abs(q)).min(axis=1)
    if kind == "cylinder":
        r, half = float(at["radius"]), float(at["length"]) / 2
        return np.minimum(r - np.hypot(q[:, 0], q[:, 1]), half - np.abs(q[:, 2]))
    if kind == "sphere":
        return float(at["radius"]) - np.linalg.norm(q, axis=1)
    raise SystemExit(f"unknown primitive {kind}")


def number(x):
    s = f"{x:.5f}".rstrip("0").rstrip(".")
    return "0" if s in ("", "-0") else s


def tightened(prim, own, margin):
    """The primitive shrunk to hold the points `own` `margin` deep: (xyz, geometry text)."""
    kind, xyz, rpy, at = prim
    rot = rotation(*rpy)
    q = (own - xyz) @ rot
    if kind == "box":
        old = np.array([float(x) for x in at["size"].split()])
        lo = np.maximum(q.min(axis=0) - margin, -old / 2)
        hi = np.minimum(q.max(axis=0) + margin, old / 2)
        size, mid = hi - lo, (lo + hi) / 2
        geometry = f'<geometry><box size="{" ".join(number(x) for x in size)}"/></geometry>'
    elif kind == "cylinder":
        r_old, half = float(at["radius"]), float(at["length"]) / 2
        r = min(np.hypot(q[:, 0], q[:, 1]).max() + margin, r_old)
        lo, hi = max(q[:, 2].min() - margin, -half), min(q[:, 2].max() + margin, half)
        mid = np.array([0.0, 0.0, (lo + hi) / 2])
        geometry = f'<geometry><cylinder radius="{number(r)}" length="{number(hi - lo)}"/></geometry>'
    else:
        r = min(np.linalg.norm(q, axis=1).max() + margin, float(at["radius"]))
        mid = np.zeros(3)
        geometry = f'<geometry><sphere radius="{number(r)}"/></geometry>'
    return xyz + rot @ mid, geometry


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("urdf", help="the built-in robot's URDF (primitives)")
    ap.add_argument("--mesh-urdf", required=True, help="the URDF naming the collision meshes")
    ap.add_argument("--mesh-dir", required=True, help="folder the mesh file names are relative to")
    ap.add_argument("--margin", type=float, default=0.0006, help="least depth of a sample (m)")
    ap.add_argument("--spacing", type=float, default=0.001, help="sample grid spacing (m)")
    ap.add_argument("--keep", default="", help="comma-separated links to leave as they are")
    ap.add_argument("--only", default="", help="comma-separated links to tighten, leaving the rest as they are")
    ap.add_argument("--mesh", action="append", default=[], metavar="LINK=FILE",
                    help="a link's collision mesh (relative to --mesh-dir, at the link's origin) where "
                         "the mesh URDF names none; may be repeated")
    ap.add_argument("--write", action="store_true", help="rewrite the URDF with the tightened shapes")
    a = ap.parse_args()
    text = open(a.urdf).read()
    ours, theirs = primitives(text), meshes(a.mesh_urdf, a.mesh_dir)
    for item in a.mesh:
        link, _, name = item.partition("=")
        if link not in ours or not name:
            raise SystemExit(f"--mesh {item}: expected LINK=FILE with a link of {a.urdf}")
        theirs[link] = [(os.path.join(a.mesh_dir, name), np.zeros(3), np.zeros(3))]
    only, keep = (set(filter(None, names.split(","))) for names in (a.only, a.keep))
    unknown = sorted((only | keep) - set(ours))
    if unknown:
        raise SystemExit(f"no such link in {a.urdf}: {', '.join(unknown)}")
    least = a.margin - GRID_REACH * a.spacing
    worst = np.inf
    for link, prims in ours.items():
        if not prims or link not in theirs or link in keep or (only and link not in only):
            continue
        points = []
        for path, xyz, rpy in theirs[link]:
            points.append(surface_samples(load_triangles(path), a.spacing) @ rotation(*rpy).T + xyz)
        points = np.concatenate(points)
        deep = np.stack([depth(points, p) for p in prims], axis=1)
        if deep.max(axis=1).min() <= 0:
            raise SystemExit(f"{link}: its primitives do not cover its mesh; nothing written")
        if a.write:
            owner = deep.argmax(axis=1)
            start = text.index(f'<link name="{link}"')
            end = text.index("</link>", start)
            body = text[start:end]
            pattern = r"<collision>\s*(<origin[^>]*/>)\s*(<geometry>.*?</geometry>)\s*</collision>"
            blocks = re.findall(pattern, body, re.S)
            if len(blocks) != len(prims):
                raise SystemExit(f"{link}: expected {len(prims)} collision blocks, found {len(blocks)}")
            for k, (prim, (origin, geometry)) in enumerate(zip(prims, blocks)):
                own = points[owner == k]
                if len(own) == 0:
                    continue
                xyz, new_geometry = tightened(prim, own, a.margin)
                new_origin = re.sub(r'xyz="[^"]*"', f'xyz="{" ".join(number(x) for x in xyz)}"', origin)
                # The visual block that mirrors the collision block changes with it.
                body = re.sub(
                    re.escape(origin) + r"(\s*)" + re.escape(geometry),
                    lambda m: new_origin + m.group(1) + new_geometry,
                    body,
                )
            text = text[:start] + body + text[end:]
            prims = primitives(text)[link]
            deep = np.stack([depth(points, p) for p in prims], axis=1)
        d = deep.max(axis=1)
        worst = min(worst, d.min())
        print(f"{link:24} {len(prims):3} shapes  least depth {d.min() * 1e3:5.2f} mm  "
              f"median {np.median(d) * 1e3:5.2f} mm")
    if a.write:
        if worst < least:
            raise SystemExit(f"a sample lies {worst * 1e3:.2f} mm deep, less than {least * 1e3:.2f} mm; nothing written")
        open(a.urdf, "w").write(text)


if __name__ == "__main__":
    sys.exit(main())
