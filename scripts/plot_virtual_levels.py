"""Draws a view's virtual levels and pages (issue 53) from shadow-virtual-bench --pictures DIR:
the visibility, each pixel's clipmap level (coloured, labelled by the world size of a texel),
and the borders between the pages the pixels read drawn over the visibility.
Usage: plot_virtual_levels.py DIR VIEW OUT_PNG   (VIEW as the files name it: street_overview)"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np


def load(path):
    raw = open(path, "rb").read()
    w, h, c = np.frombuffer(raw[:12], dtype=np.uint32)
    data = np.frombuffer(raw[12:12 + 4 * w * h * c], dtype=np.float32).reshape(h, w, c)
    view = np.frombuffer(raw[12 + 4 * w * h * c:], dtype=np.float32).reshape(4, 4).T  # column-major
    return data, view


def main(folder, name, out):
    vis, _ = load(f"{folder}/{name}.visibility.f32")
    level, _ = load(f"{folder}/{name}.virtual_level.f32")
    pos, _ = load(f"{folder}/{name}.position.f32")
    windows, light_view = load(f"{folder}/{name}.virtual_windows.f32")
    vis, level, windows = vis[..., 0], level[..., 0], windows[..., 0]
    h, w = vis.shape
    # Each pixel's page: its light-space position over its level's page size, in the level's grid.
    ls = np.einsum("ij,hwj->hwi", light_view[:2, :3], pos) + light_view[:2, 3]
    seen = np.isfinite(level)
    idx = np.where(seen, level, 0).astype(int)
    lvl, texels = windows[idx, 0], windows[idx, 3]
    page = np.floor(ls / (np.exp2(lvl) / texels * 128)[..., None])
    key = np.where(seen[..., None], np.concatenate([idx[..., None], page], axis=-1), np.nan)
    border = np.zeros((h, w), bool)
    for axis in (0, 1):
        d = np.any(np.diff(key, axis=axis) != 0, axis=-1)
        if axis == 0:
            border[1:, :] |= d
        else:
            border[:, 1:] |= d
    border &= seen

    fig, axes = plt.subplots(3, 1, figsize=(9, 14.5))
    axes[0].imshow(np.where(np.isfinite(vis), vis, np.nan), cmap="gray", vmin=0, vmax=1)
    axes[0].set_title("visibility (hard test): 1 lit, 0 shadowed")
    levels = np.unique(windows[:, 0][np.unique(idx[seen])])
    cmap = plt.get_cmap("viridis", len(levels))
    shown = np.where(seen, np.searchsorted(levels, lvl), np.nan)
    im = axes[1].imshow(shown, cmap=cmap, vmin=-0.5, vmax=len(levels) - 0.5)
    bar = fig.colorbar(im, ax=axes[1], ticks=range(len(levels)), fraction=0.03)
    bar.set_ticklabels([f"{2 ** l / windows[0, 3] * 100:.2g} cm" for l in levels])
    bar.set_label("texel of the level a pixel reads (world size)")
    axes[1].set_title("each pixel's clipmap level")
    overlay = np.dstack([np.where(np.isfinite(vis), vis, 0.6)] * 3) * 0.8
    overlay[border] = [1.0, 0.25, 0.2]
    axes[2].imshow(overlay)
    axes[2].set_title(f"borders of the pages the pixels read ({len(np.unique(key[seen], axis=0))} "
                      "pages), over the visibility")
    for ax in axes:
        ax.set_xlabel("pixel x")
        ax.set_ylabel("pixel y")
    fig.suptitle(f"{name.replace('_', '/', 1)}: virtual shadow map, 16384² levels, "
                 f"{w}x{h}", fontsize=12)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    fig.savefig(out, dpi=80)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3])
