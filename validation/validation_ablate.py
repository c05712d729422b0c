"""`lucent_validation.py ablate`: each correction of lucent's default path switched off alone.

Renders lucent (never Mitsuba: the committed references are the yardstick) on the fit and the
test cases of cases.json once as it is and once with each correction of ABLATIONS left out,
compares every image with the references as `compare` does (`compare_images`, the same
interior mask and figures), and prints per correction and split (fit, test): the median over
cases of each case's |median| error (and its change from the default), the median over cases
of the signed median, of the bias and of each channel's median, the median over cases of the
worst 8x8 block beyond twice its noise (`8x8`: where a correction acts locally, at a shadow
edge or a limb, the medians hardly move), and the worst case. A matrix
of every case's median follows, and `--json` gives every row. docs/corrections.md says what
each correction is and records these figures.

Each correction is left out through an existing flag where lucent has one (bounces,
splitting, view-ray single scattering), else through the hidden `lucent render --ablate NAME`
(`lucent_core::session::Ablations`), which changes nothing when not given.
"""

import json
import os
import sys

import numpy as np

# Name, what is left out, and the `lucent render` arguments that leave it out. `default`
# renders through the binary too (`--ablate none` changes nothing), so every image of a run
# comes from the same build.
ABLATIONS = [
    ("default", "nothing (lucent's default)", ["--ablate", "none"]),
    ("view-single", "view-ray single scattering: in the radial profile instead", ["--single-scattering", "profile"]),
    ("single-blend", "the geometric blend of single scattering across a face: linear", ["--ablate", "single-blend"]),
    ("exit-lobe", "the exit lobe T(mu_o): flat", ["--ablate", "exit-lobe"]),
    ("chord", "the body's chord along the view ray", ["--ablate", "chord"]),
    ("gain", "the finite-body gain (1 everywhere; the energy bound stays)", ["--ablate", "gain"]),
    ("slab-share", "the gain's division by the profile's slab share", ["--ablate", "slab-share"]),
    ("reach", "the gain's per-channel reach factor", ["--ablate", "reach"]),
    ("reach-division", "the reach factor's division by its channel mean (fitted): light and hue, as derived",
     ["--ablate", "reach-division"]),
    ("entry-ratio", "the entry term's albedo ratio A(mu_t)/A(1): Fresnel alone", ["--ablate", "entry-ratio"]),
    ("entry-local", "the entry term's local part: all carried by the profile", ["--ablate", "entry-local"]),
    ("bounces", "bounces between parts (--bounces 0)", ["--bounces", "0"]),
    ("bounce-tail", "the bounces' geometric tail: the series cut after three", ["--ablate", "bounce-tail"]),
    ("round-exit", "the exit lobe of light that crossed a round part (walked tilt, normal cosine): the slab's",
     ["--ablate", "round-exit"]),
    ("unbounced-single", "leaving the direct light's single scattering out of the bounces (fitted): bounced",
     ["--ablate", "unbounced-single"]),
    ("refine", "splitting faces to 6 mean free paths (--refine 0)", ["--refine", "0"]),
    ("env-shadows", "the environment's shadow by the mesh (sky cases only)", ["--ablate", "env-shadows"]),
]
# The splits, and the test cases apart by where the light comes from: `test lit` (front, side,
# top, grazing) and `test back` (the camera sees light that crossed the body), where lucent's
# deficit before issue 50 item 2 outweighs every correction.
SPLITS = ["fit", "test", "test lit", "test back"]


def backlit(cfg, case):
    """Whether the light travels towards the camera (cosine above 0.3 between the way it travels
    and the way to the eye): the camera sees mostly light that crossed the body."""
    from lucent_validation import camera, case_light_direction
    eye, _ = camera(cfg, case, np.zeros(3), 1.0)
    travel = np.array(case_light_direction(cfg, case))
    return case["light"] == "directional" and float(travel @ eye) / np.linalg.norm(travel) / np.linalg.norm(eye) > 0.3


def split_summary(rows):
    """Figures over the cases of `rows` (one correction, one split)."""
    f = [r["full"] for r in rows if r["full"]["pixels"] > 0]
    if not f:
        return None
    med = np.array([x["median"] for x in f])
    worst = int(np.nanargmax(np.abs(med)))
    return {
        "cases": len(f),
        "median_abs": float(np.nanmedian(np.abs(med))),
        "median": float(np.nanmedian(med)),
        "bias": float(np.nanmedian([x["bias"] for x in f])),
        "channels": [float(np.nanmedian([x["channel_median"][k] for x in f])) for k in range(3)],
        "noise": float(np.nanmedian([x["noise"] for x in f])),
        "worst_block": float(np.nanmedian([x["worst_block"] for x in f])),
        "worst": float(med[worst]),
        "worst_case": [r["case"] for r in rows if r["full"]["pixels"] > 0][worst],
    }


def render_all(cfg, names, out_dir, reuse, only, split):
    """Every (correction, case) row, rendering what `reuse` does not find in `out_dir`."""
    from lucent_validation import SCENES, comparable_cases, compare_images, read_exr, reference_parts, render_lucent
    rows = []
    for case in comparable_cases(cfg, only, split):
        a, b, single = reference_parts(case)
        for name, _, args in ABLATIONS:
            if name not in names:
                continue
            folder = os.path.join(out_dir, name)
            os.makedirs(folder, exist_ok=True)
            out = os.path.join(folder, f"{case['name']}.pbd.exr")
            same = name == "env-shadows" and case["light"] != "sky"
            if same:
                # No environment: the image is the default's; not rendered again.
                out = os.path.join(out_dir, "default", f"{case['name']}.pbd.exr")
            if (reuse or same) and os.path.exists(out):
                ours = read_exr(out)
            else:
                ours = render_lucent(cfg, case, os.path.join(SCENES, case["name"] + ".toml"), "pbd", out, args)
            row = {**compare_images(case, ours, a, b, single), "profile": name}
            row["group"] = ("test back" if backlit(cfg, case) else "test lit") if row["split"] == "test" else row["split"]
            rows.append(row)
        print(f"{case['name']}: done", file=sys.stderr, flush=True)
    return rows


def pct(v):
    return f"{100 * v:+6.1f}%" if v == v else "     -"


def print_tables(rows, names):
    """The per-correction summary, then every case's median under each correction."""
    summ = {}
    print("correction     split      cases  med|err|  change   median    bias        R/G/B median   noise  8x8  worst")
    for name in names:
        for split in SPLITS:
            s = split_summary([r for r in rows if r["profile"] == name and split in (r["split"], r["group"])])
            if s is None:
                continue
            summ.setdefault(name, {})[split] = s
            base = summ.get("default", {}).get(split)
            change = pct(s["median_abs"] - base["median_abs"]) if base and name != "default" else "       "
            rgb = "/".join(f"{100 * c:+.1f}" for c in s["channels"])
            print(f"{name:14s} {split:9s} {s['cases']:5d} {100 * s['median_abs']:8.1f}% {change} {pct(s['median'])} "
                  f"{pct(s['bias'])} {rgb:>17s}% {100 * s['noise']:5.1f}% {100 * s['worst_block']:4.0f}%  {pct(s['worst'])} ({s['worst_case']})")
    cases = list(dict.fromkeys(r["case"] for r in rows))
    short = [n[:11] for n in names]
    print("\nper case: median error (luminance) under each correction left out")
    print(f"{'case':30s} " + " ".join(f"{s:>11s}" for s in short))
    for case in cases:
        by = {r["profile"]: r["full"]["median"] for r in rows if r["case"] == case}
        print(f"{case:30s} " + " ".join(f"{pct(by[n]):>11s}" if n in by else f"{'':>11s}" for n in names))
    return summ


def cmd_ablate(cfg, names, out_dir, reuse, only, split, as_json):
    known = [n for n, _, _ in ABLATIONS]
    unknown = [n for n in names if n not in known]
    if unknown:
        sys.exit(f"ablate: unknown correction(s) {', '.join(unknown)}; expected some of {', '.join(known)}")
    # The default first: every other row's change is against it.
    names = ["default"] + [n for n in known if n in names and n != "default"]
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    rows = render_all(cfg, set(names), os.path.join(out_dir, "ablate"), reuse, only, split)
    if as_json:
        summ = {n: {s: split_summary([r for r in rows if r["profile"] == n and s in (r["split"], r["group"])]) for s in SPLITS}
                for n in names}
        print(json.dumps({"rows": rows, "summary": summ}, indent=1))
    else:
        for name, what, args in ABLATIONS:
            if name in names:
                print(f"  {name:13s} {what}  [{' '.join(args)}]")
        print()
        print_tables(rows, names)
    return rows
