#!/usr/bin/python3
# Plots docs/bench/csm_ringing.png (run from the repository root with Debian's python3).
# The reconstructed occlusion test of CSM (kernels/csm.cl) across a depth step, with and without
# the ringing controls: M = 8 terms, receiver depth minus occluder depth in linear [0, 1] depth
# (the basis holds half of it).
import math
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

def occluded(t_lin, m, damping):
    t = 0.5 * t_lin
    return 0.5 + sum(2 * math.exp(-damping * (k / m) ** 2) / (math.pi * (2 * k - 1)) *
                     math.sin(math.pi * (2 * k - 1) * t) for k in range(1, m + 1))

m = 8
xs = [i / 1000 - 1 for i in range(2001)]
fig, ax = plt.subplots(figsize=(7, 4))
ax.plot(xs, [0 if x < 0 else 1 for x in xs], "k:", label="exact test H(d - z)")
ax.plot(xs, [occluded(x, m, 0) for x in xs], label="M = 8, no damping")
ax.plot(xs, [occluded(x, m, 1) for x in xs], label="M = 8, damping 1")
off, scale = 0.25 / m, 4.0
ax.plot(xs, [min(1, max(0, 0.5 + scale * (occluded(x - off, m, 2) - 0.5))) for x in xs],
        label="damping 2, offset 0.25/M, scale 4 (the defaults)")
ax.set_xlabel("receiver depth - occluder depth (linear light depth, 1 = the map's range)")
ax.set_ylabel("occluded fraction (1 - visibility)")
ax.set_title("CSM reconstruction across a depth step: ringing with and without controls")
ax.grid(alpha=0.3)
ax.legend(loc="upper left", fontsize=8)
fig.tight_layout()
fig.savefig("docs/bench/csm_ringing.png", dpi=90)
