#!/usr/bin/env python3
"""A combabc worker (protocol combabc-worker 2, docs/simulators.md): copy it, replace simulate()."""
import math
import sys

COORDINATES = [0.03 * j for j in range(21)]  # metres; the config's [simulator.outputs]
CENTRES = [0.05 + 0.1 * k for k in range(6)]  # one support per bit (1 = fixed)


def simulate(bits, reals):
    return [0.05 + sum(math.exp(-((x - c) / 0.06) ** 2)
                       for b, c in zip(bits, CENTRES) if b == 0) for x in COORDINATES]


print("combabc-worker 2", len(COORDINATES), "example-supports 1.0", flush=True)
for line in sys.stdin:  # one request per line: "<id> <bits as 0/1> <real> ..."
    request_id, bits, *reals = line.split()  # every answer starts with the request's id
    try:
        values = simulate([int(b) for b in bits], [float(r) for r in reals])
        print(request_id, "ok", *(repr(v) for v in values), flush=True)
    except Exception as error:  # this candidate failed; the worker goes on
        print(request_id, "error", str(error).replace("\n", " "), flush=True)
