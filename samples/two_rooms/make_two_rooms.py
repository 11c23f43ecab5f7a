#!/usr/bin/env python3
"""Writes two_rooms.obj + two_rooms.mtl: two rooms joined by a doorway, lit by one ceiling panel in room A.

Metres, +Y up, right-handed. Room A x in [0,4], partition wall x in [4,4.2] with a 1 m x 2.1 m doorway
(z in [1.5,2.5]), room B x in [4.2,8.2]; z in [0,4]; y in [0,3]. Floor, ceiling and outer walls are
single-sided and face into the rooms (counter-clockwise seen from inside); the partition and the furniture
are closed and face outward. Large faces are cut into tiles of at most TILE metres. Standard library only;
the output is deterministic, so re-running it reproduces the committed files byte for byte.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from scene_mesh import Mesh, X, Y, Z, write_obj  # noqa: E402

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


WIDTH, DEPTH, HEIGHT = 8.2, 4.0, 3.0
WALL0, WALL1 = 4.0, 4.2
DOOR_Z0, DOOR_Z1, DOOR_H = 1.5, 2.5, 2.1


def build():
    m = Mesh(TILE)
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


def write(m):
    write_obj(m, HERE, "two_rooms", MATERIALS, "make_two_rooms.py")


if __name__ == "__main__":
    write(build())
