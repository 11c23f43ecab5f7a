#!/usr/bin/env python3
"""Writes two_rooms.obj + two_rooms.mtl: two rooms joined by a doorway, lit by one ceiling panel in room A.

Metres, +Y up, right-handed. Room A x in [0,4], partition wall x in [4,4.2] with a 1 m x 2.1 m doorway
(z in [1.5,2.5]), room B x in [4.2,8.2]; z in [0,4]; y in [0,3]. Floor, ceiling and outer walls are
single-sided and face into the rooms (counter-clockwise seen from inside); the partition and the furniture
are closed and face outward. Large faces are cut into tiles of at most TILE metres. Standard library only;
the output is deterministic, so re-running it reproduces the committed files byte for byte.
"""
import math
import os

TILE = 1.0
HERE = os.path.dirname(os.path.abspath(__file__))

MATERIALS = [
    # name, Kd, Ke (radiance, W/(m^2 sr))
    ("wall", (0.75, 0.75, 0.72), None),
    ("floor", (0.45, 0.40, 0.35), None),
    ("ceiling", (0.80, 0.80, 0.80), None),
    ("partition", (0.70, 0.70, 0.68), None),
    ("red_box", (0.80, 0.08, 0.06), None),
    ("grey_box", (0.50, 0.50, 0.50), None),
    ("blue_box", (0.08, 0.15, 0.70), None),
    ("wood_box", (0.55, 0.35, 0.18), None),
    ("ceiling_light", (0.0, 0.0, 0.0), (30.0, 30.0, 30.0)),
]


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


class Mesh:
    def __init__(self):
        self.vertices = []
        self.groups = []  # (material, [faces as 1-based index tuples])

    def rect(self, material, origin, u, v, normal):
        """Rectangle origin + s*u + t*v (s, t in [0,1]) facing `normal`, tiled, as counter-clockwise quads."""
        if dot(cross(u, v), normal) < 0:
            u, v = v, u
        assert dot(cross(u, v), normal) > 0, "normal must not lie in the rectangle"
        nu = max(1, math.ceil(math.sqrt(dot(u, u)) / TILE - 1e-9))
        nv = max(1, math.ceil(math.sqrt(dot(v, v)) / TILE - 1e-9))
        base = len(self.vertices)
        for j in range(nv + 1):
            for i in range(nu + 1):
                s, t = i / nu, j / nv
                self.vertices.append(tuple(origin[k] + s * u[k] + t * v[k] for k in range(3)))
        faces = []
        for j in range(nv):
            for i in range(nu):
                a = base + j * (nu + 1) + i + 1
                faces.append((a, a + 1, a + 1 + (nu + 1), a + (nu + 1)))
        self.groups.append((material, faces))

    def axis_rect(self, material, axis, coord, lo, hi, facing):
        """Axis-aligned rectangle on plane `axis` = coord, spanning lo..hi in the other two axes, facing +-axis."""
        a, b = [k for k in range(3) if k != axis]
        origin = [0.0, 0.0, 0.0]
        origin[axis], origin[a], origin[b] = coord, lo[0], lo[1]
        u = [0.0, 0.0, 0.0]
        v = [0.0, 0.0, 0.0]
        u[a] = hi[0] - lo[0]
        v[b] = hi[1] - lo[1]
        n = [0.0, 0.0, 0.0]
        n[axis] = facing
        self.rect(material, tuple(origin), tuple(u), tuple(v), tuple(n))

    def box(self, material, lo, hi):
        """Closed box, faces pointing out."""
        for axis in range(3):
            a, b = [k for k in range(3) if k != axis]
            self.axis_rect(material, axis, lo[axis], (lo[a], lo[b]), (hi[a], hi[b]), -1.0)
            self.axis_rect(material, axis, hi[axis], (lo[a], lo[b]), (hi[a], hi[b]), +1.0)


X, Y, Z = 0, 1, 2
WIDTH, DEPTH, HEIGHT = 8.2, 4.0, 3.0
WALL0, WALL1 = 4.0, 4.2
DOOR_Z0, DOOR_Z1, DOOR_H = 1.5, 2.5, 2.1


def build():
    m = Mesh()
    # Shell: single-sided, facing into the rooms. Floor and ceiling run under/over the partition.
    # axis_rect spans (lo, hi) in the two remaining axes in order: y plane -> (x, z), x plane -> (y, z),
    # z plane -> (x, y).
    m.axis_rect("floor", Y, 0.0, (0.0, 0.0), (WIDTH, DEPTH), +1.0)
    m.axis_rect("ceiling", Y, HEIGHT, (0.0, 0.0), (WIDTH, DEPTH), -1.0)
    m.axis_rect("wall", X, 0.0, (0.0, 0.0), (HEIGHT, DEPTH), +1.0)
    m.axis_rect("wall", X, WIDTH, (0.0, 0.0), (HEIGHT, DEPTH), -1.0)
    m.axis_rect("wall", Z, 0.0, (0.0, 0.0), (WIDTH, HEIGHT), +1.0)
    m.axis_rect("wall", Z, DEPTH, (0.0, 0.0), (WIDTH, HEIGHT), -1.0)

    # Partition: closed slab x in [4, 4.2] with the doorway cut through (jambs and lintel closed).
    for x, facing in ((WALL0, -1.0), (WALL1, +1.0)):
        m.axis_rect("partition", X, x, (0.0, 0.0), (HEIGHT, DOOR_Z0), facing)  # (y, z) on the x plane
        m.axis_rect("partition", X, x, (0.0, DOOR_Z1), (HEIGHT, DEPTH), facing)
        m.axis_rect("partition", X, x, (DOOR_H, DOOR_Z0), (HEIGHT, DOOR_Z1), facing)
    m.axis_rect("partition", Y, HEIGHT, (WALL0, 0.0), (WALL1, DEPTH), +1.0)  # (x, z) on the y plane
    m.axis_rect("partition", Y, 0.0, (WALL0, 0.0), (WALL1, DOOR_Z0), -1.0)
    m.axis_rect("partition", Y, 0.0, (WALL0, DOOR_Z1), (WALL1, DEPTH), -1.0)
    m.axis_rect("partition", Z, 0.0, (WALL0, 0.0), (WALL1, HEIGHT), -1.0)  # (x, y) on the z plane
    m.axis_rect("partition", Z, DEPTH, (WALL0, 0.0), (WALL1, HEIGHT), +1.0)
    m.axis_rect("partition", Z, DOOR_Z0, (WALL0, 0.0), (WALL1, DOOR_H), +1.0)  # jamb facing into the opening
    m.axis_rect("partition", Z, DOOR_Z1, (WALL0, 0.0), (WALL1, DOOR_H), -1.0)
    m.axis_rect("partition", Y, DOOR_H, (WALL0, DOOR_Z0), (WALL1, DOOR_Z1), -1.0)  # lintel underside

    # Furniture: closed boxes, one clearly coloured per room for colour bleeding.
    m.box("red_box", (0.6, 0.0, 0.6), (1.6, 0.9, 1.4))
    m.box("grey_box", (2.6, 0.0, 3.2), (3.6, 1.8, 3.8))
    m.box("blue_box", (6.6, 0.0, 0.5), (7.6, 0.8, 1.5))
    m.box("wood_box", (5.0, 0.0, 3.1), (6.4, 0.75, 3.8))

    # The only light: an emissive panel just below room A's ceiling, facing down.
    m.axis_rect("ceiling_light", Y, HEIGHT - 0.02, (1.5, 1.5), (2.5, 2.5), -1.0)
    return m


def fmt(c):
    s = ("%.4f" % c).rstrip("0").rstrip(".")
    return "0" if s in ("", "-0") else s


def write(m):
    obj = os.path.join(HERE, "two_rooms.obj")
    mtl = os.path.join(HERE, "two_rooms.mtl")
    with open(mtl, "w", newline="\n") as f:
        f.write("# two_rooms.mtl: written by make_two_rooms.py. Kd = albedo, Ke = radiance W/(m^2 sr).\n")
        for name, kd, ke in MATERIALS:
            f.write("\nnewmtl %s\nKd %.4f %.4f %.4f\n" % ((name,) + kd))
            if ke:
                f.write("Ke %.4f %.4f %.4f\n" % ke)
    with open(obj, "w", newline="\n") as f:
        f.write("# two_rooms.obj: written by make_two_rooms.py (metres, +Y up). Do not edit by hand.\n")
        f.write("mtllib two_rooms.mtl\n")
        for v in m.vertices:
            f.write("v %s\n" % " ".join(fmt(c) for c in v))
        for material, faces in m.groups:
            f.write("usemtl %s\n" % material)
            for face in faces:
                f.write("f %d %d %d %d\n" % face)
    quads = sum(len(f) for _, f in m.groups)
    print("wrote %s (%d vertices, %d quads = %d triangles) and %s" % (obj, len(m.vertices), quads, 2 * quads, mtl))


if __name__ == "__main__":
    write(build())
