"""Draws docs/bench/atlas_soft.png from shadow-atlas-bench --images DIR: the 640x360 visibility
of the area-light oracle, PCSS, atlas_sat and atlas_mip (top), and each technique's absolute
error against the oracle (bottom), cropped to the spheres' shadows.
Usage: plot_atlas.py DIR OUT.png"""
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


def load(directory, name):
    return np.fromfile(f"{directory}/{name}.f32", dtype="<f4").reshape(H, W)[CROP]


def main():
    directory, out = sys.argv[1], sys.argv[2]
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


if __name__ == "__main__":
    main()
