#!/usr/bin/env python3
"""Where a back-lit HTSM case misses light (issue 55): the ratio lucent / reference summed over
bands of pixels, by (a) the distance of the pixel's surface point to the light-view silhouette
and (b) the chord the light crosses to reach it (along the light's direction through the body),
both in millimetres, with the Monte Carlo noise of each band (|a - b| / (a + b) of the two
reference halves' band sums). A chord of 0 is a point the light reaches (lit from the side
the camera sees); it is its own band. Where the homogeneous suite renders the same scene's
single scattering (`SINGLE`, its `.single.exr`), each band also gives that part's share of
the reference: what lucent's view-ray single scattering should add where the light crossed.

    python3 validation/htsm_validation.py compare                     # renders into target/htsm_validation
    python3 validation/htsm_backlit.py htsm_bunny_uniform_5cm_back [MODEL] [RENDER_DIR]

The surface point of each pixel and the chords come from Mitsuba's ray casts into the
reference's own scene (lucent_validation.mitsuba_scene); the light-view silhouette from a
256^2 orthographic cast along the light's direction over the scene's bounding box.
"""

import os
import sys

import numpy as np

import htsm_validation as hv
import lucent_validation as lv

GRID = 256
# Homogeneous-suite cases with the same mesh, light, camera and base material whose `.single.exr`
# (Mitsuba, max_depth 2) is the single scattering of an HTSM case (its sigma_a is 0.005 mm^-1
# lower: the uniform case's density adds it; single scattering over a few mm barely sees it).
SINGLE = {"htsm_bunny_uniform_5cm_back": "bunny_skimmilk_5cm_back", "htsm_bunny_uniform_5cm_front": "bunny_skimmilk_5cm"}


def light_view_edges(mi, scene, c, radius, u, v, light):
    """Grid cells (i, j) on the edge of the light-view coverage, and the cell size (mm)."""
    step = 2 * radius / GRID
    cov = np.zeros((GRID, GRID), bool)
    for i in range(GRID):
        for j in range(GRID):
            o = c + (i + 0.5 - GRID / 2) * step * u + (j + 0.5 - GRID / 2) * step * v - 2 * radius * light
            cov[i, j] = scene.ray_intersect(mi.Ray3f(mi.Point3f(*o), mi.Vector3f(*light))).is_valid()
    inner = np.roll(cov, 1, 0) & np.roll(cov, -1, 0) & np.roll(cov, 1, 1) & np.roll(cov, -1, 1)
    return np.nonzero(cov & ~inner), step


def samples(name, model, render_dir):
    """Per covered pixel: distance to the light-view silhouette, chord (mm), lucent's RGB, the
    reference's mean RGB and its two halves' RGB."""
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    cfg = hv.load_cfg()
    case = next(c for c in cfg["cases"] if c["name"] == name)
    scene = mi.load_dict(lv.mitsuba_scene(cfg, case, -1, "medium"))
    sensor = scene.sensors()[0]
    w, h = cfg["resolution"]
    light = np.array(lv.case_light_direction(cfg, case))
    light /= np.linalg.norm(light)
    u = np.cross(light, [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(light, u)
    bb = scene.bbox()
    c = np.array(bb.center())
    radius = float(np.linalg.norm(np.array(bb.max) - np.array(bb.min))) / 2
    (ei, ej), step = light_view_edges(mi, scene, c, radius, u, v, light)
    ours = lv.read_exr(os.path.join(render_dir, f"{name}.{model}.exr"))
    a, b = (lv.read_exr(os.path.join(hv.REFS, f"{name}.{k}.exr"))[..., :3] for k in ("half_a", "half_b"))
    single = (lv.read_exr(os.path.join(hv.REFS, f"{SINGLE[name]}.single.exr"))[..., :3]
              if name in SINGLE else None)
    rows = []
    for y in range(h):
        for x in range(w):
            if ours[y, x, 3] < 0.99:
                continue
            ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f((x + 0.5) / w, (y + 0.5) / h), mi.Point2f(0.5, 0.5))
            si = scene.ray_intersect(ray)
            if not si.is_valid():
                continue
            p = np.array(si.p)
            gi, gj = (p - c) @ u / step + GRID / 2, (p - c) @ v / step + GRID / 2
            dist = float(np.sqrt((ei + 0.5 - gi) ** 2 + (ej + 0.5 - gj) ** 2).min()) * step
            back = scene.ray_intersect(si.spawn_ray(mi.Vector3f(*(-light))))
            chord = float(np.linalg.norm(np.array(back.p) - p)) if back.is_valid() else 0.0
            row = (dist, chord, *ours[y, x, :3], *(0.5 * (a[y, x] + b[y, x])), *a[y, x], *b[y, x])
            rows.append(row + (tuple(single[y, x]) if single is not None else ()))
    return np.array(rows)


def table(name, model, r, col, edges, label):
    print(f"{name} ({model}) by {label}: band sums lucent / reference R/G/B, noise R/G/B"
          + (", single-scattering share of the reference R/G/B" if r.shape[1] > 14 else ""))
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (r[:, col] >= lo) & (r[:, col] < hi)
        if m.sum() < 15:
            continue
        ours, ref, a, b = (r[m, k:k + 3].sum(0) for k in (2, 5, 8, 11))
        q, noise = ours / ref, np.abs(a - b) / (a + b)
        band = "lit (0)    " if hi <= 1e-3 else f"{lo:5.1f}-{hi:<5.1f}"
        line = (f"  {band} pixels {m.sum():5d}  ratio {q[0]:.2f}/{q[1]:.2f}/{q[2]:.2f}"
                f"  noise {noise[0]:.3f}/{noise[1]:.3f}/{noise[2]:.3f}")
        if r.shape[1] > 14:
            single = r[m, 14:17].sum(0) / ref
            line += f"  single {single[0]:.2f}/{single[1]:.2f}/{single[2]:.2f}"
        print(line)


def main():
    name = sys.argv[1]
    model = sys.argv[2] if len(sys.argv) > 2 else "diffusion"
    render_dir = sys.argv[3] if len(sys.argv) > 3 else os.path.join(lv.ROOT, "target", "htsm_validation")
    r = samples(name, model, render_dir)
    table(name, model, r, 0, [0, 1, 2, 4, 7, 11, 16, 100], "distance to the light-view silhouette (mm)")
    table(name, model, r, 1, [0, 1e-3, 2.5, 5, 10, 15, 20, 25, 30, 40, 100], "chord to the light through the body (mm)")


if __name__ == "__main__":
    main()
