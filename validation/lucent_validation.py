#!/usr/bin/env python3
"""lucent against a volumetric path tracer (Mitsuba 3), case by case.

    python3 validation/lucent_validation.py scenes      # lucent scene files for every case
    python3 validation/lucent_validation.py reference   # Mitsuba references (minutes a case)
    python3 validation/lucent_validation.py compare     # render lucent, print the table

Every case in cases.json is rendered by both from one description: the same mesh placed the
same way (lucent scales the mesh so that the largest side of its bounding box is `scale`
metres; Mitsuba renders in millimetres, the unit of the coefficients), the same orbit camera
(lucent's framing of the bounding sphere: crates/lucent-gpu/src/camera.rs), the same light
(a directional light of the given irradiance, or a constant sky of the given radiance), a
homogeneous medium with sigma_s = sigma_s' and an isotropic phase function (the similarity
relation lucent's materials assume), and no surface term: eta = 1 cases use a null boundary,
eta = 1.3 cases subtract a second render with an absorbing interior (the surface reflection
alone). References are two independently seeded halves (their difference gives the Monte Carlo
noise) and the single-scattering part (max_depth = 2).
"""

import argparse
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
REFS = os.path.join(HERE, "references")
SCENES = os.path.join(HERE, "scenes")
# Blocks whose reference mean is at least this share of the median interior pixel count as lit
# for `worst_lit_block`: the worst block overall tends to sit where the reference is 1e-4 of the
# median (the far side of a 10 cm sphere), which the comparison reports but no viewer sees.
LIT_LEVEL = 0.1
# Meshes by name: the bunny in the repo; the 11K Stanford dragon, fetched (not committed: the
# Stanford 3D Scanning Repository's terms) by scripts/fetch_dragon.sh and cleaned by `scenes`
# into the scenes folder (lucent reads a scene's mesh from beside it), gitignored.
MESH_FILES = {
    "bunny": os.path.join(ROOT, "assets", "bunny.obj"),
    "dragon_11k": os.path.join(SCENES, "dragon_11k.obj"),
}
FETCHED = {"dragon_11k": os.path.join(ROOT, "target", "meshes", "dragon_11k.ply")}


def load_cases():
    with open(os.path.join(HERE, "cases.json")) as f:
        return json.load(f)


def obj_vertices(path):
    vs = []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vs.append([float(x) for x in line.split()[1:4]])
    return np.array(vs)


def read_ascii_ply(path):
    """Vertices and triangles of an ASCII PLY (the dragon's: x y z first, then triangles)."""
    with open(path) as f:
        counts, props = {}, {}
        element = None
        for line in f:
            w = line.split()
            if w[:1] == ["element"]:
                element = w[1]
                counts[element], props[element] = int(w[2]), []
            elif w[:1] == ["property"]:
                props[element].append(w[-1])
            elif w[:1] == ["end_header"]:
                break
        xyz = [props["vertex"].index(k) for k in "xyz"]
        v = np.array([[float(x) for x in next(f).split()] for _ in range(counts["vertex"])])[:, xyz]
        t = [[int(x) for x in next(f).split()] for _ in range(counts["face"])]
    return v, np.array([r[1:4] for r in t if r[0] == 3], dtype=np.int64)


def clean_triangles(v, t):
    """What lucent's mesh::validate keeps: no degenerate faces, and of faces over the same three
    vertices the one whose winding the faces around it agree with (the first on a tie)."""
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    cross = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    longest = np.max([((b - a) ** 2).sum(1), ((c - b) ** 2).sum(1), ((a - c) ** 2).sum(1)], axis=0)
    ok = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2]) & (cross > 1e-12 * longest)
    groups = {}
    for f in np.nonzero(ok)[0]:
        groups.setdefault(tuple(sorted(t[f])), []).append(f)
    edges = lambda f: [(t[f][0], t[f][1]), (t[f][1], t[f][2]), (t[f][2], t[f][0])]
    directed = {}
    for g in groups.values():
        if len(g) == 1:
            for e in edges(g[0]):
                directed[e] = directed.get(e, 0) + 1
    agree = lambda f: sum(directed.get((j, i), 0) - directed.get((i, j), 0) for i, j in edges(f))
    keep = sorted(max(g, key=agree) for g in groups.values())  # max: the first of equal maxima
    return t[keep]


def unfold(v, t, max_passes=8):
    """What lucent's mesh::unfold does (in f64): the vertices of faces folded over their
    neighbours move to the mean of their neighbours, first each face's corner farthest from
    it, else all three, pass by pass while the count of folded faces falls. Returns the moved
    positions and the counts (found, left)."""
    v = v.copy()
    edge_faces = {}
    for f, tri in enumerate(t):
        for k in range(3):
            a, b = tri[k], tri[(k + 1) % 3]
            edge_faces.setdefault((min(a, b), max(a, b)), []).append(f)
    nbrs = [[] for _ in t]
    ring = {}
    for (a, b), fs in edge_faces.items():
        ring.setdefault(a, []).append(b)
        ring.setdefault(b, []).append(a)
        for f in fs:
            nbrs[f].extend(g for g in fs if g != f)

    def normals():
        c = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
        length = np.linalg.norm(c, axis=1, keepdims=True)
        return np.where(length > 0, c / np.where(length > 0, length, 1), 0)

    def folded():
        n = normals()
        out = []
        for f, tri in enumerate(t):
            if not n[f].any() or not nbrs[f]:
                continue
            total = n[nbrs[f]].sum(0)
            if not total.any() or n[f] @ total >= -0.5 * np.linalg.norm(total):
                continue
            if any(n[f] @ n[g] < 0 and any(n[f] @ (v[w] - v[tri[0]]) > 0 for w in t[g] if w not in tri) for g in nbrs[f]):
                out.append(f)
        return out

    def mean(w):
        return v[ring[w]].mean(0)

    now = folded()
    found = len(now)
    for _ in range(max_passes):
        if not now:
            break
        for every in (False, True):
            if every:
                verts = sorted({w for f in now for w in t[f]})
            else:
                verts = sorted({max(t[f], key=lambda w: ((v[w] - mean(w)) ** 2).sum()) for f in now})
            before, to = v[verts].copy(), np.array([mean(w) for w in verts])
            v[verts] = to
            after = folded()
            if len(after) < len(now):
                break
            v[verts] = before
        else:
            break
        now = after
    return v, found, len(now)


def write_obj(path, v, t):
    used = np.unique(t)
    index = np.full(len(v), -1)
    index[used] = np.arange(len(used))
    with open(path, "w") as f:
        f.write("# cleaned by validation/lucent_validation.py scenes\n")
        f.writelines(f"v {x:.7g} {y:.7g} {z:.7g}\n" for x, y, z in v[used])
        f.writelines(f"f {i + 1} {j + 1} {k + 1}\n" for i, j, k in index[t])


def mesh_missing(mesh):
    """Why a case's mesh is not here (None if it is)."""
    path = MESH_FILES.get(mesh)
    if path is None or os.path.exists(path):
        return None
    return f"{mesh}: run scripts/fetch_dragon.sh, then `lucent_validation.py scenes`"


def geometry(mesh):
    """Bounding-box centre, bounding-sphere radius and extent (largest box side), mesh units,
    as lucent computes them."""
    if mesh == "sphere":
        return np.zeros(3), 1.0, 2.0
    v = obj_vertices(MESH_FILES[mesh])
    lo, hi = v.min(0), v.max(0)
    c = 0.5 * (lo + hi)
    return c, float(np.sqrt(((v - c) ** 2).sum(1).max())), float((hi - lo).max())


def camera(cfg, centre, radius):
    """lucent's OrbitCamera::frame: eye position and vertical field of view (degrees)."""
    w, h = cfg["resolution"]
    cam = cfg["camera"]
    fov_y = math.radians(cam["fov"])
    half_x = math.atan(math.tan(fov_y / 2) * w / h)
    fit = 1.1 / math.sin(min(fov_y / 2, half_x))
    yaw, pitch = math.radians(cam["yaw"]), math.radians(cam["pitch"])
    d = np.array([math.sin(yaw) * math.cos(pitch), math.sin(pitch), math.cos(yaw) * math.cos(pitch)])
    return centre + d * fit * radius, cam["fov"]


def scene_toml(cfg, case):
    m = cfg["materials"][case["material"]]
    lines = [
        f'# {case["name"]}: generated by validation/lucent_validation.py from cases.json',
        f'mesh = "{os.path.basename(MESH_FILES[case["mesh"]]) if case["mesh"] in FETCHED else case["mesh"]}"',
        f'scale = {case["scale"]}',
        "surface = false",
        "[material]",
        f'name = "{case["material"]}"',
        f'sigma_s_prime = {m["sigma_s_prime"]}',
        f'sigma_a = {m["sigma_a"]}',
        f'eta = {case["eta"]}',
    ]
    if case["light"] == "directional":
        l = cfg["light"]
        lines += ["[[light]]", 'type = "directional"', f'direction = {l["direction"]}',
                  f'intensity = {l["irradiance"]}', "shadows = true"]
    else:
        lines += ["[environment]", 'path = "sky.exr"', f'intensity = {cfg["sky_radiance"]}']
    cam = cfg["camera"]
    lines += ["[camera]", f'yaw = {cam["yaw"]}', f'pitch = {cam["pitch"]}', f'fov = {cam["fov"]}']
    return "\n".join(lines) + "\n"


def write_exr(path, rgba):
    import mitsuba as mi
    mi.Bitmap(np.ascontiguousarray(rgba, dtype=np.float32), mi.Bitmap.PixelFormat.RGBA).write(path)


def read_exr(path):
    import mitsuba as mi
    return np.array(mi.Bitmap(path), dtype=np.float64)


def cmd_scenes(cfg):
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    os.makedirs(SCENES, exist_ok=True)
    write_exr(os.path.join(SCENES, "sky.exr"), np.ones((4, 8, 4)))
    for mesh, src in FETCHED.items():
        if os.path.exists(src):
            v, t = read_ascii_ply(src)
            kept = clean_triangles(v, t)
            v, found, left = unfold(v, kept)
            write_obj(MESH_FILES[mesh], v, kept)
            print(f"{mesh}: {len(kept)} of {len(t)} triangles kept, {found - left} of {found} folded faces undone -> {MESH_FILES[mesh]}")
        else:
            print(f"{mesh}: {src} missing (scripts/fetch_dragon.sh fetches it)")
    for case in cfg["cases"]:
        with open(os.path.join(SCENES, case["name"] + ".toml"), "w") as f:
            f.write(scene_toml(cfg, case))
    print(f"wrote {len(cfg['cases'])} scenes to {SCENES}")


def mitsuba_scene(cfg, case, max_depth, interior):
    import mitsuba as mi
    centre, radius, extent = geometry(case["mesh"])
    s = case["scale"] * 1000.0 / extent  # millimetres per mesh unit
    eye, fov = camera(cfg, centre, radius)
    m = cfg["materials"][case["material"]]
    ss, sa = np.array(m["sigma_s_prime"]), np.array(m["sigma_a"])
    if interior == "absorbing":
        ss, sa = np.zeros(3), np.full(3, 1e4)
    st = ss + sa
    # RGB values must lie in 0..1: sigma_t is given relative to its largest channel, times `scale`.
    medium = {"type": "homogeneous", "albedo": {"type": "rgb", "value": (ss / st).tolist()},
              "sigma_t": {"type": "rgb", "value": (st / st.max()).tolist()}, "scale": float(st.max()),
              "phase": {"type": "isotropic"}}
    bsdf = {"type": "null"} if case["eta"] == 1.0 else {"type": "dielectric", "int_ior": case["eta"], "ext_ior": 1.0}
    if case["mesh"] == "sphere":
        shape = {"type": "sphere", "radius": s, "center": [0.0, 0.0, 0.0]}
    else:
        shape = {"type": "obj", "filename": MESH_FILES[case["mesh"]],
                 "to_world": mi.ScalarTransform4f().scale(s)}
    shape.update({"bsdf": bsdf, "interior": medium})
    w, h = cfg["resolution"]
    if case["light"] == "directional":
        l = cfg["light"]
        emitter = {"type": "directional", "direction": l["direction"], "irradiance": {"type": "rgb", "value": [l["irradiance"]] * 3}}
    else:
        emitter = {"type": "constant", "radiance": {"type": "rgb", "value": [cfg["sky_radiance"]] * 3}}
    return {
        "type": "scene",
        "integrator": {"type": cfg.get("integrator", "volpath"), "max_depth": max_depth, "rr_depth": 100000},
        "sensor": {"type": "perspective", "fov": fov, "fov_axis": "y",
                   "to_world": mi.ScalarTransform4f().look_at(origin=(eye * s).tolist(), target=(centre * s).tolist(), up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": w, "height": h, "pixel_format": "rgba",
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent"}},
        "shape": shape,
        "emitter": emitter,
    }


def render(cfg, case, max_depth, seed, spp, interior="medium"):
    import mitsuba as mi
    scene = mi.load_dict(mitsuba_scene(cfg, case, max_depth, interior))
    img = mi.render(scene, seed=seed, spp=spp)
    return np.array(img, dtype=np.float64)


def single_depth(case):
    """Mitsuba's `max_depth` that keeps single scattering: the scattering event and the light
    (2) where the boundary is null; at eta != 1 also the refractions in and out (4), so that
    part minus the surface-only render is single scattering (plus the unscattered light through
    thin parts, 0.2% of the skim-milk bunny's red under the sky)."""
    return 2 if case["eta"] == 1.0 else 4


def cmd_reference(cfg, only):
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    os.makedirs(REFS, exist_ok=True)
    manifest_path = os.path.join(REFS, "manifest.json")
    manifest = json.load(open(manifest_path)) if os.path.exists(manifest_path) else {}
    for case in cfg["cases"]:
        if only and case["name"] not in only:
            continue
        if mesh_missing(case["mesh"]):
            print(f"{case['name']}: skipped, {mesh_missing(case['mesh'])}")
            continue
        t0 = time.time()
        spp = case["spp"]
        parts = {"half_a": render(cfg, case, -1, 1, spp), "half_b": render(cfg, case, -1, 2, spp),
                 "single": render(cfg, case, single_depth(case), 3, spp)}
        if case["eta"] != 1.0:
            parts["surface"] = render(cfg, case, -1, 4, spp, "absorbing")
        for k, v in parts.items():
            write_exr(os.path.join(REFS, f"{case['name']}.{k}.exr"), v)
        manifest[case["name"]] = {"spp_per_half": spp, "seeds": {"half_a": 1, "half_b": 2, "single": 3, "surface": 4},
                                  "mitsuba": mi.__version__, "variant": "scalar_rgb", "integrator": cfg.get("integrator", "volpath"), "seconds": round(time.time() - t0, 1)}
        json.dump(manifest, open(manifest_path, "w"), indent=1, sort_keys=True)
        print(f"{case['name']}: {time.time() - t0:.0f} s", flush=True)


def cmd_crop(cfg, name, window, spp, seeds, out_dir):
    """A window of one case's full reference at more samples (the dim side, where the reference
    is 1% of the lit side and heavy-tailed), two seeds averaged, compared pooled by brightness
    band with lucent's image from an earlier `compare` and the committed reference."""
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    case = next(c for c in cfg["cases"] if c["name"] == name)
    x0, y0, w, h = window
    parts = []
    for seed in seeds:
        d = mitsuba_scene(cfg, case, -1, "medium")
        d["sensor"]["film"].update({"crop_offset_x": x0, "crop_offset_y": y0, "crop_width": w, "crop_height": h})
        parts.append(np.array(mi.render(mi.load_dict(d), seed=seed, spp=spp), dtype=np.float64))
    hi = np.mean(parts, 0)[..., :3].sum(-1)
    a, b, _ = reference_parts(case)
    ref = (0.5 * (a + b))[y0:y0 + h, x0:x0 + w, :3].sum(-1)
    ours_full = read_exr(os.path.join(out_dir, f"{name}.pbd.exr"))
    ours = ours_full[y0:y0 + h, x0:x0 + w, :3].sum(-1)
    cover = ours_full[y0:y0 + h, x0:x0 + w, 3] > 0.999
    lit = ours_full[..., :3].sum(-1).max()
    print(f"{name} window {window}, {spp} spp x {len(seeds)} seeds; bands by lucent's brightness (share of its brightest pixel)")
    for lo, up in [(0.05, 0.2), (0.02, 0.05), (0.01, 0.02), (0.003, 0.01), (0.001, 0.003), (0.0, 0.001)]:
        m = cover & (ours >= lo * lit) & (ours < up * lit)
        if m.any():
            print(f"  {lo:.3f}-{up:.3f}: {int(m.sum()):4d} px  lucent/crop {ours[m].mean() / hi[m].mean():5.2f}  "
                  f"reference/crop {ref[m].mean() / hi[m].mean():5.2f}")


def reference_parts(case):
    get = lambda k: read_exr(os.path.join(REFS, f"{case['name']}.{k}.exr"))
    a, b, single = get("half_a"), get("half_b"), get("single")
    if case["eta"] != 1.0:
        surf = get("surface")[..., :3]
        a[..., :3] -= surf
        b[..., :3] -= surf
        single[..., :3] -= surf
    return a, b, single


def interior_mask(alpha):
    """Pixels fully covered whose 4-neighbours are too (1 px edge removed)."""
    m = alpha > 0.999
    inner = m.copy()
    inner[1:, :] &= m[:-1, :]
    inner[:-1, :] &= m[1:, :]
    inner[:, 1:] &= m[:, :-1]
    inner[:, :-1] &= m[:, 1:]
    return inner


def stats(ours, a, b, mask):
    """Per-pixel relative error of `ours` against the mean of halves a and b (luminance-like
    channel sum), with the Monte Carlo noise and the worst 8x8 block beyond its noise."""
    ref = 0.5 * (a + b)
    lum = lambda x: x[..., :3].sum(-1)
    r, o = lum(ref), lum(ours)
    noise_px = 0.5 * np.abs(lum(a) - lum(b))  # |a-b|/2 = std error of the mean of two halves
    sel = mask & (r > 1e-6)
    rel = (o[sel] - r[sel]) / r[sel]
    med = float(np.median(rel))
    mad = float(np.median(np.abs(rel - med)) * 1.4826)
    bias = float(o[sel].mean() / r[sel].mean() - 1)
    noise = float(np.median(noise_px[sel] / r[sel]))
    worst, worst_level, worst_lit = 0.0, 0.0, 0.0
    median_ref = float(np.median(r[sel]))
    H, W = r.shape
    for y in range(0, H - 7, 8):
        for x in range(0, W - 7, 8):
            blk = sel[y:y + 8, x:x + 8]
            if blk.sum() < 32:
                continue
            ro, rr = o[y:y + 8, x:x + 8][blk].mean(), r[y:y + 8, x:x + 8][blk].mean()
            nb = math.sqrt((noise_px[y:y + 8, x:x + 8][blk] ** 2).sum()) / blk.sum()
            err = max(abs(ro - rr) - 2 * nb, 0.0) / rr
            if err > worst:
                worst, worst_level = err, rr / median_ref
            if rr >= LIT_LEVEL * median_ref:
                worst_lit = max(worst_lit, err)
    return {"median": med, "bias": bias, "spread": mad, "noise": noise, "worst_block": worst,
            "worst_block_level": worst_level, "worst_lit_block": worst_lit, "pixels": int(sel.sum())}


def chroma_violations(ours, mask, a, b):
    """Pixels whose green or blue exceeds red: (in lucent, in the reference beyond twice its
    noise, in lucent where the reference has red clearly above both). Light scattered through
    marble or milk is redder the farther it travelled, but within about a mean free path of a
    shadow edge the bluer channels' sharper profiles win, so the path tracer shows such pixels
    too; only the third count is an error."""
    ref = 0.5 * (a + b)
    o, c = ours[..., :3], ref[..., :3]
    sigma = lambda k: np.hypot(0.5 * np.abs(a[..., k] - b[..., k]), 0.5 * np.abs(a[..., 0] - b[..., 0]))
    sel = mask & (o.sum(-1) > 1e-4)
    ours_v = sel & ((o[..., 1] > o[..., 0] * 1.001) | (o[..., 2] > o[..., 0] * 1.001))
    ref_v = sel & (((c[..., 1] - c[..., 0]) > 2 * sigma(1)) | ((c[..., 2] - c[..., 0]) > 2 * sigma(2)))
    ref_maybe = ((c[..., 1] - c[..., 0]) > -2 * sigma(1)) | ((c[..., 2] - c[..., 0]) > -2 * sigma(2))
    return {"lucent": int(ours_v.sum()), "reference": int(ref_v.sum()), "unlike_reference": int((ours_v & ~ref_maybe).sum())}


def heat_map(path, ours, ref, mask):
    import mitsuba as mi
    lum = lambda x: x[..., :3].sum(-1)
    r, o = lum(ref), lum(ours)
    err = np.where(mask & (r > 1e-6), (o - r) / np.maximum(r, 1e-6), 0.0)
    scale = max(float(np.percentile(r[mask], 99)) if mask.any() else 1.0, 1e-6)
    tone = lambda x: np.clip(x / scale, 0, 1) ** (1 / 2.2)
    red = np.clip(err / 0.5, 0, 1)
    blue = np.clip(-err / 0.5, 0, 1)
    heat = np.stack([1 - blue, 1 - red - blue, 1 - red], -1) * mask[..., None]
    img = np.concatenate([np.repeat(tone(o)[..., None], 3, -1), np.repeat(tone(r)[..., None], 3, -1), heat], 1)
    mi.util.write_bitmap(path, (np.clip(img, 0, 1) * 255).astype(np.uint8))


def lucent_module():
    """The `lucent` Python module if installed (it renders in-process), else None: the
    `lucent` binary renders through a subprocess and an EXR file."""
    try:
        import lucent
    except ImportError:
        return None
    return lucent if hasattr(lucent, "render") else None


def cmd_compare(cfg, profiles, out_dir, as_json, write_bounds, reuse=False, extra=()):
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    os.makedirs(out_dir, exist_ok=True)
    lucent = os.path.join(ROOT, "target", "release", "lucent")
    module = lucent_module()
    w, h = cfg["resolution"]
    rows = []
    for case in cfg["cases"]:
        if mesh_missing(case["mesh"]):
            print(f"{case['name']}: skipped, {mesh_missing(case['mesh'])}", file=sys.stderr)
            continue
        a, b, single = reference_parts(case)
        for profile in profiles:
            out = os.path.join(out_dir, f"{case['name']}.{profile}.exr")
            scene = os.path.join(SCENES, case["name"] + ".toml")
            if reuse and os.path.exists(out):
                ours = read_exr(out)
            elif module is not None and not extra:
                # The Python module (pip install ./crates/lucent-py): the CLI's image, no file between.
                ours = module.render(scene=scene, profile=profile, width=w, height=h, surface=False).astype(np.float64)
                module.write_exr(out, ours)
            else:
                subprocess.run([lucent, "render", "--scene", scene, "--profile", profile,
                                "--width", str(w), "--height", str(h), "--no-surface", "--out", out, *extra],
                               check=True, capture_output=True)
                ours = read_exr(out)
            # lucent's coverage decides: Mitsuba's alpha is 1 everywhere under a constant sky and
            # below 1 where a null boundary lets camera rays through a thin medium (ketchup).
            # Both agree to the edge pixels on the marble sphere (checked when the cases were set up).
            mask = interior_mask(ours[..., 3])
            full = stats(ours, a, b, mask)
            ms_a, ms_b = a.copy(), b.copy()
            ms_a[..., :3] -= single[..., :3]
            ms_b[..., :3] -= single[..., :3]
            ms = stats(ours, ms_a, ms_b, mask)
            heat_map(os.path.join(out_dir, f"{case['name']}.{profile}.png"), ours, 0.5 * (a + b), mask)
            rows.append({"case": case["name"], "profile": profile, "full": full, "multiple_only": ms,
                         "green_or_blue_above_red": chroma_violations(ours, mask, a, b) if case["material"] != "ketchup" else None})
    chroma = lambda v: "-" if v is None else f"{v['lucent']}/{v['reference']}/{v['unlike_reference']}"
    if as_json:
        print(json.dumps(rows, indent=1))
    else:
        print(f"{'case':24} {'profile':8} {'median':>7} {'bias':>7} {'spread':>7} {'noise':>6} {'worst8x8':>8} {'at':>7} "
              f"{'lit8x8':>7} {'MS-only med':>11} {'g/b>r ours/ref/unlike':>20}")
        for r in rows:
            f, m = r["full"], r["multiple_only"]
            print(f"{r['case']:24} {r['profile']:8} {f['median']:+7.1%} {f['bias']:+7.1%} {f['spread']:7.1%} {f['noise']:6.1%} "
                  f"{f['worst_block']:8.1%} {f['worst_block_level']:7.0e} {f['worst_lit_block']:7.1%} {m['median']:+11.1%} "
                  f"{chroma(r['green_or_blue_above_red']):>20}")
    if write_bounds:
        bounds = {}
        for r in rows:
            if r["profile"] != profiles[0]:
                continue
            f = r["full"]
            bounds[r["case"]] = {"median": abs(f["median"]) + 0.02, "bias": abs(f["bias"]) + 0.02,
                                 "worst_block": f["worst_block"] + 0.05}
        json.dump({"profile": profiles[0], "cases": bounds}, open(os.path.join(HERE, "bounds.json"), "w"), indent=1, sort_keys=True)
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    sub.add_parser("scenes")
    r = sub.add_parser("reference")
    r.add_argument("cases", nargs="*", help="case names (default: all)")
    k = sub.add_parser("crop", help="a window of a case's reference at more samples, against lucent (after compare)")
    k.add_argument("case")
    k.add_argument("--window", default="20,20,24,56", help="x,y,width,height in pixels")
    k.add_argument("--spp", type=int, default=4096)
    k.add_argument("--seeds", default="11,12")
    k.add_argument("--out", default=os.path.join(ROOT, "target", "validation"))
    c = sub.add_parser("compare")
    c.add_argument("--profiles", default="pbd,dipole,mertens")
    c.add_argument("--out", default=os.path.join(ROOT, "target", "validation"))
    c.add_argument("--json", action="store_true")
    c.add_argument("--write-bounds", action="store_true", help="record the first profile's figures (+ margins) in bounds.json")
    c.add_argument("--reuse", action="store_true", help="compare the images an earlier run left in --out instead of rendering")
    c.add_argument("--lucent-args", default="", help="more `lucent render` arguments, e.g. '--single-scattering profile'")
    args = p.parse_args()
    cfg = load_cases()
    if args.cmd == "scenes":
        cmd_scenes(cfg)
    elif args.cmd == "crop":
        cmd_crop(cfg, args.case, [int(v) for v in args.window.split(",")], args.spp,
                 [int(v) for v in args.seeds.split(",")], args.out)
    elif args.cmd == "reference":
        cmd_reference(cfg, set(args.cases))
    else:
        cmd_compare(cfg, args.profiles.split(","), args.out, args.json, args.write_bounds, args.reuse, args.lucent_args.split())


if __name__ == "__main__":
    sys.exit(main())
