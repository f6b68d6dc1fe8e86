"""How often P(bit = 1) +- 2 SE holds the exact ABC posterior marginal, over seeds, on an 8-bit
linear toy with a rare bit (exact posterior by enumeration): the delta method's SE alone, the
reported one (Wave.marginals_se: the rule of three near 0 and 1, docs/algorithm.md "Monte-Carlo
errors") and the rule of three in the weights' ESS only ("kish"). Measured for issue 35.

    PYTHONPATH=build/python python3 bench/python/probability_error_coverage.py MODE EPS SEEDS N

MODE: mf (a cheap model wrong on bit 3, continuation probabilities 0.5 / 0.2 fixed) or indep
(single fidelity, the independent kernel); EPS: the thresholds, e.g. 6,4,2.5,2.0; SEEDS runs of
N particles per wave."""
import itertools
import sys

import numpy as np

import combabc

d = 8
rng = np.random.default_rng(3)
W = rng.integers(0, 3, size=(6, d)).astype(float)
truth = np.array([1, 0, 1, 1, 0, 0, 1, 0], dtype=np.uint8)
obs = W @ truth
prior = np.array([0.5, 0.3, 0.6, 0.5, 0.15, 0.7, 0.5, 0.03])
eps = [float(x) for x in sys.argv[2].split(",")]
mode = sys.argv[1]
seeds = int(sys.argv[3])
n = int(sys.argv[4])


def expensive(b):
    return W @ b


def cheap(b):
    c = np.array(b, dtype=float)
    c[2] = 1 - c[2]
    return W @ c + 0.3


m = np.zeros(d)
z = 0.0
for bits in itertools.product([0, 1], repeat=d):
    b = np.array(bits)
    p = np.prod(np.where(b == 1, prior, 1 - prior))
    if np.linalg.norm(W @ b - obs) <= eps[-1]:
        z += p
        m += p * b
exact = m / z
print("exact", np.round(exact, 4))
space = combabc.BinarySpace(dimension=d, prior_one=list(prior))
kw = {}
opts = dict(num_waves=len(eps), accepted_per_wave=n, thresholds=eps, threads=1)
if mode == "mf":
    kw["low_fidelity"] = cheap
    opts["multi_fidelity"] = combabc.MultiFidelityOptions(continue_if_accepted=0.5,
                                                          continue_if_rejected=0.2, adapt=False,
                                                          cost_ratio=10)
if mode == "indep":
    opts["proposal"] = combabc.ProposalOptions(kind="independent")
problem = combabc.Problem(space, expensive, obs, **kw)
zs_new, zs_old, rows = [], [], []
for seed in range(1, seeds + 1):
    h = combabc.run(problem, combabc.make_options(seed=seed, **opts))
    w = h.waves[-1]
    wt = w.weight / w.weight.sum()
    p = w.marginals
    old = np.sqrt(((wt[:, None] ** 2) * (w.bits - p) ** 2).sum(axis=0))
    new = w.marginals_se
    raw = wt @ w.bits
    kish = 1 / np.sum(wt ** 2)
    fk = min(3 / kish, 0.5)
    pc = np.clip(raw, 0, 1)
    kse = np.maximum.reduce([old, fk - np.minimum(pc, 1 - pc), np.abs(raw - pc)])
    for k in range(d):
        rows.append((seed, k, exact[k], p[k], old[k], new[k], kse[k]))
rows = np.array(rows)
for label, sel in (("all", np.ones(len(rows), bool)),
                   ("edge(exact<0.1 or >0.9)", (rows[:, 2] < 0.1) | (rows[:, 2] > 0.9))):
    r = rows[sel & (rows[:, 2] > 0) & (rows[:, 2] < 1)]
    for name, col in (("delta", 4), ("floored", 5), ("kish", 6)):
        with np.errstate(divide="ignore", invalid="ignore"):
            zz = (r[:, 3] - r[:, 2]) / r[:, col]
        zz = np.where(np.isnan(zz), 0, zz)
        print(f"{label:24s} {name:8s} n={len(r)} cover|z|<=2: {np.mean(np.abs(zz) <= 2):.3f} "
              f"mean z^2 (finite): {np.mean(zz[np.isfinite(zz)] ** 2):.2f} "
              f"se=0: {np.sum(r[:, col] == 0)} worst |z|: {np.max(np.abs(zz)):.1f}")
