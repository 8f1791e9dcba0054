"""Draws docs/bench/csm_images.png from shadow-csm-images DIR: the hard test and FILTER_CSM at
M = 4, 8, 16 over the sphere field's shadows, with the ringing controls off (top) and at their
defaults (bottom), cropped to the shadows.
Usage: plot_csm_images.py DIR OUT.png"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

W, H = 640, 360
CROP = (slice(150, 330), slice(120, 440))  # rows, columns: the shadows


def load(directory, name):
    return np.fromfile(f"{directory}/{name}.f32", dtype="<f4").reshape(H, W)[CROP]


def main():
    directory, out = sys.argv[1], sys.argv[2]
    fig, axes = plt.subplots(2, 4, figsize=(16, 6.4), constrained_layout=True)
    rows = [("raw", "controls off"), ("controls", "default controls")]
    for r, (suffix, label) in enumerate(rows):
        hard = axes[r][0]
        shown = hard.imshow(np.nan_to_num(load(directory, "hard"), nan=1.0), cmap="gray", vmin=0,
                            vmax=1)
        hard.set_title("hard test (reference)")
        for ax, m in zip(axes[r][1:], (4, 8, 16)):
            ax.imshow(np.nan_to_num(load(directory, f"M{m}_{suffix}"), nan=1.0), cmap="gray",
                      vmin=0, vmax=1)
            ax.set_title(f"CSM M = {m}, {'raw' if suffix == 'raw' else 'controls'}")
        for ax in axes[r]:
            ax.set_xticks([]), ax.set_yticks([])
        axes[r][0].set_ylabel(label, fontsize=12)
    fig.colorbar(shown, ax=axes, shrink=0.6, label="visibility (1 lit, 0 shadowed)")
    fig.suptitle("CSM's ringing in the image (2048 map, 4-texel window). Controls off (damping 0, "
                 "offset 0, scale 1): lit surfaces read half shadowed, the series being 1/2 at\n"
                 "zero depth difference, and the spheres band. Defaults (damping 2, offset "
                 "0.25/M, scale 4): lit is lit; M = 4 still leaks light into shadows.")
    fig.savefig(out, dpi=80)


if __name__ == "__main__":
    main()
