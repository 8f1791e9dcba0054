"""TECHNIQUE_VIRTUAL's pages on the client (PRODUCT_VIRTUAL_PAGES): the pool, one light's page
tables, windows and pixel levels, and the hard test through them, as docs/api.md's "Virtual
shadow maps" lays them out."""

from __future__ import annotations

from typing import Iterable, Union

import numpy as np

from ._client import RenderResult, Texture

PAGE_TEXELS = 128
MAX_SLOPE = 1.0  # the service's cap on the slope bias's depth change per texel (prelude.cl)


class VirtualShadowMap:
    """One light's virtual map from a reply with PRODUCT_VIRTUAL_PAGES: a directional light's
    clipmap, or a spot or point light's mip chains (one face, or six).

        vsm = sc.VirtualShadowMap(result, light=0)       # or result.textures
        levels = vsm.level_of(pixels)                      # (..., 2) x, y -> level index, -1: none
        vis = vsm.visibility(points, levels, normals=n)    # (..., 3) world -> 1 lit, 0 shadowed

    Arrays: `pool` (128 P, 128), `table` (W L, W) of slots (-1: no page), `windows` (L, 4) int64
    rows [level, first page x, first page y, texels] (a mip's: [mip, 0, 0, its texels]), `levels`
    (height, width) int64 (-1: none), `view` (world -> light space; a perspective map's first
    face's view) and `to_ndc` (the first level's world -> texture NDC), float64; `faces` (F, 4, 4)
    float64, each face's world -> mip 0's texture NDC, or None for a directional light."""

    def __init__(self, textures: Union[RenderResult, Iterable[Texture]], light: int = 0):
        if isinstance(textures, RenderResult):
            textures = textures.textures
        by_name = {t.name: t for t in textures}

        def find(base: str, per_light: bool = True) -> Texture:
            # With several lights each per-light texture ends in _light<i>; with one, none does.
            for name in (f"{base}_light{light}", base) if per_light else (base,):
                t = by_name.get(name)
                if t is not None and (name != base or not per_light or t.light == light):
                    return t
            raise KeyError(f"no texture {base!r} for light {light} (have {', '.join(by_name)}): "
                           "ask for PRODUCT_VIRTUAL_PAGES with TECHNIQUE_VIRTUAL")

        pool, windows = find("virtual_pool", per_light=False), find("virtual_windows")
        self.pool = pool.data[..., 0]
        self.table = find("virtual_table").data[..., 0]
        self.windows = windows.data[..., 0].astype(np.int64)
        level = find("virtual_level").data[..., 0]
        self.levels = np.nan_to_num(level, nan=-1).astype(np.int64)
        self.view = windows.world_to_camera.astype(np.float64)
        self.to_ndc = windows.world_to_ndc.astype(np.float64)
        count = len(self.windows)
        if self.windows.shape != (count, 4) or count == 0:
            raise ValueError(f"virtual_windows: shape {windows.data.shape}, expected (L, 4, 1)")
        try:  # a spot or point light's: column-major rows of 16
            rows = find("virtual_faces").data[..., 0].astype(np.float64)
            self.faces = rows.reshape(-1, 4, 4).transpose(0, 2, 1)
        except KeyError:
            self.faces = None
        if self.faces is not None and count % len(self.faces):
            raise ValueError(f"virtual_faces: {len(self.faces)} faces for {count} levels")
        self.mips = count // len(self.faces) if self.faces is not None else count
        pages = int(self.windows[:, 3].max()) // PAGE_TEXELS
        if self.table.shape != (pages * count, pages):
            raise ValueError(f"virtual_table: shape {self.table.shape}, expected "
                             f"({pages * count}, {pages}) for {count} levels of {pages} pages")
        if self.pool.shape[1] != PAGE_TEXELS or self.pool.shape[0] % PAGE_TEXELS:
            raise ValueError(f"virtual_pool: shape {self.pool.shape}, expected (128 P, 128)")

    @property
    def level_count(self) -> int:
        return len(self.windows)

    @property
    def pool_pages(self) -> int:
        return self.pool.shape[0] // PAGE_TEXELS

    def level_of(self, pixel) -> np.ndarray:
        """The level index (0 = finest) that the service's filters read at camera pixel (x, y),
        or at each of an (..., 2) array of them; -1 where the camera sees nothing or no level
        holds the pixel."""
        p = np.asarray(pixel, dtype=np.int64)
        return self.levels[p[..., 1], p[..., 0]]

    @property
    def perspective(self) -> bool:
        return self.faces is not None

    def _project(self, level_index, world_points) -> np.ndarray:
        """(..., 4): each point in clip space of its level index's face (a perspective map's)."""
        i, _ = self._window(level_index)
        m = self.faces[i // self.mips]
        p = np.asarray(world_points, dtype=np.float64)
        return np.einsum("...ij,...j->...i", m, np.concatenate([p, np.ones_like(p[..., :1])], -1))

    def ndc_depth(self, world_points, level_index=0) -> np.ndarray:
        """Each point's NDC depth (what the hard test compares): the one all of a directional
        light's levels share, or that of its level index's face (NaN behind the light)."""
        p = np.asarray(world_points, dtype=np.float64)
        if not self.perspective:
            return p @ self.to_ndc[2, :3] + self.to_ndc[2, 3]
        c = self._project(level_index, p)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(c[..., 3] > 0, c[..., 2] / c[..., 3], np.nan)

    def _window(self, level_index) -> tuple[np.ndarray, np.ndarray]:
        i = np.asarray(level_index, dtype=np.int64)
        if np.any(i >= self.level_count):
            raise ValueError(f"level index {int(i.max())} of {self.level_count} levels")
        valid = i >= 0
        return np.where(valid, i, 0), valid

    def texel(self, level_index, world_points) -> np.ndarray:
        """(..., 2): each point's texel coordinates (x = column, y = row) in the window of its
        level index (broadcast with the points), 0..texels across it."""
        i, _ = self._window(level_index)
        w = self.windows[i].astype(np.float64)
        p = np.asarray(world_points, dtype=np.float64)
        if self.perspective:  # the face's texture NDC times the mip's texels; NaN behind it
            c = self._project(i, p)
            with np.errstate(invalid="ignore", divide="ignore"):
                t = c[..., :2] / c[..., 3:] * w[..., 3:]
            return np.where(c[..., 3:] > 0, t, np.nan)
        ls = p @ self.view[:2, :3].T + self.view[:2, 3]
        # texels / 2^level: a power of two, so this equals dividing by the texel's size.
        scale = w[..., 3] / np.exp2(w[..., 0])
        return ls * scale[..., None] - w[..., 1:3] * PAGE_TEXELS

    def depth_at(self, level_index, world_points) -> np.ndarray:
        """The pool's depth at each point's texel of its level index (broadcast with the points);
        NaN off the level's window, where its page has no slot or the index is -1."""
        i, valid = self._window(level_index)
        t = self.texel(i, world_points)
        texels = self.windows[i, 3]
        with np.errstate(invalid="ignore"):
            inside = valid & np.all((t >= 0) & (t < texels[..., None]), axis=-1)
        ti = np.where(inside[..., None], np.floor(np.nan_to_num(t)), 0).astype(np.int64)
        # Level i's block of W rows holds its pages in rows of its own width (texels / 128).
        width = self.table.shape[1]
        page = ti // PAGE_TEXELS
        flat = page[..., 1] * (texels // PAGE_TEXELS) + page[..., 0]
        slot = self.table[width * i + flat // width, flat % width]
        held = inside & (slot >= 0)
        s = np.where(held, slot, 0).astype(np.int64)
        depth = self.pool[PAGE_TEXELS * s + ti[..., 1] % PAGE_TEXELS, ti[..., 0] % PAGE_TEXELS]
        return np.where(held, depth, np.nan)

    def _perspective_slope(self, i, world_points, normals) -> np.ndarray:
        # The receiver plane's tangents t1 = normalize(n x e) (e = the x axis unless n is close
        # to it) and t2 = n x t1, through the face's projection at the point: pcf.cl's set-up.
        n = np.asarray(normals, dtype=np.float64)
        m = self.faces[i // self.mips]
        c = self._project(i, world_points)
        ex = np.abs(n[..., 0]) < 0.9
        a = np.stack([np.where(ex, 0, -n[..., 2]), np.where(ex, n[..., 2], 0),
                      np.where(ex, -n[..., 1], n[..., 0])], -1)
        a /= np.linalg.norm(a, axis=-1, keepdims=True)
        b = np.cross(n, a)
        m1 = np.einsum("...ij,...j->...i", m[..., :3], a)
        m2 = np.einsum("...ij,...j->...i", m[..., :3], b)
        with np.errstate(invalid="ignore", divide="ignore"):
            s = c[..., :3] / c[..., 3:]
            d1 = (m1[..., :3] - s * m1[..., 3:]) / c[..., 3:]
            d2 = (m2[..., :3] - s * m2[..., 3:]) / c[..., 3:]
            det = (d1[..., 0] * d2[..., 1] - d2[..., 0] * d1[..., 1]) * self.windows[i, 3]
            gx = (d1[..., 2] * d2[..., 1] - d2[..., 2] * d1[..., 1]) / det
            gy = (d1[..., 0] * d2[..., 2] - d2[..., 0] * d1[..., 2]) / det
            slope = np.abs(np.clip(gx, -MAX_SLOPE, MAX_SLOPE)) + np.abs(
                np.clip(gy, -MAX_SLOPE, MAX_SLOPE))
        finite = np.isfinite(gx) & np.isfinite(gy) & (det != 0)
        return np.where(finite, np.minimum(slope, MAX_SLOPE), MAX_SLOPE)

    def depth_slope(self, level_index, normals, world_points=None) -> np.ndarray:
        """|dz/du| + |dz/dv|: the NDC depth change per texel of the level index across a receiver
        plane of world normal `normals`, capped at MAX_SLOPE (edge-on planes get it), as the
        service's slope bias measures it. A perspective map's depends on where the plane is:
        `world_points` then."""
        i, _ = self._window(level_index)
        if self.perspective:
            return self._perspective_slope(i, world_points, normals)
        n = np.asarray(normals, dtype=np.float64) @ self.view[:3, :3].T
        # Orthographic levels: NDC depth is linear in light-space z, the same for every level.
        dz = abs(self.to_ndc[2, :3] @ self.view[2, :3])
        texel = np.exp2(self.windows[i, 0].astype(np.float64)) / self.windows[i, 3]
        across = np.abs(n[..., 0]) + np.abs(n[..., 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = dz * texel * across / np.abs(n[..., 2])
        return np.where(np.isfinite(slope), np.minimum(slope, MAX_SLOPE), MAX_SLOPE)

    def visibility(self, world_points, level_indices, bias=2e-5, bias_slope=0.75,
                   normals=None) -> np.ndarray:
        """The hard test: 1 where z - bias <= the pool's depth, off the window or on a page
        without a slot (level index -1 too), else 0; NaN for NaN points. `bias` broadcasts with
        the points. With `normals` (world, facing the camera) it is the service's test: the bias
        adds bias_slope * depth_slope(), and a point whose seen side faces away from the light is
        0."""
        p = np.asarray(world_points, dtype=np.float64)
        z = self.ndc_depth(p, self._window(level_indices)[0])
        bias = np.asarray(bias, dtype=np.float64)
        if normals is not None:
            bias = bias + bias_slope * self.depth_slope(level_indices, normals, p)
        depth = self.depth_at(level_indices, p)
        with np.errstate(invalid="ignore"):
            lit = np.isnan(depth) | (z - bias <= depth)
        if normals is not None:
            n = np.asarray(normals, dtype=np.float64)
            if self.perspective:  # away from the light at the view's origin
                light = np.linalg.inv(self.view)[:3, 3]
                away = np.sum(n * (p - light), axis=-1) >= 0
            else:  # light space's -z is the light's travel; a normal along it faces away
                away = n @ -self.view[2, :3] >= 0
            lit &= ~away
        # A perspective map's points behind the light (NaN depth) are off it: lit.
        return np.where(np.isnan(p[..., 0]), np.nan, lit).astype(np.float32)
