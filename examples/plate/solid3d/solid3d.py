#!/usr/bin/env python3
"""The default sensor strip (docs/model.md) as a layered 3D solid in CalculiX, the reference
against which docs/model.md ("Against a layered 3D solid (CalculiX)") checks the plate theories.

    python3 solid3d.py --clamps BITS36 [--per-section 10] [--across 8] [--per-layer 2]
                       [--workdir DIR] [--keep]

prints `position_cm,top_um,mid_um` : |w| every 1 cm on the centreline y = W/2 of the top face
(z = h, the face the LDV sees) and of the mid-plane (z = h/2). BITS36: one 0/1 per clamp,
1 = fixed; clamps 1-18 are the 5 cm sections of edge y = 0 from x = 0, 19-36 those of y = W.

Model (each choice mirrors the built-in model, docs/model.md):
* 0.90 m x 0.04 m x 4 mm, three layers (faces 1.5 mm, E 30 MPa; core 1.0 mm, E 5 MPa;
  nu 0.45), each its own material and `--per-layer` C3D20R bricks thick.
* In plane `--per-section` elements per 5 cm clamp section (uniform, so nodes sit on every
  section boundary) and `--across` elements across the width, graded towards the long edges
  (half uniform, half cosine spacing), where the clamps make the strongest gradients.
* Winkler bed on the bottom face: one grounded SPRING1 per bottom node in z, its stiffness the
  node's share of k * area (the diagonal of the face's consistent matrix scaled to the face's
  area, so every spring is positive; ccx 2.20 has no *FOUNDATION).
* 5 Hz as a static step (examples/sensor-calculix/README.md): the built-in model's inertia acts
  on w only, so it is folded into the bed, k_eff = k_f - omega^2 * rho_avg * h with
  rho_avg * h = sum rho_k h_k. Damping is left out (compare with every loss factor 0).
* A fixed clamp section fixes u, v, w of every node of its side face (the whole thickness) along
  the section, its end nodes included (a node shared with a free section is fixed, as in the
  built-in model). With no clamp fixed, two mid-plane nodes hold the in-plane rigid motions
  (u, v at x = 0 and v at x = L on the centreline), which the z springs do not.
* Load: 0.042 N as a uniform pressure on the 1 cm x 1 cm patch of the top face centred at
  (0.45 m, 0.02 m), applied as exactly integrated nodal forces (*CLOAD), so the patch need not
  fall on element edges.
"""
import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

LENGTH, WIDTH = 0.90, 0.04  # m
SECTIONS = 18  # clamp sections per long edge
LAYERS = [(1.5e-3, 30.0e6, 0.45, 1150.0), (1.0e-3, 5.0e6, 0.45, 1100.0),
          (1.5e-3, 30.0e6, 0.45, 1150.0)]  # bottom to top: thickness, E, nu, rho
FOUNDATION = 5.0e4  # N/m^3
FREQUENCY = 5.0  # Hz
FORCE, LOAD_X, LOAD_Y, PATCH = 0.042, 0.45, 0.02, 0.01  # N, m, m, m
OUTPUT_CM = list(range(91))

# C3D20 corner and mid-edge nodes as offsets (i, j, k) on the doubled grid, in ccx's order.
C3D20 = [(0, 0, 0), (2, 0, 0), (2, 2, 0), (0, 2, 0), (0, 0, 2), (2, 0, 2), (2, 2, 2), (0, 2, 2),
         (1, 0, 0), (2, 1, 0), (1, 2, 0), (0, 1, 0), (1, 0, 2), (2, 1, 2), (1, 2, 2), (0, 1, 2),
         (0, 0, 1), (2, 0, 1), (2, 2, 1), (0, 2, 1)]
# The 8-node serendipity face (bottom or top): local (xi, eta) of its nodes in the order above.
FACE8 = [(-1, -1), (1, -1), (1, 1), (-1, 1), (0, -1), (1, 0), (0, 1), (-1, 0)]
FACE8_OFFSETS = [(0, 0), (2, 0), (2, 2), (0, 2), (1, 0), (2, 1), (1, 2), (0, 1)]


def serendipity(xi, eta):
    """The 8 shape functions of the serendipity quadrilateral at (xi, eta)."""
    n = []
    for a, b in FACE8:
        if a != 0 and b != 0:
            n.append(0.25 * (1 + a * xi) * (1 + b * eta) * (a * xi + b * eta - 1))
        elif a == 0:
            n.append(0.5 * (1 - xi * xi) * (1 + b * eta))
        else:
            n.append(0.5 * (1 + a * xi) * (1 - eta * eta))
    return np.array(n)


GAUSS3 = [(-math.sqrt(0.6), 5.0 / 9.0), (0.0, 8.0 / 9.0), (math.sqrt(0.6), 5.0 / 9.0)]


def face_integral(u0, u1, v0, v1):
    """Integral of the 8 shape functions over the part [u0, u1] x [v0, v1] of the reference
    square, per unit reference area (exact: they are quadratic in each variable)."""
    total = np.zeros(8)
    for gu, wu in GAUSS3:
        for gv, wv in GAUSS3:
            xi = 0.5 * (u0 + u1) + 0.5 * (u1 - u0) * gu
            eta = 0.5 * (v0 + v1) + 0.5 * (v1 - v0) * gv
            total += wu * wv * serendipity(xi, eta) * 0.25 * (u1 - u0) * (v1 - v0)
    return total / 4.0  # the reference square's area is 4


def lumped_weights():
    """Diagonal of the face's consistent matrix int N_i N_j, scaled to sum 1 (row sums would give
    negative corner springs for the serendipity face)."""
    diag = np.zeros(8)
    for gu, wu in GAUSS3:
        for gv, wv in GAUSS3:
            n = serendipity(gu, gv)
            diag += wu * wv * n * n
    return diag / diag.sum()


def width_coordinates(across):
    """Corner y coordinates: half uniform, half cosine spacing (finer at the long edges)."""
    t = np.linspace(0.0, 1.0, across + 1)
    return WIDTH * (0.5 * t + 0.5 * (1.0 - np.cos(math.pi * t)) / 2.0)


def thickness_coordinates(per_layer):
    z, out = 0.0, [0.0]
    for t, _, _, _ in LAYERS:
        out += [z + t * (k + 1) / per_layer for k in range(per_layer)]
        z += t
    return np.array(out)


def doubled(corners):
    """Corner coordinates plus the mid-points: the coordinates of the doubled node grid."""
    out = np.empty(2 * len(corners) - 1)
    out[0::2] = corners
    out[1::2] = 0.5 * (corners[:-1] + corners[1:])
    return out


class Mesh:
    def __init__(self, per_section, across, per_layer):
        self.nx, self.ny, self.nz = SECTIONS * per_section, across, len(LAYERS) * per_layer
        self.per_section, self.per_layer = per_section, per_layer
        self.x = doubled(np.linspace(0.0, LENGTH, self.nx + 1))
        self.y = doubled(width_coordinates(across))
        self.z = doubled(thickness_coordinates(per_layer))

    def node(self, i, j, k):
        return 1 + i + len(self.x) * (j + len(self.y) * k)

    @staticmethod
    def used(i, j, k):
        return (i % 2) + (j % 2) + (k % 2) <= 1  # C3D20 has no face- or body-centre nodes

    def index_of(self, coords, value):
        k = int(np.argmin(np.abs(coords - value)))
        if abs(coords[k] - value) > 1e-9:
            sys.exit(f"no node at {value} m: choose a mesh with nodes every 1 cm and on y = W/2")
        return k


def effective_foundation():
    omega = 2.0 * math.pi * FREQUENCY
    rho_h = sum(t * r for t, _, _, r in LAYERS)
    return FOUNDATION - omega * omega * rho_h  # N/m^3: the w-inertia folded into the bed


def lines(items, per_line=16):
    items = list(items)
    return [", ".join(map(str, items[s:s + per_line])) for s in range(0, len(items), per_line)]


def write_deck(path, clamps, mesh):
    m = mesh
    out = ["*HEADING", "combabc sensor strip as a layered 3D solid (examples/plate/solid3d)",
           "*NODE, NSET=NALL"]
    for k in range(len(m.z)):
        for j in range(len(m.y)):
            for i in range(len(m.x)):
                if m.used(i, j, k):
                    out.append(f"{m.node(i, j, k)}, {m.x[i]:.12g}, {m.y[j]:.12g}, {m.z[k]:.12g}")
    # Bricks, one element set per layer.
    number = 0
    for layer in range(len(LAYERS)):
        out.append(f"*ELEMENT, TYPE=C3D20R, ELSET=LAYER{layer + 1}")
        for ez in range(layer * m.per_layer, (layer + 1) * m.per_layer):
            for ey in range(m.ny):
                for ex in range(m.nx):
                    number += 1
                    ids = [m.node(2 * ex + a, 2 * ey + b, 2 * ez + c) for a, b, c in C3D20]
                    # ccx reads an element over continuation lines of at most 16 entries.
                    out.append(f"{number}, " + ", ".join(map(str, ids[:15])) + ",")
                    out.append(", ".join(map(str, ids[15:])))
    for layer, (_, e, nu, _) in enumerate(LAYERS):
        out += [f"*MATERIAL, NAME=M{layer + 1}", "*ELASTIC", f"{e:.9g}, {nu}",
                f"*SOLID SECTION, ELSET=LAYER{layer + 1}, MATERIAL=M{layer + 1}"]
    # Winkler bed: grounded springs on the bottom face's nodes (k = 0).
    k_eff = effective_foundation()
    weights = lumped_weights()
    stiffness = {}
    for ey in range(m.ny):
        for ex in range(m.nx):
            area = (m.x[2 * ex + 2] - m.x[2 * ex]) * (m.y[2 * ey + 2] - m.y[2 * ey])
            for (a, b), w in zip(FACE8_OFFSETS, weights):
                n = m.node(2 * ex + a, 2 * ey + b, 0)
                stiffness[n] = stiffness.get(n, 0.0) + k_eff * area * w
    first_spring = number + 1
    out.append("*ELEMENT, TYPE=SPRING1, ELSET=BED")
    springs = {}
    for offset, n in enumerate(sorted(stiffness)):
        out.append(f"{first_spring + offset}, {n}")
        # ccx takes one stiffness per *SPRING set: group the nodes by their value.
        springs.setdefault(float(f"{stiffness[n]:.10g}"), []).append(first_spring + offset)
    for g, (value, elements) in enumerate(sorted(springs.items())):
        out += [f"*ELSET, ELSET=BED{g}"] + lines(elements)
        out += [f"*SPRING, ELSET=BED{g}", "3", f"{value:.10g}"]
    # Fixed clamp sections: every node of the side face along the section.
    fixed = set()
    for c, state in enumerate(clamps):
        if state:
            j = 0 if c < SECTIONS else len(m.y) - 1
            s = c % SECTIONS
            for i in range(2 * s * m.per_section, 2 * (s + 1) * m.per_section + 1):
                fixed.update(m.node(i, j, k) for k in range(len(m.z)) if m.used(i, j, k))
    out.append("*BOUNDARY")
    out += [f"{n}, 1, 3" for n in sorted(fixed)]
    jc = m.index_of(m.y, WIDTH / 2)
    kc = m.index_of(m.z, sum(t for t, _, _, _ in LAYERS) / 2)
    if not fixed:  # only springs in z: hold the in-plane rigid motions
        out += [f"{m.node(0, jc, kc)}, 1, 2", f"{m.node(len(m.x) - 1, jc, kc)}, 2, 2"]
    # Output lines: the centreline of the top face and of the mid-plane, every 1 cm.
    top = len(m.z) - 1
    columns = [m.index_of(m.x, 0.01 * cm) for cm in OUTPUT_CM]
    for name, k in (("TOPLINE", top), ("MIDLINE", kc)):
        out += [f"*NSET, NSET={name}"] + lines(m.node(i, jc, k) for i in columns)
    # Load: the patch pressure as nodal forces integrated over each top face's share of it.
    pressure = FORCE / (PATCH * PATCH)
    forces = {}
    x0, x1 = LOAD_X - PATCH / 2, LOAD_X + PATCH / 2
    y0, y1 = LOAD_Y - PATCH / 2, LOAD_Y + PATCH / 2
    for ey in range(m.ny):
        ya, yb = m.y[2 * ey], m.y[2 * ey + 2]
        for ex in range(m.nx):
            xa, xb = m.x[2 * ex], m.x[2 * ex + 2]
            lo_x, hi_x, lo_y, hi_y = max(xa, x0), min(xb, x1), max(ya, y0), min(yb, y1)
            if hi_x <= lo_x or hi_y <= lo_y:
                continue
            ref = lambda v, a, b: 2.0 * (v - a) / (b - a) - 1.0  # noqa: E731
            share = face_integral(ref(lo_x, xa, xb), ref(hi_x, xa, xb), ref(lo_y, ya, yb),
                                  ref(hi_y, ya, yb))
            for (a, b), s in zip(FACE8_OFFSETS, share):
                n = m.node(2 * ex + a, 2 * ey + b, top)
                forces[n] = forces.get(n, 0.0) - pressure * (xb - xa) * (yb - ya) * s
    out += ["*STEP", "*STATIC", "*CLOAD"]
    out += [f"{n}, 3, {f:.12g}" for n, f in sorted(forces.items())]
    out += ["*NODE PRINT, NSET=TOPLINE", "U", "*NODE PRINT, NSET=MIDLINE", "U", "*END STEP"]
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(out) + "\n")
    return sum(forces.values())


def read_sets(path):
    """{set name: {node: |uz|}} from ccx's .dat ('displacements (vx,vy,vz) for set NAME ...')."""
    sets, current = {}, None
    with open(path, encoding="utf-8") as f:
        for text in f:
            parts = text.split()
            if "displacements" in text and "for set" in text:
                current = sets.setdefault(parts[parts.index("set") + 1], {})
            elif current is not None and len(parts) == 4 and parts[0].isdigit():
                current[int(parts[0])] = abs(float(parts[3]))
    return sets


def simulate(clamps, mesh, workdir, threads=1):
    total_force = write_deck(os.path.join(workdir, "strip.inp"), clamps, mesh)
    if abs(abs(total_force) - FORCE) > 1e-9 * FORCE:
        sys.exit(f"load integration: {total_force} N instead of {FORCE} N")
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), CCX_NPROC_EQUATION_SOLVER=str(threads))
    start = time.monotonic()
    run = subprocess.run(["ccx", "-i", "strip"], cwd=workdir, env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, check=False)
    seconds = time.monotonic() - start
    if run.returncode != 0 or "ERROR" in run.stdout:
        tail = [t for t in run.stdout.splitlines() if t.strip()][-3:] or ["no output"]
        sys.exit(f"ccx failed (status {run.returncode}): {' | '.join(tail)}")
    sets = read_sets(os.path.join(workdir, "strip.dat"))
    profiles = []
    for name in ("TOPLINE", "MIDLINE"):
        values = [sets.get(name, {})[n] for n in sorted(sets.get(name, {}))]
        if len(values) != len(OUTPUT_CM):
            sys.exit(f"strip.dat: {len(values)} values for {name}; expected {len(OUTPUT_CM)}")
        profiles.append(values)  # node numbers grow with x along a line
    return profiles[0], profiles[1], seconds


def parse_clamps(text):
    if len(text) != 2 * SECTIONS or set(text) - {"0", "1"}:
        sys.exit(f"--clamps wants {2 * SECTIONS} characters 0/1")
    return [int(c) for c in text]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--clamps", required=True, help="36 x 0/1, 1 = clamp fixed")
    p.add_argument("--per-section", type=int, default=10, help="elements along x per 5 cm")
    p.add_argument("--across", type=int, default=8, help="elements across the width")
    p.add_argument("--per-layer", type=int, default=2, help="elements through each layer")
    p.add_argument("--threads", type=int, default=1, help="ccx threads (OMP_NUM_THREADS)")
    p.add_argument("--workdir", help="folder for the deck and ccx's files (default: a temporary one)")
    p.add_argument("--keep", action="store_true", help="keep the temporary folder")
    a = p.parse_args()
    if a.per_section % 5 or a.across < 2 or a.per_layer < 1:
        sys.exit("--per-section must be a multiple of 5 (nodes every 1 cm); --across >= 2")
    mesh = Mesh(a.per_section, a.across, a.per_layer)
    workdir = a.workdir or tempfile.mkdtemp(prefix="solid3d-")
    os.makedirs(workdir, exist_ok=True)
    try:
        top, mid, seconds = simulate(parse_clamps(a.clamps), mesh, workdir, a.threads)
    finally:
        if not a.workdir and not a.keep:
            shutil.rmtree(workdir, ignore_errors=True)
    print(f"# ccx {seconds:.1f} s wall, mesh {mesh.nx} x {mesh.ny} x {mesh.nz} C3D20R",
          file=sys.stderr)
    print("position_cm,top_um,mid_um")
    for cm, t, m in zip(OUTPUT_CM, top, mid):
        print(f"{cm},{t * 1e6:.6g},{m * 1e6:.6g}")


if __name__ == "__main__":
    main()
