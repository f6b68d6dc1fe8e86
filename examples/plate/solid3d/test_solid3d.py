#!/usr/bin/env python3
"""Checks of solid3d.py's deck writer that need no ccx (ctest: examples_solid3d_deck)."""
import math
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import solid3d  # noqa: E402


def read_deck(path):
    """{keyword line: [data lines]} in file order (keywords repeat, so a list of pairs)."""
    blocks = []
    with open(path, encoding="utf-8") as f:
        for line in f:
            line = line.strip()
            if line.startswith("*"):
                blocks.append((line, []))
            elif line:
                blocks[-1][1].append(line)
    return blocks


class Solid3dTest(unittest.TestCase):
    def test_lumped_weights_positive_and_partition_the_face(self):
        w = solid3d.lumped_weights()
        self.assertAlmostEqual(sum(w), 1.0, places=14)
        self.assertTrue(all(v > 0 for v in w))
        self.assertAlmostEqual(w[0], w[3], places=14)  # the four corners alike
        self.assertGreater(w[4], w[0])  # the mid-side nodes carry more than the corners

    def test_face_integral_of_the_whole_face_is_the_partition_of_unity(self):
        self.assertAlmostEqual(sum(solid3d.face_integral(-1, 1, -1, 1)), 1.0, places=14)
        # A quarter of the face: the shape functions still sum to 1 everywhere.
        self.assertAlmostEqual(sum(solid3d.face_integral(0.2, 0.7, -0.9, -0.4)),
                               0.25 * 0.25, places=14)

    def test_deck(self):
        mesh = solid3d.Mesh(per_section=5, across=3, per_layer=1)
        clamps = [0] * 36
        clamps[8] = 1  # section 9 of edge y = 0
        with tempfile.TemporaryDirectory() as work:
            path = os.path.join(work, "strip.inp")
            force = solid3d.write_deck(path, clamps, mesh)
            blocks = read_deck(path)
        # The patch (not on element edges across this width) carries the whole load.
        self.assertAlmostEqual(force, -solid3d.FORCE, places=15)
        nodes = next(d for k, d in blocks if k.startswith("*NODE,"))
        nx, ny, nz = 2 * 90 + 1, 2 * 3 + 1, 2 * 3 + 1
        grid = nx * ny * nz
        unused = sum(1 for i in range(nx) for j in range(ny) for k in range(nz)
                     if i % 2 + j % 2 + k % 2 >= 2)
        self.assertEqual(len(nodes), grid - unused)
        bricks = [d for k, d in blocks if "TYPE=C3D20R" in k]
        self.assertEqual([len(d) // 2 for d in bricks], [90 * 3] * 3)
        # The springs add up to k_eff times the strip's area.
        total = 0.0
        sets = {k.split("ELSET=")[1]: d for k, d in blocks if k.startswith("*ELSET")}
        for key, data in blocks:
            if key.startswith("*SPRING"):
                members = sum(len(line.split(",")) for line in sets[key.split("ELSET=")[1]])
                total += members * float(data[1])
        expected = solid3d.effective_foundation() * solid3d.LENGTH * solid3d.WIDTH
        self.assertAlmostEqual(total / expected, 1.0, places=8)
        self.assertLess(solid3d.effective_foundation(), solid3d.FOUNDATION)
        # Clamp 9 fixes its side face: 2 x 5 + 1 node columns along x, each with the used nodes
        # through the thickness (corner columns 7, mid-side columns 4).
        fixed = next(d for k, d in blocks if k == "*BOUNDARY")
        self.assertEqual(len(fixed), 6 * 7 + 5 * 4)
        self.assertTrue(all(line.endswith("1, 3") for line in fixed))
        x = [mesh.x[(int(line.split(",")[0]) - 1) % nx] for line in fixed]
        self.assertAlmostEqual(min(x), 0.40)
        self.assertAlmostEqual(max(x), 0.45)

    def test_width_grading_is_symmetric_and_finer_at_the_edges(self):
        y = solid3d.width_coordinates(8)
        sizes = [b - a for a, b in zip(y[:-1], y[1:])]
        for a, b in zip(sizes, reversed(sizes)):
            self.assertTrue(math.isclose(a, b, rel_tol=1e-12))
        self.assertLess(sizes[0], sizes[3])
        self.assertAlmostEqual(y[4], solid3d.WIDTH / 2, places=15)


if __name__ == "__main__":
    unittest.main()
