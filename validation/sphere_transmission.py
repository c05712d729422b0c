#!/usr/bin/env python3
"""A sphere lit from one side by a collimated beam, by forward Monte Carlo: the ground truth of
lucent's transmission through curved bodies (issue 50; `bssrdf::sphere_walk` is the same
quantity by an independent, reciprocal estimator).

A sphere of radius R mean free paths (sigma_t = 1) scatters isotropically, with an
index-matched boundary (eta = 1, the validation suite's null boundary) or, with --eta, a smooth
dielectric one (each photon reflected with Fresnel's probability where it enters and each time
it meets the boundary from inside, total internal reflection included, else refracted; the
exit direction is the refracted one: `bssrdf::sphere_forward` walks the same). A collimated beam of
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


def fresnel(cos_i, eta):
    """Unpolarised Fresnel reflectance arriving at cosine `cos_i` onto relative index `eta`
    (total internal reflection: 1)."""
    cos_i = np.clip(cos_i, 0.0, 1.0)
    sin2_t = (1 - cos_i * cos_i) / (eta * eta)
    cos_t = np.sqrt(np.maximum(1 - sin2_t, 0.0))
    r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return np.where(sin2_t >= 1, 1.0, 0.5 * (r_par ** 2 + r_perp ** 2))


def refract(d, m, ratio):
    """Unit directions `d` refracted through unit normals `m` facing against them, `ratio` the
    index they leave over the one they enter (no total internal reflection asked)."""
    cos_i = -np.einsum("ij,ij->i", d, m)
    cos_t = np.sqrt(np.maximum(1 - ratio * ratio * (1 - cos_i * cos_i), 0.0))
    t = ratio * d + (ratio * cos_i - cos_t)[:, None] * m
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def walk(radius, photons, rng, max_steps=10**7, directions=False, eta=1.0):
    """Exit cosine with +z (the exit point's z / R) and scatterings n of each photon; with
    `directions`, also each photon's exit point and direction (outside). A photon reflected
    where it enters leaves with n = -1 (never scored)."""
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
    if eta != 1.0:
        m = pos / radius
        enter = rng.random(photons) >= fresnel(-m[:, 2], eta)
        n[~enter] = -1
        d = refract(d, m, 1.0 / eta)
        idx, pos, d = idx[enter], pos[enter], d[enter]
    for _ in range(max_steps):
        if idx.size == 0:
            break
        s = -np.log1p(-rng.random(idx.size))
        b = np.einsum("ij,ij->i", pos, d)
        c = np.einsum("ij,ij->i", pos, pos) - radius * radius
        to_exit = -b + np.sqrt(np.maximum(b * b - c, 0.0))
        hit = s >= to_exit
        out = hit
        if eta != 1.0 and hit.any():
            # At the boundary: reflected back in with Fresnel's probability, else out.
            p_hit = pos[hit] + d[hit] * to_exit[hit, None]
            m = p_hit / radius
            cos = np.einsum("ij,ij->i", d[hit], m)
            back = rng.random(cos.size) < fresnel(cos, 1.0 / eta)
            out = hit.copy()
            out[np.flatnonzero(hit)[back]] = False
            sel = np.flatnonzero(hit)[back]
            pos[sel] = p_hit[back] * (1 - 1e-12)
            d[sel] = d[sel] - 2 * np.einsum("ij,ij->i", d[sel], m[back])[:, None] * m[back]
            s[sel] = 0.0
        if out.any():
            p_out = pos[out] + d[out] * to_exit[out, None]
            exit_z[idx[out]] = p_out[:, 2] / radius
            d_out = d[out] if eta == 1.0 else refract(d[out], -p_out / radius, eta)
            exit_p[idx[out]], exit_d[idx[out]] = p_out, d_out
        # Reflected photons moved to the boundary already and take no step (and add no
        # scattering) this round.
        refl = hit & ~out
        keep = ~out
        idx, pos, d, s, refl = idx[keep], pos[keep], d[keep], s[keep], refl[keep]
        step = ~refl
        pos[step] = pos[step] + d[step] * s[step, None]
        n[idx[step]] += 1
        k = int(step.sum())
        u = 1 - 2 * rng.random(k)
        phi = 2 * np.pi * rng.random(k)
        st = np.sqrt(np.maximum(0.0, 1 - u * u))
        d[step] = np.stack([st * np.cos(phi), st * np.sin(phi), u], axis=1)
    return (exit_z, n, exit_p, exit_d) if directions else (exit_z, n)


def exit_directions(radius, albedo, photons, seed, edges_deg, eta=1.0):
    """Per bin of theta: (lo, hi, mean normal cosine, mean tangent cosine, back / on flux) of
    the multiply scattered light leaving there (module docs)."""
    exit_z, n, p, d = walk(radius, photons, np.random.default_rng(seed), directions=True, eta=eta)
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


def transmitted(radius, albedos, photons, seed, edges_deg, eta=1.0):
    """T per bin of theta (edges in degrees from the antipode) and albedo, and standard errors."""
    rng = np.random.default_rng(seed)
    exit_z, n = walk(radius, photons, rng, eta=eta)
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
    p.add_argument("--eta", type=float, default=1.0, help="the boundary's relative index (1: index-matched)")
    p.add_argument("--json", action="store_true")
    p.add_argument("--directions", action="store_true", help="where the light goes as it leaves (--radius, one --albedo)")
    a = p.parse_args()
    if a.directions:
        for lo, hi, mu_n, mu_t, ratio in exit_directions(a.radius, a.albedo[0], a.photons, a.seed, a.edges, a.eta):
            print(f"  theta {lo:5.1f}-{hi:5.1f} deg: mean cos to normal {mu_n:.3f}, to the tangent away "
                  f"from the lit pole {mu_t:+.3f}, back / on flux {ratio:.2f}")
        return
    out = []
    if a.material:
        sp, sa = MATERIALS[a.material]
        for c in range(3):
            st = sp[c] + sa[c]
            rows = transmitted(a.mm * st, [sp[c] / st], a.photons, a.seed + c, a.edges, a.eta)
            out.append({"channel": "RGB"[c], "radius_mfp": a.mm * st, "albedo": sp[c] / st,
                        "bins": [[lo, hi, r[0][0], r[0][1]] for (lo, hi), r in rows]})
    else:
        rows = transmitted(a.radius, a.albedo, a.photons, a.seed, a.edges, a.eta)
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
