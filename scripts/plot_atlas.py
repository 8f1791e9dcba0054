"""Draws the atlas figures of docs/benchmarks.md from shadow-atlas-bench image dumps (640x360
float32 files, NaN where the camera sees nothing).

  plot_atlas.py DIR OUT.png
      the sphere field (shadow-atlas-bench --images DIR): the visibility of the area-light
      oracle, PCSS, atlas_sat and atlas_mip (top), each technique's absolute error (bottom),
      cropped to the spheres' shadows (docs/bench/atlas_soft.png).
  plot_atlas.py --standard BEFORE_DIR AFTER_DIR SCENE_VIEW OUT.png [--crop Y0:Y1,X0:X1]
                [--filter atlas_sat|atlas_mip] [--change TEXT]
      one standard view (shadow-atlas-bench --standard --images DIR, files SCENE_VIEW_NAME.f32)
      before and after a change: the oracle and the filter before and after (top), its absolute
      error before and after with their means (over the seen pixels and over those the oracle
      sees fully lit), and where the error changed (bottom); TEXT names the change in the title."""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

W, H = 640, 360
NAMES = ["oracle", "pcss", "atlas_sat", "atlas_mip"]
TITLES = {"oracle": "area-light oracle (Embree)", "pcss": "PCSS (16 + 32 taps)",
          "atlas_sat": "atlas + SAT", "atlas_mip": "atlas + mips"}
CROP = (slice(150, 330), slice(120, 440))  # rows, columns: the shadows


def load(directory, name, crop=CROP):
    return np.fromfile(f"{directory}/{name}.f32", dtype="<f4").reshape(H, W)[crop]


def sphere_field(directory, out):
    images = {n: load(directory, n) for n in NAMES}
    fig, axes = plt.subplots(2, 4, figsize=(16, 6.4), constrained_layout=True)
    for ax, name in zip(axes[0], NAMES):
        shown = ax.imshow(np.nan_to_num(images[name], nan=1.0), cmap="gray", vmin=0, vmax=1)
        ax.set_title(TITLES[name])
        ax.set_xticks([]), ax.set_yticks([])
    fig.colorbar(shown, ax=axes[0], shrink=0.8, label="visibility (1 lit, 0 shadowed)")
    axes[1][0].axis("off")
    axes[1][0].text(0.5, 0.5, "absolute error against the oracle\n(mean over the crop)",
                    ha="center", va="center", fontsize=12)
    for ax, name in zip(axes[1][1:], NAMES[1:]):
        err = np.abs(images[name] - images["oracle"])
        shown = ax.imshow(np.nan_to_num(err), cmap="magma", vmin=0, vmax=0.5)
        ax.set_title(f"{TITLES[name]}: {np.nanmean(err):.4f}")
        ax.set_xticks([]), ax.set_yticks([])
    fig.colorbar(shown, ax=axes[1], shrink=0.8, label="|visibility error|")
    fig.suptitle("Soft shadows of a 3° sun, 640x360 crop: the atlas filters against PCSS")
    fig.savefig(out, dpi=80)


def standard(before, after, view, out, crop, name, change):
    rows, cols = crop
    oracle = load(after, f"{view}_oracle", crop)
    was, now = load(before, f"{view}_{name}", crop), load(after, f"{view}_{name}", crop)
    lit = oracle == 1.0
    extent = (cols.start, cols.stop, rows.stop, rows.start)  # image pixels, row 0 at the top
    fig, axes = plt.subplots(2, 3, figsize=(15, 2 * 3.6 * (rows.stop - rows.start) /
                                                (cols.stop - cols.start) + 2.2),
                             constrained_layout=True)
    for ax, (title, image) in zip(axes[0], [(TITLES["oracle"], oracle),
                                            (f"{TITLES[name]}, before", was),
                                            (f"{TITLES[name]}, after", now)]):
        shown = ax.imshow(np.nan_to_num(image, nan=1.0), cmap="gray", vmin=0, vmax=1,
                          extent=extent)
        ax.set_title(title)
    fig.colorbar(shown, ax=axes[0], shrink=0.9, label="visibility (1 lit, 0 shadowed)")
    errors = [np.abs(was - oracle), np.abs(now - oracle)]
    for ax, when, err in zip(axes[1], ["before", "after"], errors):
        shown = ax.imshow(np.nan_to_num(err), cmap="magma", vmin=0, vmax=0.5, extent=extent)
        ax.set_title(f"|error| {when}: mean {np.nanmean(err):.4f}, on fully lit "
                     f"{np.nanmean(err[lit]):.4f}", fontsize=10)
    fig.colorbar(shown, ax=axes[1][:2], shrink=0.9, label="|visibility error|")
    gain = np.nan_to_num(errors[0] - errors[1])
    shown = axes[1][2].imshow(gain, cmap="RdBu", vmin=-0.5, vmax=0.5, extent=extent)
    axes[1][2].set_title("|error| before - after (blue: better)", fontsize=10)
    fig.colorbar(shown, ax=axes[1][2], shrink=0.9, label="change of |visibility error|")
    for ax in axes.flat:
        ax.set_xlabel("x (pixels)")
        ax.set_ylabel("y (pixels)")
    fig.suptitle(f"{view.replace('_', ' / ', 1)} against the area-light oracle, 640x360 (crop): "
                 f"{TITLES[name]} before and after {change}")
    fig.savefig(out, dpi=72)


def parse_crop(text):
    y, x = text.split(",")
    y0, y1 = (int(v) for v in y.split(":"))
    x0, x1 = (int(v) for v in x.split(":"))
    return slice(y0, y1), slice(x0, x1)


def main():
    args = sys.argv[1:]
    if args and args[0] == "--standard":
        crop, name = (slice(0, H), slice(0, W)), "atlas_mip"
        change = "keeping to its charts (issue 43)"
        if "--crop" in args:
            at = args.index("--crop")
            crop = parse_crop(args[at + 1])
            del args[at:at + 2]
        if "--filter" in args:
            at = args.index("--filter")
            name = args[at + 1]
            del args[at:at + 2]
        if "--change" in args:
            at = args.index("--change")
            change = args[at + 1]
            del args[at:at + 2]
        standard(args[1], args[2], args[3], args[4], crop, name, change)
    else:
        sphere_field(args[0], args[1])


if __name__ == "__main__":
    main()
