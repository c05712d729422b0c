# %% [markdown]
# # lucent from Python: render, deform, compare with a path tracer
#
# A notebook in cells (`# %%`: Jupyter, VS Code or plain `python3` run it). It needs only the
# `lucent` module (`pip install ./crates/lucent-py`) and numpy; matplotlib, if installed, draws
# the figure, else a PNG is written without it. The reference is committed: Mitsuba 3's
# `volpathmis` render of the validation case `bunny_marble_10cm` (validation/cases.json), two
# independently seeded halves of 512 samples per pixel each, so their difference gives the
# Monte Carlo noise and no Mitsuba is needed here.
#
#     python3 examples/python/render_deform_compare.py [OUT_DIR]

# %%
import json
import os
import sys
import time
import zlib
import struct

import numpy as np

import lucent

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
CASE = "bunny_marble_10cm"
SCENE = os.path.join(ROOT, "validation", "scenes", CASE + ".toml")
OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target", "python-example")
os.makedirs(OUT, exist_ok=True)
width, height = json.load(open(os.path.join(ROOT, "validation", "cases.json")))["resolution"]

# %% [markdown]
# ## Render
# The scene file fixes mesh, material (marble: sigma_s', sigma_a per channel in mm^-1, eta 1),
# scale (10 cm), the directional light, the camera and `surface = false` (the path tracer's
# null boundary has no surface term). `render` returns float32 (H, W, 4): linear radiance
# premultiplied by coverage, and coverage.

# %%
t = time.perf_counter()
ours = lucent.render(scene=SCENE, width=width, height=height)
print(f"lucent.render: {ours.shape} in {time.perf_counter() - t:.2f} s")

# %% [markdown]
# ## Against the path tracer
# Per-pixel relative error of the channel sum on the object's interior (full coverage, one
# pixel in from the edge), with the Monte Carlo noise of the reference's mean, |a - b| / 2,
# beside it: an error within about twice the noise is no error.

# %%
refs = os.path.join(ROOT, "validation", "references")
a = lucent.read_exr(os.path.join(refs, CASE + ".half_a.exr")).astype(np.float64)
b = lucent.read_exr(os.path.join(refs, CASE + ".half_b.exr")).astype(np.float64)
ref = 0.5 * (a + b)
lum = lambda x: x[..., :3].sum(-1)
cover = ours[..., 3] > 0.999
inner = cover.copy()
inner[1:, :] &= cover[:-1, :]
inner[:-1, :] &= cover[1:, :]
inner[:, 1:] &= cover[:, :-1]
inner[:, :-1] &= cover[:, 1:]
mask = inner & (lum(ref) > 1e-6)
err = np.where(mask, (lum(ours) - lum(ref)) / np.maximum(lum(ref), 1e-6), 0.0)
noise = np.where(mask, 0.5 * np.abs(lum(a) - lum(b)) / np.maximum(lum(ref), 1e-6), 0.0)
print(f"{mask.sum()} interior pixels: median error {np.median(err[mask]):+.1%}, "
      f"mean |error| {np.abs(err[mask]).mean():.1%}, median Monte Carlo noise {np.median(noise[mask]):.1%}, "
      f"pixels beyond 2x their noise {np.mean(np.abs(err[mask]) > 2 * noise[mask]):.0%}")

# %% [markdown]
# ## Deform
# A session keeps the solve: the links are made on the rest pose and updated to each new pose
# (Mertens 2003 section 5.5, incremental mode). `solve()` returns per-face radiosity B and
# per-vertex radiance as numpy arrays with the stage timings.

# %%
s = lucent.Session(scene=SCENE, width=width, height=height)
rest = s.solve()
print(f"{s}: rest pose {rest.timings['total_ms']:.0f} ms, {rest.links} links")
for degrees in (15, 30, 45):
    s.deform(f"twist:{degrees}")
    bent = s.solve()
    t = bent.timings
    print(f"twist {degrees:2} deg: {t['total_ms']:.0f} ms (links updated in {t['link_ms']:.0f} ms), "
          f"mean B {bent.face_b.mean(0).round(4)} vs rest {rest.face_b.mean(0).round(4)}")
twisted = s.render()

# %% [markdown]
# ## The figure: lucent, the reference, the error map (red: lucent brighter, blue: darker,
# full colour at 50 %), the twisted bunny

# %%
scale = float(np.percentile(lum(ref)[mask], 99))
tone = lambda x: np.clip(lum(x) / scale, 0, 1) ** (1 / 2.2)
red, blue = np.clip(err / 0.5, 0, 1), np.clip(-err / 0.5, 0, 1)
heat = np.stack([1 - blue, 1 - red - blue, 1 - red], -1) * mask[..., None]
gray = lambda x: np.repeat(tone(x)[..., None], 3, -1)
panels = [("lucent", gray(ours)), ("Mitsuba volpathmis", gray(ref)), ("relative error", heat),
          ("lucent, twisted 45 deg", gray(twisted))]
try:
    import matplotlib
    matplotlib.use("Agg") if "ipykernel" not in sys.modules else None
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 4, figsize=(16, 3.6))
    for ax, (title, img) in zip(axes, panels):
        ax.imshow(np.clip(img, 0, 1))
        ax.set_title(title)
        ax.axis("off")
    path = os.path.join(OUT, "render_deform_compare.png")
    fig.savefig(path, dpi=100, bbox_inches="tight")
except ImportError:
    # No matplotlib: the panels side by side as an 8-bit PNG, written by hand.
    img = (np.clip(np.concatenate([p for _, p in panels], 1), 0, 1) * 255).astype(np.uint8)
    h, w = img.shape[:2]
    raw = b"".join(b"\0" + img[y].tobytes() for y in range(h))
    chunk = lambda tag, data: struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    path = os.path.join(OUT, "render_deform_compare.png")
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
lucent.write_exr(os.path.join(OUT, "lucent.exr"), ours)
print(f"wrote {path}")
