#!/usr/bin/env python3
"""Exact (Monte Carlo) transport through a slab lit on one side: the ground truth of lucent's
cross-body transmission (issue 50).

A slab of optical thickness tau (mean free paths, sigma_t = 1) scatters isotropically and has
an index-matched boundary (eta = 1, the validation suite's null boundary). A collimated beam
enters one face at direction cosine mu0. Photons walk with albedo 1 and each one's number of
scatterings n is kept, so that any albedo a weights it by a**n afterwards: one walk serves every
material. What leaves is split as lucent splits it: unscattered (n = 0), single scattering
(n = 1, the view ray's), multiple scattering (n >= 2, what the diffusion profile carries).

    python3 validation/slab_walk.py table [--photons N] [--seed S]   # totals, JSON to stdout
    python3 validation/slab_walk.py profile --tau T [--photons N]      # radial T(rho), R(rho)
    python3 validation/slab_walk.py material --name marble --mm 3 [--mu0 1] [--photons N]
                                         # one validation material's slab, per channel

Output of `table`: for each (tau, mu0) and each albedo of ALBEDOS: T_ms, R_ms, T_ss, R_ss,
T_direct, each with its standard error (one standard deviation of the mean).
"""
import argparse
import json
import sys

import numpy as np

TAUS = [0.5, 1.0, 2.0, 3.0, 5.0, 7.0, 10.0, 14.0, 20.0]
MU0S = [1.0, 0.5]
# The validation materials' albedos (sigma_s' / (sigma_s' + sigma_a), validation/cases.json)
# and a few between.
ALBEDOS = {
    "marble": [2.19 / 2.1921, 2.62 / 2.6241, 3.00 / 3.0071],
    "skimmilk": [0.70 / 0.7014, 1.22 / 1.2225, 1.90 / 1.9142],
    "ketchup": [0.18 / 0.241, 0.07 / 1.04, 0.03 / 1.48],
    "grid": [0.3, 0.6, 0.8, 0.9, 0.95, 0.99],
}


def walk(tau, mu0, photons, rng, max_steps=10**7):
    """Exit side (+1 transmitted, -1 reflected), scatterings n and exit position (x, y) of
    each photon entering at the origin at cosine mu0 (tilted toward +x); `walk.exit_mu` holds
    each one's exit cosine with the face's normal after the call."""
    n = np.zeros(photons, dtype=np.int64)
    side = np.zeros(photons, dtype=np.int8)
    ex = np.zeros(photons)
    ey = np.zeros(photons)
    emu = np.zeros(photons)
    idx = np.arange(photons)
    pos = np.zeros((photons, 3))
    d = np.tile([np.sqrt(max(0.0, 1 - mu0 * mu0)), 0.0, mu0], (photons, 1))
    for _ in range(max_steps):
        if idx.size == 0:
            break
        s = -np.log1p(-rng.random(idx.size))
        z_new = pos[:, 2] + s * d[:, 2]
        out_front = z_new >= tau
        out_back = z_new <= 0.0
        out = out_front | out_back
        if out.any():
            # Distance to the plane crossed.
            zb = np.where(out_front, tau, 0.0)
            dz = d[:, 2]
            t = np.where(out, (zb - pos[:, 2]) / np.where(dz == 0, 1e-300, dz), 0.0)
            o = np.nonzero(out)[0]
            gi = idx[o]
            side[gi] = np.where(out_front[o], 1, -1)
            ex[gi] = pos[o, 0] + t[o] * d[o, 0]
            ey[gi] = pos[o, 1] + t[o] * d[o, 1]
            emu[gi] = np.abs(d[o, 2])
        keep = ~out
        idx, pos, d, s = idx[keep], pos[keep], d[keep], s[keep]
        pos = pos + s[:, None] * d
        n[idx] += 1
        # Isotropic new direction.
        z = 1.0 - 2.0 * rng.random(idx.size)
        a = 2.0 * np.pi * rng.random(idx.size)
        r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
        d = np.stack([r * np.cos(a), r * np.sin(a), z], axis=1)
    walk.exit_mu = emu
    return side, n, ex, ey


def mean_se(v):
    return float(v.mean()), float(v.std(ddof=1) / np.sqrt(v.size))


def totals(side, n, albedo):
    w = albedo ** n.astype(np.float64)
    front, back = side == 1, side == -1
    out = {}
    for name, sel in [
        ("T_ms", front & (n >= 2)),
        ("R_ms", back & (n >= 2)),
        ("T_ss", front & (n == 1)),
        ("R_ss", back & (n == 1)),
        ("T_direct", front & (n == 0)),
    ]:
        out[name], out[name + "_se"] = mean_se(np.where(sel, w, 0.0))
    return out


def table(photons, seed):
    rng = np.random.default_rng(seed)
    rows = []
    for tau in TAUS:
        for mu0 in MU0S:
            side, n, _, _ = walk(tau, mu0, photons, rng)
            for mat, alb in ALBEDOS.items():
                for c, a in enumerate(alb):
                    row = {"tau": tau, "mu0": mu0, "material": mat, "channel": c, "albedo": a}
                    row.update(totals(side, n, a))
                    rows.append(row)
            print(f"tau {tau} mu0 {mu0} done", file=sys.stderr)
    return rows


def profile(tau, photons, seed, albedo):
    rng = np.random.default_rng(seed)
    side, n, ex, ey = walk(tau, 1.0, photons, rng)
    rho = np.hypot(ex, ey)
    w = albedo ** n.astype(np.float64)
    edges = np.concatenate([[0.0], np.geomspace(0.05, 20.0 * max(tau, 1.0), 40)])
    area = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    out = []
    for s, name in [(1, "T"), (-1, "R")]:
        sel = (side == s) & (n >= 2)
        h, _ = np.histogram(rho[sel], bins=edges, weights=w[sel])
        out.append((name, (h / photons / area).tolist()))
    return {"tau": tau, "albedo": albedo, "edges": edges.tolist(), **dict(out)}


def lobe(tau, albedo, photons, seed, bins=10):
    """Exit radiance of multiple scattering over exit cosine, transmitted and reflected, each
    normalised to its exitance (1 everywhere for a Lambertian exit): p(mu) = dF/dmu / (2 mu F)."""
    rng = np.random.default_rng(seed)
    side, n, _, _ = walk(tau, 1.0, photons, rng)
    mu = walk.exit_mu
    w = albedo ** n.astype(np.float64)
    edges = np.linspace(0.0, 1.0, bins + 1)
    mid = 0.5 * (edges[1:] + edges[:-1])
    out = {"tau": tau, "albedo": albedo, "mu": mid.tolist()}
    for s_, name in [(1, "T"), (-1, "R")]:
        sel = (side == s_) & (n >= 2)
        h, _ = np.histogram(mu[sel], bins=edges, weights=w[sel])
        out[name] = (h / (edges[1] - edges[0]) / (2 * mid) / h.sum()).tolist()
    return out


def material(name, mm, mu0, photons, seed):
    """T_ms, R_ms per channel (+- standard error) of a slab `mm` millimetres of a material of
    validation/cases.json (sigma_t = sigma_s' + sigma_a per mm, isotropic)."""
    import os
    cases = json.load(open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "cases.json")))
    m = cases["materials"][name]
    rng = np.random.default_rng(seed)
    out = {"material": name, "mm": mm, "mu0": mu0, "photons": photons, "seed": seed, "channels": []}
    for c in range(3):
        st = m["sigma_s_prime"][c] + m["sigma_a"][c]
        side, n, _, _ = walk(st * mm, mu0, photons, rng)
        t = totals(side, n, m["sigma_s_prime"][c] / st)
        out["channels"].append({"tau": st * mm, "albedo": m["sigma_s_prime"][c] / st,
                                "T_ms": t["T_ms"], "T_ms_se": t["T_ms_se"], "R_ms": t["R_ms"], "R_ms_se": t["R_ms_se"]})
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("what", choices=["table", "profile", "material", "lobe"])
    p.add_argument("--name", default="marble")
    p.add_argument("--mm", type=float, default=3.0)
    p.add_argument("--mu0", type=float, default=1.0)
    p.add_argument("--photons", type=int, default=200_000)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--tau", type=float, default=5.0)
    p.add_argument("--albedo", type=float, default=0.999)
    a = p.parse_args()
    if a.what == "table":
        json.dump(table(a.photons, a.seed), sys.stdout, indent=1)
    elif a.what == "lobe":
        json.dump(lobe(a.tau, a.albedo, a.photons, a.seed), sys.stdout)
    elif a.what == "material":
        json.dump(material(a.name, a.mm, a.mu0, a.photons, a.seed), sys.stdout, indent=1)
    else:
        json.dump(profile(a.tau, a.photons, a.seed, a.albedo), sys.stdout)


if __name__ == "__main__":
    main()
