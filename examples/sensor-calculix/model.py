#!/usr/bin/env python3
"""The default sensor strip (docs/model.md) as a CalculiX shell model, for combabc's command
simulator (docs/simulators.md, "Command simulator").

    python3 model.py PARAMS.json        # in the call's folder: writes strip.inp, runs ccx,
                                        # prints |w| on the top centreline, one value a line
    python3 model.py --clamps BITS36    # the same for a full 36-clamp configuration
                                        # ('1' = clamp k fixed), for comparisons

The bits of this example's calibration are two tied clamp pairs: clamp 9 with its facing clamp 27
(40-45 cm) and clamp 10 with clamp 28 (45-50 cm), the sections on either side of the load. Every
other clamp is FIXED_OTHERS (free: the strip is held only by its bed and the two pairs). A
PARAMS.json with 36 bits is read as every clamp's state instead, as the built-in sensor reads its
bits (examples/sensor-multifidelity: the same bit vector for both models, ties in the config).

Model (each choice mirrors the built-in model's defaults, docs/model.md):
* 0.90 m x 0.04 m strip, S4 shells (ccx expands them to C3D8I bricks), 0.5 cm x 0.5 cm elements
  (180 x 8), so every clamp section is 10 elements long and the 1 cm x 1 cm patch is 2 x 2.
* The three-layer laminate as one equivalent isotropic layer of thickness h = 4 mm whose bending
  stiffness equals the laminate's D11 about its neutral plane (exact for equal Poisson ratios).
* Winkler foundation: one SPRING1 element per node in z, stiffness k * tributary area.
* 5 Hz as a static problem: the built-in model's harmonic equation is
  (K + (k_f - omega^2 rho h) M) w = f with hysteretic damping; here the inertia is folded into the
  foundation (k = k_f - omega^2 rho h, exact for the w-only inertia the plate model has) and the
  loss factors (0.10-0.15; they change |w| by well under 1 % this far below the 16.7 Hz
  foundation resonance) are neglected. No eigenmodes are needed, so one run stays well under 1 s.
* A fixed clamp section fixes all six dofs of its edge nodes, section ends included (a node
  shared by a fixed and a free section is fixed, as in the built-in model).
* In-plane dofs (1, 2) are fixed everywhere: the symmetric laminate under a transverse load has
  no membrane response, and without a fixed clamp the strip would otherwise float in its plane.
* Load: 0.04 N as a 400 Pa pressure on the 1 cm x 1 cm patch centred at (0.45 m, 0.02 m).
* Output: |w| at x = 0, 0.01, ..., 0.90 m on y = 0.02 m (the centreline; shell w is constant
  through the thickness), read from *NODE PRINT in strip.dat.
"""
import json
import math
import os
import subprocess
import sys

LENGTH, WIDTH = 0.90, 0.04  # m
NX, NY = 180, 8  # elements along and across
CLAMPS_PER_EDGE = 18
LAYERS = [(1.5e-3, 30.0e6, 0.45, 1150.0), (1.0e-3, 5.0e6, 0.45, 1100.0),
          (1.5e-3, 30.0e6, 0.45, 1150.0)]  # bottom to top: thickness, E, nu, rho
FOUNDATION = 5.0e4  # N/m^3
FREQUENCY = 5.0  # Hz
FORCE, LOAD_X, PATCH = 0.04, 0.45, 0.01  # N, m, m
FREE_BITS = [(9, 27), (10, 28)]  # the calibrated tied pairs (1-based clamp numbers)
FIXED_OTHERS = False  # the state of every other clamp
OUTPUT_X = [0.01 * i for i in range(91)]


def equivalent_layer():
    """Thickness, Young's modulus, Poisson ratio and density of the single layer with the
    laminate's h, D11 and rho h."""
    h = sum(t for t, _, _, _ in LAYERS)
    z, first, weight = 0.0, 0.0, 0.0
    for t, e, nu, _ in LAYERS:
        q = e / (1.0 - nu * nu)
        first += q * ((z + t) ** 2 - z ** 2) / 2.0
        weight += q * t
        z += t
    zn = first / weight
    d, z = 0.0, 0.0
    for t, e, nu, _ in LAYERS:
        q = e / (1.0 - nu * nu)
        d += q * ((z + t - zn) ** 3 - (z - zn) ** 3) / 3.0
        z += t
    nu = LAYERS[0][2]
    e = 12.0 * d * (1.0 - nu * nu) / h ** 3
    rho = sum(t * r for t, _, _, r in LAYERS) / h
    return h, e, nu, rho


def node(i, j):
    return j * (NX + 1) + i + 1


def clamps_from_bits(bits):
    if len(bits) == 2 * CLAMPS_PER_EDGE:
        return list(bits)  # every clamp's state, clamp 1 first
    if len(bits) != len(FREE_BITS):
        sys.exit(f"PARAMS.json: {len(bits)} bits; expected {len(FREE_BITS)} (the tied pairs) "
                 f"or {2 * CLAMPS_PER_EDGE} (every clamp)")
    clamps = [1 if FIXED_OTHERS else 0] * (2 * CLAMPS_PER_EDGE)
    for bit, pair in zip(bits, FREE_BITS):
        for k in pair:
            clamps[k - 1] = bit
    return clamps


def write_deck(path, clamps):
    h, e, nu, rho = equivalent_layer()
    omega = 2.0 * math.pi * FREQUENCY
    k_eff = FOUNDATION - omega * omega * rho * h  # N/m^3: inertia folded into the bed
    dx, dy = LENGTH / NX, WIDTH / NY
    out = ["*HEADING", "combabc sensor strip (examples/sensor-calculix)", "*NODE, NSET=NALL"]
    for j in range(NY + 1):
        for i in range(NX + 1):
            out.append(f"{node(i, j)}, {i * dx:.9g}, {j * dy:.9g}, 0")
    out.append("*ELEMENT, TYPE=S4, ELSET=PLATE")
    for j in range(NY):
        for i in range(NX):
            out.append(f"{j * NX + i + 1}, {node(i, j)}, {node(i + 1, j)}, "
                       f"{node(i + 1, j + 1)}, {node(i, j + 1)}")
    out += ["*MATERIAL, NAME=LAMINATE", "*ELASTIC", f"{e:.9g}, {nu}",
            "*SHELL SECTION, ELSET=PLATE, MATERIAL=LAMINATE", f"{h:.9g}"]
    # Winkler bed: one grounded spring per node, stiffness k * tributary area.
    first_spring = NX * NY + 1
    out.append("*ELEMENT, TYPE=SPRING1, ELSET=BED")
    for j in range(NY + 1):
        for i in range(NX + 1):
            out.append(f"{first_spring + node(i, j) - 1}, {node(i, j)}")
    # ccx takes one stiffness per *SPRING set, so nodes are grouped by tributary area.
    groups = {}
    for j in range(NY + 1):
        for i in range(NX + 1):
            area = dx * dy * (0.5 if i in (0, NX) else 1.0) * (0.5 if j in (0, NY) else 1.0)
            groups.setdefault(area, []).append(first_spring + node(i, j) - 1)
    for n, (area, elements) in enumerate(sorted(groups.items())):
        out.append(f"*ELSET, ELSET=BED{n}")
        out += [", ".join(map(str, elements[s:s + 16])) for s in range(0, len(elements), 16)]
        out += [f"*SPRING, ELSET=BED{n}", "3", f"{k_eff * area:.9g}"]
    # Fixed clamp sections: all dofs of their edge nodes; in-plane dofs everywhere.
    per_section = NX // CLAMPS_PER_EDGE
    fixed = set()
    for k, state in enumerate(clamps):
        if state:
            j = 0 if k < CLAMPS_PER_EDGE else NY
            s = k % CLAMPS_PER_EDGE
            fixed.update(node(i, j) for i in range(s * per_section, (s + 1) * per_section + 1))
    out += ["*BOUNDARY", "NALL, 1, 2"]
    out += [f"{n}, 1, 6" for n in sorted(fixed)]
    # Centreline output nodes, every 1 cm.
    centre = NY // 2
    step = round(0.01 / dx)
    out.append("*NSET, NSET=LINE")
    line = [node(i * step, centre) for i in range(len(OUTPUT_X))]
    out += [", ".join(map(str, line[s:s + 16])) for s in range(0, len(line), 16)]
    # Patch load: a pressure on the elements inside the 1 cm x 1 cm patch.
    patch = [j * NX + i + 1 for j in range(NY) for i in range(NX)
             if abs((i + 0.5) * dx - LOAD_X) < PATCH / 2 and abs((j + 0.5) * dy - WIDTH / 2) < PATCH / 2]
    pressure = FORCE / (PATCH * PATCH)
    out += ["*STEP", "*STATIC", "*DLOAD"]
    out += [f"{el}, P, {-pressure:.9g}" for el in patch]  # S4 P acts against the normal (+z)
    out += ["*NODE PRINT, NSET=LINE", "U", "*END STEP"]
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(out) + "\n")


def read_displacements(path):
    """|w| of the LINE nodes in node order from ccx's .dat (lines: node ux uy uz)."""
    values = {}
    with open(path, encoding="utf-8") as f:
        for text in f:
            parts = text.split()
            if len(parts) == 4 and parts[0].isdigit():
                values[int(parts[0])] = abs(float(parts[3]))
    return [values[n] for n in sorted(values)]


def simulate(clamps, workdir="."):
    write_deck(os.path.join(workdir, "strip.inp"), clamps)
    # ccx writes strip.dat/.frd/.sta/.cvg beside the deck; OMP_NUM_THREADS=1 keeps one run on one
    # core (combabc runs one process per executor thread).
    env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_EQUATION_SOLVER="1")
    run = subprocess.run(["ccx", "-i", "strip"], cwd=workdir, env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, check=False)
    if run.returncode != 0 or "ERROR" in run.stdout:
        tail = [t for t in run.stdout.splitlines() if t.strip()][-1:] or ["no output"]
        sys.exit(f"ccx failed (status {run.returncode}): {tail[0]}")
    values = read_displacements(os.path.join(workdir, "strip.dat"))
    if len(values) != len(OUTPUT_X):
        sys.exit(f"strip.dat: {len(values)} centreline values; expected {len(OUTPUT_X)}")
    return values


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--clamps":
        clamps = [int(c) for c in sys.argv[2]]
        if len(clamps) != 2 * CLAMPS_PER_EDGE or set(clamps) - {0, 1}:
            sys.exit("--clamps wants 36 characters 0/1")
    elif len(sys.argv) == 2:
        with open(sys.argv[1], encoding="utf-8") as f:
            clamps = clamps_from_bits(json.load(f)["bits"])
    else:
        sys.exit(__doc__)
    for value in simulate(clamps):
        print(repr(value))


if __name__ == "__main__":
    main()
