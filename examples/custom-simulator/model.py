#!/usr/bin/env python3
"""The command-simulator form of worker.py's model (docs/simulators.md, "Command simulator"):
combabc runs `python3 model.py PARAMS.json` once per candidate; it prints the outputs as CSV."""
import json
import math
import sys

COORDINATES = [0.03 * j for j in range(21)]  # metres; the config's [simulator.outputs]
CENTRES = [0.05 + 0.1 * k for k in range(6)]  # one support per bit (1 = fixed)

with open(sys.argv[1], encoding="utf-8") as f:
    params = json.load(f)  # {"bits": [0, 1, ...], "reals": {"name": value, ...}}
bits = params["bits"]
for x in COORDINATES:
    print(repr(0.05 + sum(math.exp(-((x - c) / 0.06) ** 2)
                          for b, c in zip(bits, CENTRES) if b == 0)))
