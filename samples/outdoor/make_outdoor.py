#!/usr/bin/env python3
"""Writes outdoor.obj + outdoor.mtl: an open level, three houses and a walled yard on a ground plane.

The level the shared scenes do not have: open ground under a sun and a sky, lit mostly by bounce light where
the sun does not reach (under eaves, in a walled yard, inside the houses through doors and windows).

Metres, +Y up, right-handed. The ground is one single-sided plane facing up (x, z in [-GROUND, GROUND]); the
houses, their floors, roofs and the yard walls are closed solids facing out. Each house has walls THICK thick
with door and window openings cut through (the openings' reveals are faces too), a flat roof slab whose eaves
overhang the walls by EAVES, and house B has a second storey (an inner floor slab). Large faces are cut into
tiles of at most TILE metres. Standard library only; the output is deterministic, so re-running it reproduces
the committed files byte for byte.
"""
import math
import os

TILE = 2.0
HERE = os.path.dirname(os.path.abspath(__file__))
GROUND = 24.0  # the ground plane spans [-GROUND, GROUND] in x and z
THICK = 0.3  # wall thickness
EAVES = 0.7  # roof overhang beyond the walls
ROOF = 0.25  # roof slab thickness

MATERIALS = [
    # name, Kd (albedo)
    ("ground", (0.32, 0.30, 0.24)),
    ("street", (0.22, 0.22, 0.22)),
    ("plaster", (0.75, 0.72, 0.66)),
    ("plaster_ochre", (0.78, 0.60, 0.32)),
    ("plaster_blue", (0.45, 0.55, 0.70)),
    ("roof", (0.30, 0.14, 0.10)),
    ("slab", (0.55, 0.55, 0.55)),
    ("yard_wall", (0.60, 0.58, 0.55)),
    ("bench", (0.45, 0.30, 0.16)),
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
        if hi[0] - lo[0] <= 1e-9 or hi[1] - lo[1] <= 1e-9:
            return
        origin = [0.0, 0.0, 0.0]
        origin[axis], origin[a], origin[b] = coord, lo[0], lo[1]
        u = [0.0, 0.0, 0.0]
        v = [0.0, 0.0, 0.0]
        u[a] = hi[0] - lo[0]
        v[b] = hi[1] - lo[1]
        n = [0.0, 0.0, 0.0]
        n[axis] = facing
        self.rect(material, tuple(origin), tuple(u), tuple(v), tuple(n))

    def box(self, material, lo, hi, skip=()):
        """Closed box, faces pointing out; `skip` names faces left out as (axis, -1 | +1)."""
        for axis in range(3):
            a, b = [k for k in range(3) if k != axis]
            for side, coord in ((-1.0, lo[axis]), (1.0, hi[axis])):
                if (axis, side) not in skip:
                    self.axis_rect(material, axis, coord, (lo[a], lo[b]), (hi[a], hi[b]), side)

    def wall(self, material, along, lo, hi, openings, skip_ends=False):
        """A solid wall: box lo..hi, long along axis `along` (X or Z), thin along the other horizontal axis,
        with rectangular openings cut through it: (u0, u1, y0, y1) along the wall and in height. The two big
        faces are split on the grid of the openings' edges; each opening gets its four reveal faces."""
        across = Z if along == X else X
        us = sorted({lo[along], hi[along]} | {o[0] for o in openings} | {o[1] for o in openings})
        ys = sorted({lo[Y], hi[Y]} | {o[2] for o in openings} | {o[3] for o in openings})

        def open_at(u, y):
            return any(o[0] <= u <= o[1] and o[2] <= y <= o[3] for o in openings)

        for side, coord in ((-1.0, lo[across]), (1.0, hi[across])):
            for i in range(len(us) - 1):
                for j in range(len(ys) - 1):
                    if open_at(0.5 * (us[i] + us[i + 1]), 0.5 * (ys[j] + ys[j + 1])):
                        continue
                    cell_lo, cell_hi = [0.0] * 3, [0.0] * 3
                    cell_lo[along], cell_hi[along] = us[i], us[i + 1]
                    cell_lo[Y], cell_hi[Y] = ys[j], ys[j + 1]
                    a, b = [k for k in range(3) if k != across]
                    self.axis_rect(material, across, coord, (cell_lo[a], cell_lo[b]), (cell_hi[a], cell_hi[b]), side)
        # Top (bottom lies on the ground, ends butt against the crossing walls unless asked).
        a, b = [k for k in range(3) if k != Y]
        self.axis_rect(material, Y, hi[Y], (lo[a], lo[b]), (hi[a], hi[b]), 1.0)
        if not skip_ends:
            for side, coord in ((-1.0, lo[along]), (1.0, hi[along])):
                a, b = [k for k in range(3) if k != along]
                self.axis_rect(material, along, coord, (lo[a], lo[b]), (hi[a], hi[b]), side)
        # Reveals: the faces inside each opening, facing into it.
        for u0, u1, y0, y1 in openings:
            t0, t1 = lo[across], hi[across]
            for ucoord, facing in ((u0, 1.0), (u1, -1.0)):  # jambs
                a, b = [k for k in range(3) if k != along]
                rlo, rhi = [0.0] * 3, [0.0] * 3
                rlo[across], rhi[across] = t0, t1
                rlo[Y], rhi[Y] = y0, y1
                self.axis_rect(material, along, ucoord, (rlo[a], rlo[b]), (rhi[a], rhi[b]), facing)
            for ycoord, facing in ((y1, -1.0), (y0, 1.0)):  # lintel underside, sill top (none for doors)
                if facing > 0 and y0 <= lo[Y] + 1e-9:
                    continue
                rlo, rhi = [0.0] * 3, [0.0] * 3
                rlo[across], rhi[across] = t0, t1
                rlo[along], rhi[along] = u0, u1
                a, b = [k for k in range(3) if k != Y]
                self.axis_rect(material, Y, ycoord, (rlo[a], rlo[b]), (rhi[a], rhi[b]), facing)


X, Y, Z = 0, 1, 2


def house(m, material, x0, z0, x1, z1, height, openings, storey=None):
    """Four thick walls on the footprint x0..x1, z0..z1 (outer faces), a roof slab with eaves, and an inner
    floor slab at `storey` metres. openings: {"south": [...], "north": [...], "west": [...], "east": [...]},
    each (offset along the wall from its low end, width, sill y, top y)."""

    def cut(side, base):
        return [(base + o, base + o + w, y0, y1) for o, w, y0, y1 in openings.get(side, [])]

    # South (z = z0) and north (z = z1) walls span the full width; west and east walls fit between them.
    m.wall(material, X, (x0, 0.0, z0), (x1, height, z0 + THICK), cut("south", x0))
    m.wall(material, X, (x0, 0.0, z1 - THICK), (x1, height, z1), cut("north", x0))
    m.wall(material, Z, (x0, 0.0, z0 + THICK), (x0 + THICK, height, z1 - THICK), cut("west", z0), skip_ends=True)
    m.wall(material, Z, (x1 - THICK, 0.0, z0 + THICK), (x1, height, z1 - THICK), cut("east", z0), skip_ends=True)
    m.box("roof", (x0 - EAVES, height, z0 - EAVES), (x1 + EAVES, height + ROOF, z1 + EAVES))
    if storey is not None:
        m.box("slab", (x0 + THICK, storey - 0.2, z0 + THICK), (x1 - THICK, storey, z1 - THICK))


def build():
    m = Mesh()
    # Ground: single-sided, facing up; a darker street strip along x between the houses.
    m.axis_rect("ground", Y, 0.0, (-GROUND, -GROUND), (GROUND, -2.0), 1.0)  # y plane spans (x, z)
    m.axis_rect("street", Y, 0.0, (-GROUND, -2.0), (GROUND, 2.0), 1.0)
    m.axis_rect("ground", Y, 0.0, (-GROUND, 2.0), (GROUND, GROUND), 1.0)

    door = lambda o: (o, 1.0, 0.0, 2.1)  # noqa: E731
    window = lambda o, y0=1.0: (o, 1.2, y0, y0 + 1.2)  # noqa: E731
    # House A: one storey, door and windows facing the street (south of the street, its north wall on it).
    house(m, "plaster", -10.0, -10.0, -2.0, -3.0, 3.2,
          {"north": [window(1.0), door(3.5), window(5.8)], "west": [window(2.5)], "south": [window(3.0)]})
    # House B: two storeys across the street, openings on both floors.
    house(m, "plaster_ochre", -4.0, 3.0, 3.0, 10.0, 6.0,
          {"south": [door(1.0), window(3.0), window(5.0), window(1.0, 3.8), window(3.0, 3.8), window(5.0, 3.8)],
           "east": [window(2.5), window(2.5, 3.8)], "north": [window(2.9, 3.8)]},
          storey=3.0)
    # House C: south of the street, its yard (walled) to its east, a door onto the yard.
    house(m, "plaster_blue", 3.0, -9.0, 9.0, -3.0, 3.5,
          {"north": [window(1.0), door(3.0)], "east": [door(2.5), window(4.2)], "south": [window(2.4)]})
    # The yard: walls 2.2 m high closing x in [9, 16], z in [-12, -3] against house C's east wall.
    yard_h = 2.2
    m.wall("yard_wall", X, (9.0, 0.0, -3.0 - THICK), (16.0, yard_h, -3.0), [(11.0, 12.2, 0.0, 2.0)])  # gate
    m.wall("yard_wall", X, (6.0, 0.0, -12.0), (16.0, yard_h, -12.0 + THICK), [])
    m.wall("yard_wall", Z, (16.0 - THICK, 0.0, -12.0 + THICK), (16.0, yard_h, -3.0 - THICK), [], skip_ends=True)
    m.wall("yard_wall", Z, (6.0, 0.0, -12.0 + THICK), (6.0 + THICK, yard_h, -9.0), [], skip_ends=True)
    # A bench in the yard and one on the street: small solids standing on the ground (no bottom face).
    m.box("bench", (12.0, 0.0, -8.0), (14.0, 0.45, -7.4), skip=((Y, -1.0),))
    m.box("bench", (-1.0, 0.0, -2.9), (1.0, 0.45, -2.4), skip=((Y, -1.0),))
    return m


def fmt(c):
    s = ("%.4f" % c).rstrip("0").rstrip(".")
    return "0" if s in ("", "-0") else s


def write(m):
    obj = os.path.join(HERE, "outdoor.obj")
    mtl = os.path.join(HERE, "outdoor.mtl")
    with open(mtl, "w", newline="\n") as f:
        f.write("# outdoor.mtl: written by make_outdoor.py. Kd = albedo.\n")
        for name, kd in MATERIALS:
            f.write("\nnewmtl %s\nKd %.4f %.4f %.4f\n" % ((name,) + kd))
    with open(obj, "w", newline="\n") as f:
        f.write("# outdoor.obj: written by make_outdoor.py (metres, +Y up). Do not edit by hand.\n")
        f.write("mtllib outdoor.mtl\n")
        for v in m.vertices:
            f.write("v %s\n" % " ".join(fmt(c) for c in v))
        for material, faces in m.groups:
            if not faces:
                continue
            f.write("usemtl %s\n" % material)
            for face in faces:
                f.write("f %d %d %d %d\n" % face)
    quads = sum(len(f) for _, f in m.groups)
    print("wrote %s (%d vertices, %d quads = %d triangles) and %s" % (obj, len(m.vertices), quads, 2 * quads, mtl))


if __name__ == "__main__":
    write(build())
