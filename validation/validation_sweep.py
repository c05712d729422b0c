"""`lucent_validation.py sweep --seed N --count K`: random scenes that nobody can tune to.

Each draw picks, from a generator seeded with N (the same draws for the same seed, whatever is
installed): a mesh from `lucent_validation.MESHES`, a material from SWEEP_MATERIALS (Jensen et
al. 2001's measured coefficients, the numbers of lucent's presets, in cases.json), a scale
uniform in 2-14 cm, a light direction uniform on the sphere and an orbit camera (yaw uniform
over the circle, pitch uniform in -20..60 degrees, 35 degree field of view). Both renderers
render it as they render the committed cases (eta = 1, null boundary, directional light of
irradiance 1): Mitsuba as two seeded halves at `--spp` samples each (default 64, an eighth of
the committed references'; the table's noise column is their difference), lucent with the
default profile. A draw whose mesh is not here (fetched meshes) is reported and skipped, so
the other draws stay the same. Nothing of a sweep is committed: its draws are fresh for every
seed, so no constant can be chosen on them.
"""

import json
import math
import os
import time

import numpy as np

SWEEP_MATERIALS = ["marble", "skimmilk", "wholemilk", "skin1", "apple", "cream", "ketchup"]
SCALE_RANGE_M = (0.02, 0.14)
PITCH_RANGE_DEG = (-20.0, 60.0)
# The targets, printed beside the summary (luminance and each channel's median).
TARGET_LUMINANCE, TARGET_CHANNEL = 0.05, 0.07


def draw(seed, count):
    """The sweep's draws for `seed`: a list of case dictionaries as cases.json holds them."""
    from lucent_validation import MESHES
    rng = np.random.default_rng(seed)
    draws = []
    for i in range(count):
        mesh = MESHES[int(rng.integers(len(MESHES)))]
        material = SWEEP_MATERIALS[int(rng.integers(len(SWEEP_MATERIALS)))]
        scale = float(rng.uniform(*SCALE_RANGE_M))
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        yaw, pitch = float(rng.uniform(-180.0, 180.0)), float(rng.uniform(*PITCH_RANGE_DEG))
        draws.append({
            "name": f"sweep_{seed}_{i:02d}_{mesh}_{material}_{round(scale * 100)}cm",
            "mesh": mesh, "material": material, "scale": round(scale, 4), "eta": 1.0, "light": "directional",
            "light_direction": [round(float(x), 4) for x in d],
            "camera": {"yaw": round(yaw, 2), "pitch": round(pitch, 2), "fov": 35.0},
            "split": f"sweep {seed}",
        })
    return draws


def describe(case, cfg):
    """The draw in words: where the light comes from relative to the camera."""
    from lucent_validation import camera, case_light_direction
    eye, _ = camera(cfg, case, np.zeros(3), 1.0)
    to_eye = eye / np.linalg.norm(eye)
    travel = np.array(case_light_direction(cfg, case))
    travel /= np.linalg.norm(travel)
    # cos of the angle between where the light comes from and where the camera is:
    # 1 = lit from the camera's side (front), -1 = lit from behind.
    c = float(-travel @ to_eye)
    kind = "front" if c > 0.5 else "back" if c < -0.5 else "side"
    return f"light {kind} ({math.degrees(math.acos(max(-1.0, min(1.0, c)))):.0f} deg from the eye)"


def cmd_sweep(cfg, seed, count, spp, out_dir, as_json):
    import mitsuba as mi
    import lucent_validation as lv
    from validation_stats import print_rows, print_summary, summary
    mi.set_variant("scalar_rgb")
    out_dir = os.path.join(out_dir, f"sweep_{seed}")
    os.makedirs(out_dir, exist_ok=True)
    rows, notes = [], []
    for i, case in enumerate(draw(seed, count)):
        what = (f"{case['name']}: light travels {case['light_direction']}, camera yaw {case['camera']['yaw']} "
                f"pitch {case['camera']['pitch']}, {describe(case, cfg)}")
        if lv.mesh_missing(case["mesh"]):
            notes.append(f"{what}: skipped, {lv.mesh_missing(case['mesh'])}")
            print(notes[-1], flush=True)
            continue
        t0 = time.time()
        # lucent reads a scene's mesh only from the scene's own folder: the draw's scene file goes
        # beside the cases' (validation/scenes/sweep_*.toml, gitignored).
        scene = os.path.join(lv.SCENES, case["name"] + ".toml")
        with open(scene, "w") as f:
            f.write(lv.scene_toml(cfg, case))
        # The draw's Mitsuba halves are kept beside its images and reused by a later sweep of
        # the same seed and samples (the draws are a function of the seed; lucent is re-rendered).
        halves = []
        for h in (1, 2):
            cached = os.path.join(out_dir, f"{case['name']}.mitsuba_{spp}spp_{h}.exr")
            if os.path.exists(cached):
                halves.append(lv.read_exr(cached))
            else:
                halves.append(lv.render(cfg, case, -1, 1000 * seed + 2 * i + h, spp))
                lv.write_exr(cached, halves[-1])
        a, b = halves
        ours = lv.render_lucent(cfg, case, scene, "pbd", os.path.join(out_dir, case["name"] + ".exr"))
        os.remove(scene)
        row = lv.compare_images(case, ours, a, b, None, os.path.join(out_dir, case["name"] + ".png"))
        rows.append({**row, "profile": "pbd", "draw": case, "seconds": round(time.time() - t0, 1)})
        notes.append(what)
        print(f"{what} ({time.time() - t0:.0f} s)", flush=True)
    summ = summary(rows, "pbd")
    within = sum(1 for r in rows if abs(r["full"]["median"]) <= TARGET_LUMINANCE
                 and all(abs(m) <= TARGET_CHANNEL for m in r["full"]["channel_median"]))
    result = {"seed": seed, "count": count, "spp_per_half": spp, "rows": rows, "summary": summ, "notes": notes,
              "within_targets": within}
    json.dump(result, open(os.path.join(out_dir, "sweep.json"), "w"), indent=1)
    if as_json:
        print(json.dumps(result, indent=1))
        return result
    print(f"\nsweep seed {seed}: {len(rows)} of {count} draws rendered; Mitsuba volpathmis at 2 x {spp} spp")
    print_rows(rows, chroma_column=False)
    print_summary(summ, "pbd")
    print(f"  within the issue's targets (luminance median within {TARGET_LUMINANCE:.0%}, each channel's within "
          f"{TARGET_CHANNEL:.0%}): {within} of {len(rows)}")
    return result
