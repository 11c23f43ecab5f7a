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
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from scene_mesh import Mesh, X, Y, Z, write_obj  # noqa: E402

TILE = 2.0
HERE = os.path.dirname(os.path.abspath(__file__))
GROUND = 24.0  # the ground plane spans [-GROUND, GROUND] in x and z
THICK = 0.3  # wall thickness
EAVES = 0.7  # roof overhang beyond the walls
ROOF = 0.25  # roof slab thickness

MATERIALS = [
    # name, Kd (albedo), Ke
    ("ground", (0.32, 0.30, 0.24), None),
    ("street", (0.22, 0.22, 0.22), None),
    ("plaster", (0.75, 0.72, 0.66), None),
    ("plaster_ochre", (0.78, 0.60, 0.32), None),
    ("plaster_blue", (0.45, 0.55, 0.70), None),
    ("roof", (0.30, 0.14, 0.10), None),
    ("slab", (0.55, 0.55, 0.55), None),
    ("yard_wall", (0.60, 0.58, 0.55), None),
    ("bench", (0.45, 0.30, 0.16), None),
]




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
    m = Mesh(TILE)
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


def write(m):
    write_obj(m, HERE, "outdoor", MATERIALS, "make_outdoor.py")


if __name__ == "__main__":
    write(build())
