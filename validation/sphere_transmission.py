#!/usr/bin/env python3
"""A sphere lit from one side by a collimated beam, by forward Monte Carlo: the ground truth of
lucent's transmission through curved bodies (issue 50; `bssrdf::sphere_walk` is the same
quantity by an independent, reciprocal estimator).

A sphere of radius R mean free paths (sigma_t = 1) scatters isotropically, with an
index-matched boundary (eta = 1, the validation suite's null boundary). A collimated beam of
irradiance 1 travels along +z and lights the hemisphere z < 0; photons enter uniformly over
the beam's cross-section (the disk of radius R), walk with albedo 1, and each one's number of
scatterings n is kept, so that any albedo a weights it by a**n afterwards: one walk serves every
material. Only multiple scattering is scored (n >= 2; n = 0 is unscattered light, n = 1 the
view ray's single scattering), where it leaves, in bins of the angle theta from the antipode
of the lit pole (the point (0, 0, R)): T(theta) is the exit flux density there per unit
incident irradiance, with its standard error.

    python3 validation/sphere_transmission.py --radius 5 --albedo 0.999 [--photons N] [--seed S]
    python3 validation/sphere_transmission.py --material marble --mm 10   # a marble sphere, 2 cm

Output: one line per angular bin (degrees from the antipode): T per albedo and its standard
error (JSON with --json).

    python3 validation/sphere_transmission.py --radius 5 --albedo 0.999 --directions

With --directions, where the transmitted light goes as it leaves, per bin: its mean cosine with
the normal (2/3 for a Lambertian exit), its mean cosine with the tangent pointing away from the
lit pole (0 for a Lambertian exit; positive: the light flows on, away from the lit side), and
the flux leaving tilted back toward the lit side over the flux tilted on (tangent cosine below
-0.5 against above 0.5; 1 for a Lambertian exit).
"""
import argparse
import json

import numpy as np

# Reduced scattering and absorption per mm (Jensen et al. 2001, as validation/cases.json).
MATERIALS = {
    "marble": ([2.19, 2.62, 3.00], [0.0021, 0.0041, 0.0071]),
    "skimmilk": ([0.70, 1.22, 1.90], [0.0014, 0.0025, 0.0142]),
    "ketchup": ([0.18, 0.07, 0.03], [0.061, 0.97, 1.45]),
}


def walk(radius, photons, rng, max_steps=10**7, directions=False):
    """Exit cosine with +z (the exit point's z / R) and scatterings n of each photon; with
    `directions`, also each photon's exit point and direction."""
    # Entry: uniform over the disk, on the lit hemisphere.
    r = radius * np.sqrt(rng.random(photons))
    a = 2 * np.pi * rng.random(photons)
    x, y = r * np.cos(a), r * np.sin(a)
    z = -np.sqrt(np.maximum(radius * radius - x * x - y * y, 0.0))
    pos = np.stack([x, y, z], axis=1)
    d = np.tile([0.0, 0.0, 1.0], (photons, 1))
    n = np.zeros(photons, dtype=np.int64)
    exit_z = np.zeros(photons)
    exit_p, exit_d = np.zeros((photons, 3)), np.zeros((photons, 3))
    idx = np.arange(photons)
    for _ in range(max_steps):
        if idx.size == 0:
            break
        s = -np.log1p(-rng.random(idx.size))
        b = np.einsum("ij,ij->i", pos, d)
        c = np.einsum("ij,ij->i", pos, pos) - radius * radius
        to_exit = -b + np.sqrt(np.maximum(b * b - c, 0.0))
        out = s >= to_exit
        if out.any():
            p_out = pos[out] + d[out] * to_exit[out, None]
            exit_z[idx[out]] = p_out[:, 2] / radius
            exit_p[idx[out]], exit_d[idx[out]] = p_out, d[out]
        keep = ~out
        idx, pos, d, s = idx[keep], pos[keep], d[keep], s[keep]
        pos = pos + d * s[:, None]
        n[idx] += 1
        u = 1 - 2 * rng.random(idx.size)
        phi = 2 * np.pi * rng.random(idx.size)
        st = np.sqrt(np.maximum(0.0, 1 - u * u))
        d = np.stack([st * np.cos(phi), st * np.sin(phi), u], axis=1)
    return (exit_z, n, exit_p, exit_d) if directions else (exit_z, n)


def exit_directions(radius, albedo, photons, seed, edges_deg):
    """Per bin of theta: (lo, hi, mean normal cosine, mean tangent cosine, back / on flux) of
    the multiply scattered light leaving there (module docs)."""
    exit_z, n, p, d = walk(radius, photons, np.random.default_rng(seed), directions=True)
    theta = np.degrees(np.arccos(np.clip(exit_z, -1, 1)))
    w = np.where(n >= 2, np.power(float(albedo), n.astype(float)), 0.0)
    normal = p / radius
    away = np.array([0.0, 0.0, 1.0]) - normal[:, 2:3] * normal
    away /= np.maximum(np.linalg.norm(away, axis=1, keepdims=True), 1e-12)
    mu_n, mu_t = np.einsum("ij,ij->i", d, normal), np.einsum("ij,ij->i", d, away)
    rows = []
    for lo, hi in zip(edges_deg[:-1], edges_deg[1:]):
        m = (theta >= lo) & (theta < hi) & (w > 0)
        if w[m].sum() == 0:
            continue
        back, on = w[m & (mu_t < -0.5)].sum(), w[m & (mu_t > 0.5)].sum()
        rows.append((lo, hi, float(np.average(mu_n[m], weights=w[m])),
                     float(np.average(mu_t[m], weights=w[m])), float(back / on) if on > 0 else float("nan")))
    return rows


def transmitted(radius, albedos, photons, seed, edges_deg):
    """T per bin of theta (edges in degrees from the antipode) and albedo, and standard errors."""
    rng = np.random.default_rng(seed)
    exit_z, n = walk(radius, photons, rng)
    theta = np.degrees(np.arccos(np.clip(exit_z, -1, 1)))
    power = np.pi * radius * radius / photons  # each photon's share of the beam's power
    rows = []
    for lo, hi in zip(edges_deg[:-1], edges_deg[1:]):
        area = 2 * np.pi * radius * radius * (np.cos(np.radians(lo)) - np.cos(np.radians(hi)))
        inside = (theta >= lo) & (theta < hi) & (n >= 2)
        row = []
        for a in albedos:
            w = np.where(inside, np.power(float(a), n.astype(float)), 0.0) * power / area * photons
            row.append((float(w.mean()), float(w.std() / np.sqrt(photons))))
        rows.append(((lo, hi), row))
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--radius", type=float, help="radius in mean free paths")
    p.add_argument("--albedo", type=float, nargs="*", default=[])
    p.add_argument("--material", choices=sorted(MATERIALS))
    p.add_argument("--mm", type=float, help="radius in mm (with --material): one walk per channel")
    p.add_argument("--photons", type=int, default=200_000)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--edges", type=float, nargs="*", default=[0, 10, 20, 30, 45, 60, 90, 120, 180])
    p.add_argument("--json", action="store_true")
    p.add_argument("--directions", action="store_true", help="where the light goes as it leaves (--radius, one --albedo)")
    a = p.parse_args()
    if a.directions:
        for lo, hi, mu_n, mu_t, ratio in exit_directions(a.radius, a.albedo[0], a.photons, a.seed, a.edges):
            print(f"  theta {lo:5.1f}-{hi:5.1f} deg: mean cos to normal {mu_n:.3f}, to the tangent away "
                  f"from the lit pole {mu_t:+.3f}, back / on flux {ratio:.2f}")
        return
    out = []
    if a.material:
        sp, sa = MATERIALS[a.material]
        for c in range(3):
            st = sp[c] + sa[c]
            rows = transmitted(a.mm * st, [sp[c] / st], a.photons, a.seed + c, a.edges)
            out.append({"channel": "RGB"[c], "radius_mfp": a.mm * st, "albedo": sp[c] / st,
                        "bins": [[lo, hi, r[0][0], r[0][1]] for (lo, hi), r in rows]})
    else:
        rows = transmitted(a.radius, a.albedo, a.photons, a.seed, a.edges)
        for k, alb in enumerate(a.albedo):
            out.append({"radius_mfp": a.radius, "albedo": alb,
                        "bins": [[lo, hi, r[k][0], r[k][1]] for (lo, hi), r in rows]})
    if a.json:
        print(json.dumps(out, indent=1))
        return
    for o in out:
        print(f"{o.get('channel', '')} radius {o['radius_mfp']:.3f} mfp, albedo {o['albedo']:.5f}")
        for lo, hi, t, se in o["bins"]:
            print(f"  theta {lo:5.1f}-{hi:5.1f} deg: T {t:.5f} +- {se:.5f}")


if __name__ == "__main__":
    main()
