"""Quad meshes for the sample generators (make_two_rooms.py, make_outdoor.py): axis-aligned rectangles cut into
tiles, boxes, walls with openings, written as OBJ + MTL. Standard library only; deterministic output.

Metres, +Y up, right-handed. A rectangle's quads wind counter-clockwise seen from the side its normal points to.
"""
import math
import os

X, Y, Z = 0, 1, 2


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


class Mesh:
    def __init__(self, tile):
        self.tile = tile  # largest tile edge, metres
        self.vertices = []
        self.groups = []  # (material, [faces as 1-based index tuples])

    def rect(self, material, origin, u, v, normal):
        """Rectangle origin + s*u + t*v (s, t in [0,1]) facing `normal`, tiled, as counter-clockwise quads."""
        if dot(cross(u, v), normal) < 0:
            u, v = v, u
        assert dot(cross(u, v), normal) > 0, "normal must not lie in the rectangle"
        nu = max(1, math.ceil(math.sqrt(dot(u, u)) / self.tile - 1e-9))
        nv = max(1, math.ceil(math.sqrt(dot(v, v)) / self.tile - 1e-9))
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


def fmt(c):
    s = ("%.4f" % c).rstrip("0").rstrip(".")
    return "0" if s in ("", "-0") else s


def write_obj(m, folder, name, materials, tool):
    """Writes folder/name.obj and folder/name.mtl. materials: (name, Kd, Ke or None) in MTL order."""
    obj = os.path.join(folder, name + ".obj")
    mtl = os.path.join(folder, name + ".mtl")
    emissive = any(ke for _, _, ke in materials)
    with open(mtl, "w", newline="\n") as f:
        f.write("# %s.mtl: written by %s. Kd = albedo%s.\n" % (name, tool, ", Ke = radiance W/(m^2 sr)" if emissive else ""))
        for mname, kd, ke in materials:
            f.write("\nnewmtl %s\nKd %.4f %.4f %.4f\n" % ((mname,) + kd))
            if ke:
                f.write("Ke %.4f %.4f %.4f\n" % ke)
    with open(obj, "w", newline="\n") as f:
        f.write("# %s.obj: written by %s (metres, +Y up). Do not edit by hand.\n" % (name, tool))
        f.write("mtllib %s.mtl\n" % name)
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
