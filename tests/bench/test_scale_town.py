#!/usr/bin/env python3
"""bench/scale.py: the towns it bakes are N exact copies of the source, and its exponent fit is a least-squares
slope on log-log axes (checked against closed forms)."""
import math
import os
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.dont_write_bytecode = True
sys.path.insert(0, os.path.join(ROOT, "bench"))
import scale  # noqa: E402

SOURCE = os.path.join(ROOT, "samples", "outdoor", "outdoor.obj")


def bounds(verts):
    return [min(v[a] for v in verts) for a in range(3)], [max(v[a] for v in verts) for a in range(3)]


class TownIsCopiesOfTheSource(unittest.TestCase):
    def test_four_copies_tile_a_square_of_twice_the_pitch(self):
        src_v, src_f, _ = scale.read_obj(SOURCE)
        lo, hi = bounds(src_v)
        pitch = max(hi[0] - lo[0], hi[2] - lo[2])
        with tempfile.TemporaryDirectory() as d:
            scene, faces = scale.write_town(SOURCE, os.path.splitext(SOURCE)[0] + ".scene.json", 4, d)
            self.assertEqual(faces, 4 * len(src_f))
            v, f, mtllib = scale.read_obj(os.path.join(d, "town_4.obj"))
            self.assertTrue(os.path.exists(os.path.join(d, mtllib)))
            self.assertTrue(os.path.exists(scene))
        self.assertEqual(len(v), 4 * len(src_v))
        self.assertEqual(len(f), 4 * len(src_f))
        tlo, thi = bounds(v)
        for a in (0, 2):
            self.assertAlmostEqual(thi[a] - tlo[a], 2 * pitch, places=3)
        self.assertAlmostEqual(tlo[1], lo[1], places=5)
        self.assertAlmostEqual(thi[1], hi[1], places=5)
        # Each copy is the source moved rigidly: its edge lengths are the source's, face by face.
        n = len(src_v)
        for c in range(4):
            for (_, fs), (_, ft) in list(zip(src_f, f[c * len(src_f):(c + 1) * len(src_f)]))[::97]:
                for i, j in zip(fs, fs[1:] + fs[:1]):
                    a, b = src_v[i], src_v[j]
                    p, q = v[ft[fs.index(i)]], v[ft[fs.index(j)]]
                    self.assertAlmostEqual(math.dist(a, b), math.dist(p, q), places=3)
                    self.assertTrue(c * n <= ft[fs.index(i)] < (c + 1) * n)

    def test_copies_must_be_a_square(self):
        with tempfile.TemporaryDirectory() as d, self.assertRaises(SystemExit):
            scale.write_town(SOURCE, os.path.splitext(SOURCE)[0] + ".scene.json", 8, d)


class ExponentIsTheLogLogSlope(unittest.TestCase):
    def test_power_laws(self):
        xs = [1e3, 4e3, 16e3, 64e3]
        self.assertAlmostEqual(scale.fit_exponent(xs, [3 * x ** 1.25 for x in xs]), 1.25, places=9)
        self.assertAlmostEqual(scale.fit_exponent(xs, [7.0 for _ in xs]), 0.0, places=9)
        self.assertIsNone(scale.fit_exponent([5.0], [1.0]))
        self.assertIsNone(scale.fit_exponent(xs, [None] * 4))


if __name__ == "__main__":
    unittest.main()
