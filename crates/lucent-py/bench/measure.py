#!/usr/bin/env python3
"""The Python module's two targets (issue 54), measured against the `lucent` binary:

1. agreement: `lucent.render(scene=S, ...)` against `lucent render --scene S ... --out x.exr`
   for every validation scene whose mesh is here: the largest per-pixel relative difference
   (|a - b| / max(|b|, 1e-3 of the image's peak)) and whether the two are bit for bit equal;
2. speed: the same solve from Python (`Session.solve()`) and from the command line, runs
   interleaved so both see the same machine load, each solve in a fresh process (a fresh
   interpreter for Python); medians of the solve's stage sum (what
   `FrameSession` times: irradiance, link, pull, gather, single scattering, push, bounces; the
   CLI logs it at RUST_LOG=info) and of each front end's own wall-clock solve time.

    python3 crates/lucent-py/bench/measure.py [--runs 7] [--lucent target/release/lucent]
"""

import argparse
import glob
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

import numpy as np

import lucent

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
STAGES = re.compile(r"irradiance ([\d.]+) ms, link ([\d.]+) ms, pull ([\d.]+) ms, gather ([\d.]+) ms, "
                    r"push ([\d.]+) ms, bounces ([\d.]+) ms, single scattering ([\d.]+) ms")


def cli(binary, args, out):
    env = dict(os.environ, RUST_LOG="info")
    p = subprocess.run([binary, "render", *args, "--out", out], check=True, capture_output=True, text=True, env=env)
    stages = STAGES.search(p.stderr)
    solve = re.search(r"solve (\d+) ms", p.stdout)
    return sum(float(x) for x in stages.groups()), float(solve.group(1))


def agreement(binary, width, height):
    print(f"{'scene':28} {'max rel diff':>12} {'bit-equal':>9}")
    for scene in sorted(glob.glob(os.path.join(ROOT, "validation", "scenes", "*.toml"))):
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "x.exr")
            try:
                cli(binary, ["--scene", scene, "--width", str(width), "--height", str(height), "--no-surface"], out)
            except subprocess.CalledProcessError as e:
                print(f"{os.path.basename(scene):28} CLI failed: {e.stderr.strip().splitlines()[-1]}")
                continue
            ref = lucent.read_exr(out)
        ours = lucent.render(scene=scene, width=width, height=height, surface=False)
        peak = float(np.abs(ref).max())
        diff = float((np.abs(ours - ref) / np.maximum(np.abs(ref), 1e-3 * peak)).max())
        print(f"{os.path.basename(scene):28} {diff:12.2e} {str(bool(np.array_equal(ours, ref))):>9}")


# One solve in a fresh interpreter, as the CLI solves in a fresh process: caches that live for
# the process (the profile's tables) start empty in both.
ONE_SOLVE = """
import json, sys, lucent
s = lucent.Session(scene=sys.argv[1], width=int(sys.argv[2]), height=int(sys.argv[3]), mode="render")
print(json.dumps(s.solve().timings))
"""


def python_solve(scene, width, height):
    p = subprocess.run([sys.executable, "-c", ONE_SOLVE, scene, str(width), str(height)],
                       check=True, capture_output=True, text=True)
    t = json.loads(p.stdout.strip().splitlines()[-1])
    return t["total_ms"], t["wall_ms"]


def speed(binary, scene, width, height, runs):
    args = ["--scene", scene, "--width", str(width), "--height", str(height)]
    c_stage, c_wall, p_stage, p_wall, warm = [], [], [], [], []
    session = None
    with tempfile.TemporaryDirectory() as d:
        for _ in range(runs):
            s, w = cli(binary, args, os.path.join(d, "x.exr"))
            c_stage.append(s)
            c_wall.append(w)
            # As the CLI solves one image: a fresh session in its mode, solved once. (The CLI's
            # "solve" wall time also spans making the session, which Python's wall_ms does not.)
            s, w = python_solve(scene, width, height)
            p_stage.append(s)
            p_wall.append(w)
            # The same in one long-lived interpreter, as a notebook would solve again and again.
            session = lucent.Session(scene=scene, width=width, height=height, mode="render")
            warm.append(session.solve().timings["total_ms"])
    med = statistics.median
    rng = lambda v: f"{min(v):.0f}-{max(v):.0f}"
    print(f"{os.path.basename(scene)} at {width}x{height}, {runs} runs each, interleaved:")
    print(f"  solve stage sum: CLI median {med(c_stage):.0f} ms ({rng(c_stage)}), Python (fresh interpreter) "
          f"median {med(p_stage):.0f} ms ({rng(p_stage)}): Python/CLI {med(p_stage) / med(c_stage):.3f}")
    print(f"  wall-clock solve: CLI median {med(c_wall):.0f} ms ({rng(c_wall)}), Python Session.solve() "
          f"median {med(p_wall):.0f} ms ({rng(p_wall)}): Python/CLI {med(p_wall) / med(c_wall):.3f}")
    print(f"  Python, later sessions in one interpreter: stage sum median {med(warm):.0f} ms ({rng(warm)})")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--lucent", default=os.path.join(ROOT, "target", "release", "lucent"))
    p.add_argument("--runs", type=int, default=7)
    p.add_argument("--skip-agreement", action="store_true")
    p.add_argument("--scene", default=os.path.join(ROOT, "validation", "scenes", "bunny_marble_10cm.toml"))
    p.add_argument("--size", default="400x300", help="image size of the speed runs (the eye of view-ray single scattering)")
    a = p.parse_args()
    if not a.skip_agreement:
        agreement(a.lucent, 128, 96)
    w, h = (int(x) for x in a.size.split("x"))
    speed(a.lucent, a.scene, w, h, a.runs)


if __name__ == "__main__":
    main()
