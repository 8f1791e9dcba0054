"""Draws shadow-virtual-bench's trade (issue 53) from its CSV (--csv): per standard sun view, the
misclassified share of pixels against the pages a virtual map draws as its LOD bias goes from -1
(finer) to +1 (coarser), beside the dense maps of the same view as horizontal lines.
Usage: plot_virtual.py CSV OUT_PNG"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import matplotlib.ticker

DENSE = [("uniform", "2048", "#9ecae1", "uniform 2048²"), ("uniform", "4096", "#4292c6",
                                                             "uniform 4096²"),
         ("uniform", "8192", "#08306b", "uniform 8192²"), ("psm", "1024", "#dd8452", "PSM 1024²"),
         ("lispsm", "1024", "#55a868", "LiSPSM 1024²")]


def main(path, out):
    rows = list(csv.DictReader(open(path)))
    views = []
    for r in rows:
        if r["view"] not in views:
            views.append(r["view"])
    cols = 4
    rows_n = (len(views) + cols - 1) // cols
    fig, axes = plt.subplots(rows_n, cols, figsize=(4.2 * cols, 3.4 * rows_n), squeeze=False)
    for k, view in enumerate(views):
        ax = axes[k // cols][k % cols]
        mine = [r for r in rows if r["view"] == view]
        virt = sorted((float(r["bias"]), float(r["requested"]), float(r["misclassified_pct"]))
                      for r in mine if r["technique"] == "virtual")
        floor = 1e-3
        xs = [max(p, 1) for _, p, _ in virt]
        ys = [max(e, floor) for _, _, e in virt]
        ax.plot(xs, ys, "o-", color="#c44e52", label="virtual 16384² (bias -1 .. +1)")
        for (b, p, e), x, y in zip(virt, xs, ys):
            ax.annotate(f"{b:+g}", (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7)
        for tech, size, colour, label in DENSE:
            for r in mine:
                if r["technique"] == tech and r["size"] == size:
                    ax.axhline(max(float(r["misclassified_pct"]), floor), color=colour, ls="--",
                               lw=1, label=label)
        ax.axvline(1024, color="grey", ls=":", lw=1, label="default pool (1024 pages)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_major_locator(matplotlib.ticker.FixedLocator([32, 64, 128, 256, 512, 1024]))
        ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_title(view, fontsize=10)
        ax.set_xlabel("pages drawn (128² texels each)")
        ax.set_ylabel("misclassified pixels (%)")
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
    for k in range(len(views), rows_n * cols):
        axes[k // cols][k % cols].axis("off")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower right", fontsize=9, frameon=False)
    fig.suptitle("Virtual shadow maps against dense maps: hard visibility against Embree, "
                 "1280x720 sun views (2-core EPYC, PoCL)", fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.96))
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
