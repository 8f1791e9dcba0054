"""Plots the server's CPU use over time for a request run to its end and the same request sent
with a 100 ms deadline (scripts/bench-cancel writes the samples)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def read(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [float(r["t_s"]) for r in rows], [float(r["cpu_percent"]) for r in rows]


def idle_after(t, cpu, start, threshold=10.0):
    """The first time after `start` from which the CPU stays under `threshold` percent."""
    for i in range(len(t)):
        if t[i] >= start and all(c < threshold for c in cpu[i:]):
            return t[i]
    return None


full, deadline, out = sys.argv[1:4]
tf, cf = read(full)
td, cd = read(deadline)
idle = idle_after(td, cd, 0.1)
fig, ax = plt.subplots(figsize=(8, 4.2), dpi=110)
ax.plot(tf, cf, label="run to its end (no deadline)", color="tab:gray")
ax.plot(td, cd, label="same request, 100 ms deadline", color="tab:red")
ax.axvline(0.1, color="tab:red", linestyle=":", linewidth=1)
ax.annotate("deadline", (0.1, 205), color="tab:red", fontsize=9, xytext=(4, 0),
            textcoords="offset points")
if idle is not None:
    ax.axvline(idle, color="black", linestyle="--", linewidth=1)
    ax.annotate(f"idle (<10%) from {idle:.2f} s", (idle, 180), fontsize=9, xytext=(4, 0),
                textcoords="offset points")
ax.set_xlabel("time since the request was sent (s)")
ax.set_ylabel("shadow-server CPU use (% of one core)")
ax.set_ylim(0, 220)
ax.set_xlim(0, max(tf[-1] if tf else 1, td[-1] if td else 1))
ax.set_title("8192² map, 7680×4320 camera, PCSS 64/64 on 2 cores: cancellation stops the work")
ax.grid(alpha=0.3)
ax.legend(loc="upper right")
fig.tight_layout()
fig.savefig(out)
print(f"idle after the deadline: {idle:.2f} s" if idle is not None else "never idle")
