"""Draws shadow-bench's plots from its CSV files (scripts/bench-shadow runs both):
  pareto.png      mean wall time per request (log) against mean visibility MAE, one labelled
                  point per ranked variant, the Pareto front joined (variants.csv);
  near_error.png  misclassified rate within 10 m of the eye and over the whole image, per view,
                  for the equal-texel variants (results.csv);
  auto_frames.png the equal-texel variants and AUTO per view over the view and its nudged
                  frames: mean and range of the misclassified rate (results.csv, frames.csv);
  goal_ceiling.png the error goals' views within 1.5x against how closely each candidate's
                  error is predicted, with and without the probe's measures' cost, beside the
                  spreads of today's prediction and of the rate over nudged frames
                  (goal_ceiling.csv).
Usage: plot_bench.py BENCH_DIR [OUT_DIR]   (OUT_DIR defaults to BENCH_DIR)"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import matplotlib.ticker
from matplotlib.text import Text
from matplotlib.transforms import Bbox

EQUAL_TEXELS = ["uniform 2048", "psm 2048", "psm_cube 912", "lispsm 2048"]
COLOURS = {"uniform 2048": "#4c72b0", "psm 2048": "#dd8452", "psm_cube 912": "#55a868",
           "lispsm 2048": "#c44e52"}
NEAR = "<10 m"
AUTO = "auto 2048"


def read(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def place_labels(ax, points):
    """Puts each label near its point where it overlaps no other label or point and stays inside
    the axes, measuring each text as drawn: beside the point first, then further out with a
    leader line; where nothing is free, the spot with the least overlap."""
    fig = ax.figure
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    marks = [ax.transData.transform((x, y)) for (x, y, _) in points]
    dots = [Bbox.from_bounds(px - 7, py - 7, 14, 14) for (px, py) in marks]
    taken = []  # the labels placed so far
    directions = [(1, 0.3), (1, -1), (-1, 0.3), (-1, -1), (0.3, 1), (0.3, -1.6), (-1, 1),
                  (1, 1)]

    def gap(box, mark):  # pixels from a label's box to a point (0 inside)
        dx = max(box.x0 - mark[0], 0.0, mark[0] - box.x1)
        dy = max(box.y0 - mark[1], 0.0, mark[1] - box.y1)
        return (dx * dx + dy * dy) ** 0.5

    def overlap(box, own):  # with the labels so far and every other point's dot
        area = sum(max(0.0, min(box.x1, b.x1) - max(box.x0, b.x0)) *
                   max(0.0, min(box.y1, b.y1) - max(box.y0, b.y0))
                   for b in taken + dots[:own] + dots[own + 1:])
        inside = (max(0.0, min(box.x1, frame.x1) - max(box.x0, frame.x0)) *
                  max(0.0, min(box.y1, frame.y1) - max(box.y0, frame.y0)))
        # A label nearer another point than its own reads as that point's.
        mine = gap(box, marks[own])
        closer = sum(gap(box, m) < mine for k, m in enumerate(marks) if k != own)
        return area + 10 * (box.width * box.height - inside) + 150 * closer

    # The most crowded points choose first: isolated ones find room anywhere.
    def neighbours(i):
        return sum(abs(marks[i][0] - m[0]) < 120 and abs(marks[i][1] - m[1]) < 40 for m in marks)

    order = sorted(range(len(points)), key=lambda i: (-neighbours(i), points[i][0]))
    for i in order:
        x, y, text = points[i]
        best = None
        for radius in (6, 16, 28, 42, 60):
            for (dx, dy) in directions:
                ha = "left" if dx > 0 else "right"
                label = ax.annotate(
                    text, (x, y), textcoords="offset points", fontsize=8, ha=ha, va="center",
                    xytext=(dx * radius, dy * radius * 0.6),
                    arrowprops=dict(arrowstyle="-", color="#999999", lw=0.6,
                                    shrinkA=0, shrinkB=3) if radius > 6 else None)
                # The text alone: an annotation's own extent includes its leader line.
                label.update_positions(renderer)
                box = Text.get_window_extent(label, renderer).expanded(1.05, 1.15)
                cost = overlap(box, i)
                if best is None or cost < best[0]:
                    if best is not None:
                        best[1].remove()
                    best = (cost, label, box)
                else:
                    label.remove()
                if cost == 0:
                    break
            if best[0] == 0:
                break
        taken.append(best[2])


def pareto_plot(variants, out):
    ranked = [v for v in variants if v["ranked"] == "1"]
    fig, ax = plt.subplots(figsize=(10, 6.5), dpi=110)
    for v in ranked:
        front = v["pareto"] == "1"
        ax.scatter(float(v["mean_wall_ms"]), float(v["mean_mae"]), s=60 if front else 30,
                   marker="s" if front else "o", color="#c0392b" if front else "#7f8c8d",
                   zorder=3)
    front = sorted((float(v["mean_wall_ms"]), float(v["mean_mae"]))
                   for v in ranked if v["pareto"] == "1")
    if front:
        ax.plot([p[0] for p in front], [p[1] for p in front], color="#c0392b", lw=1.2,
                label="Pareto front (no variant is both faster and more accurate)", zorder=2)
    ax.scatter([], [], color="#7f8c8d", s=30, label="dominated variant")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.margins(x=0.2, y=0.08)
    # Plain numbers at 1, 2 and 5 of each decade instead of 10^n alone.
    for axis in (ax.xaxis, ax.yaxis):  # a locator per axis: they cannot be shared
        axis.set_major_locator(matplotlib.ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel("mean gRPC wall time per request (ms, log scale)")
    ax.set_ylabel("mean visibility MAE against Embree (log scale; 0 = exact, 1 = all wrong)")
    ax.set_title("shadow-bench: speed against accuracy, mean over the views every ranked "
                 "variant ran on", fontsize=10)
    ax.grid(True, which="both", color="#dddddd", lw=0.6)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=2, fontsize=8)
    fig.tight_layout()
    place_labels(ax, [(float(v["mean_wall_ms"]), float(v["mean_mae"]), v["variant"])
                      for v in ranked])
    fig.savefig(out)


def by_view(rows, variants):
    """The views in the order they come, and each view's rows of `variants` by variant."""
    views, rows_of = [], {}
    for r in rows:
        if r["variant"] not in variants:
            continue
        view = r["scene"] + "/" + r["view"]
        if view not in rows_of:
            views.append(view)
            rows_of[view] = {}
        rows_of[view].setdefault(r["variant"], []).append(r)
    return views, rows_of


def near_plot(results, out):
    views, rows_of = by_view(results, EQUAL_TEXELS)
    rates = {w: {v: (float(r[0]["misclassified " + NEAR]), int(r[0]["px " + NEAR]),
                     float(r[0]["misclassified_rate"])) for v, r in of.items()}
             for w, of in rows_of.items()}
    fig, axes = plt.subplots(1, 2, figsize=(12, 0.42 * len(views) + 1.8), dpi=110, sharey=True)
    height = 0.8 / len(EQUAL_TEXELS)
    for k, v in enumerate(EQUAL_TEXELS):
        ys = [i + (k - 1.5) * height for i in range(len(views))]
        near = [100 * rates[w][v][0] if v in rates[w] and rates[w][v][1] > 0 else 0
                for w in views]
        overall = [100 * rates[w][v][2] if v in rates[w] else 0 for w in views]
        axes[0].barh(ys, near, height, color=COLOURS[v], label=v)
        axes[1].barh(ys, overall, height, color=COLOURS[v], label=v)
    labels = []
    for w in views:
        some = next(iter(rates[w].values()))
        missing = [v.split()[0] for v in EQUAL_TEXELS if v not in rates[w]]
        note = " (no pixel < 10 m)" if some[1] == 0 else ""
        if missing:
            note += " (refused: " + ", ".join(missing) + ")"
        labels.append(w + note)
    axes[0].set_yticks(range(len(views)))
    axes[0].set_yticklabels(labels, fontsize=8)
    axes[0].invert_yaxis()
    axes[0].set_xlabel("misclassified pixels within 10 m of the eye (%)")
    axes[1].set_xlabel("misclassified pixels, whole image (%)")
    for ax in axes:
        ax.grid(True, axis="x", color="#dddddd", lw=0.6)
    axes[0].legend(loc="lower right", fontsize=8, title="~4.2 M texels each", title_fontsize=8)
    fig.suptitle("Near-viewer error per technique at equal texel count, per standard view "
                 "(against Embree shadow rays)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out)


def frames_plot(results, frames, out):
    """Per view, each compared variant's misclassified rate over frame 0 (the view, results.csv)
    and its nudged frames (frames.csv): the mean as a dot, the range as a line."""
    compared = EQUAL_TEXELS + [AUTO]
    views, rows_of = by_view(results + frames, compared)
    rates = {w: {v: [100 * float(r["misclassified_rate"]) for r in rs] for v, rs in of.items()}
             for w, of in rows_of.items()}
    if not any(len(v) > 1 for w in rates.values() for v in w.values()):
        return
    fig, ax = plt.subplots(figsize=(10, 0.5 * len(views) + 1.8), dpi=110)
    height = 0.8 / len(compared)
    colours = dict(COLOURS, **{AUTO: "black"})
    for k, v in enumerate(compared):
        ys, means, lo, hi = [], [], [], []
        for i, w in enumerate(views):
            got = [x for x in rates[w].get(v, []) if x > 0]
            if not got:
                continue
            ys.append(i + (k - (len(compared) - 1) / 2) * height)
            means.append(sum(got) / len(got))
            lo.append(min(got))
            hi.append(max(got))
        ax.hlines(ys, lo, hi, color=colours[v], lw=1.2)
        ax.plot(means, ys, "o" if v != AUTO else "D", color=colours[v], ms=4 if v != AUTO else 5,
                label=v if v != AUTO else "auto 2048 (the server's pick)", ls="none")
    ax.set_xscale("log")
    ax.set_yticks(range(len(views)))
    ax.set_yticklabels(views, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("misclassified pixels, whole image (%, log scale): mean over the frames (dot), "
                  "lowest to highest (line)")
    ax.grid(True, which="both", axis="x", color="#dddddd", lw=0.6)
    ax.legend(loc="lower right", fontsize=8, title="~4.2 M texels each", title_fontsize=8)
    ax.set_title("AUTO against each technique at equal texels, over the view and four frames\n"
                 "with the light turned 0.05° (a point light moved 1 cm), against Embree shadow "
                 "rays", fontsize=10)
    fig.tight_layout()
    fig.savefig(out)


GOAL_COLOURS = ["#4c72b0", "#dd8452", "#55a868", "#c44e52", "#8172b3"]


def ceiling_plot(rows, out):
    curves = [r for r in rows if r["kind"] == "curve"]
    goals = sorted({r["name"] for r in curves})
    spread = {r["name"]: float(r["sigma"]) for r in rows if r["kind"] == "spread"}
    fig, ax = plt.subplots(figsize=(12, 5.5), dpi=110)
    for i, goal in enumerate(goals):
        colour = GOAL_COLOURS[i % len(GOAL_COLOURS)]
        for measures, style in (("1", "-"), ("0", "--")):
            pts = sorted((float(r["sigma"]), 100 * float(r["within"]) / int(r["views"]))
                         for r in curves if r["name"] == goal and r["measures"] == measures)
            ax.plot([p[0] for p in pts], [p[1] for p in pts], style, color=colour, lw=1.4,
                    marker="o", ms=3)
        for r in rows:  # smaller for each goal, so that equal ones show nested
            if r["kind"] == "actual" and r["name"] == goal:
                ax.plot(float(r["sigma"]), 100 * int(r["within"]) / int(r["views"]), "D",
                        color=colour, ms=11 - 2.5 * i, mec="black", zorder=4 + i)
        ax.plot([], [], "-", color=colour, lw=3, label=goal.replace("quality error ", "max_error "))
    ax.plot([], [], "-", color="black", lw=1.4, label="the probe's measures at their cost")
    ax.plot([], [], "--", color="black", lw=1.4, label="the probe's measures free")
    ax.plot([], [], "D", color="white", mec="black", ms=8, label="as the goals ran this sweep")
    lo, hi = spread.get("frames_median", 0), spread.get("frames_mean", 0)
    ax.axvspan(min(lo, hi), max(lo, hi), color="#bbbbbb", alpha=0.5,
               label="the rate's own spread over nudged frames (median to mean)")
    for name, label, ls in (("prediction", "the server's prediction", "-."),
                            ("edge_estimate", "edge-sampling estimate (draws each map)", ":")):
        if name in spread:
            ax.axvline(spread[name], color="#555555", ls=ls, lw=1.2, label=label)
    ax.axhline(90, color="#c0392b", lw=1, label="issue 17's goal: 90% of the views")
    ax.set_xlim(0, max(float(r["sigma"]) for r in curves))
    lowest = min(100 * float(r["within"]) / int(r["views"]) for r in curves)
    ax.set_ylim(max(0, 10 * (lowest // 10) - 10), 102)
    ax.set_xlabel("spread of the predicted error: sd of log(predicted / measured)")
    ax.set_ylabel("views met within 1.5x the cheapest configuration that met the bound (%)")
    ax.set_title("max_error goals replayed with each candidate's error predicted to within a "
                 "spread\n(times known; mean over the draws)", fontsize=10)
    ax.grid(True, color="#dddddd", lw=0.6)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1), fontsize=8)
    fig.tight_layout()
    fig.savefig(out)


def main():
    bench = sys.argv[1]
    out = sys.argv[2] if len(sys.argv) > 2 else bench
    pareto_plot(read(os.path.join(bench, "variants.csv")), os.path.join(out, "pareto.png"))
    results = read(os.path.join(bench, "results.csv"))
    near_plot(results, os.path.join(out, "near_error.png"))
    frames = os.path.join(bench, "frames.csv")
    if os.path.exists(frames):
        frames_plot(results, read(frames), os.path.join(out, "auto_frames.png"))
    ceiling = os.path.join(bench, "goal_ceiling.csv")
    if os.path.exists(ceiling):
        ceiling_plot(read(ceiling), os.path.join(out, "goal_ceiling.png"))


main()
