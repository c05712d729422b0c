#!/usr/bin/env python3
"""How much more light a finite body returns than the half-space a diffusion profile assumes.

Every profile lucent has (and every radial BSSRDF) is fitted to a flat, semi-infinite medium.
On a sphere, the area at chord distance below r is exactly pi r^2, as on a plane, so a radial
profile integrated over a sphere gives the half-space total: whatever the profile, lucent's
sphere under uniform light returns R_d_total. Light that in a half-space wanders deep and is
absorbed reaches another part of a finite body's boundary instead, so the truth is higher.

This script measures that gain in diffusion theory: the radially symmetric diffusion equation
in a sphere of radius a under uniform irradiance (first-collision source converging as (a/r)^2,
extrapolated boundary phi = 2 A D dphi/dn), against the same solve in a half-space, on the
same grid (20 cells per mean free path) so discretisation cancels in the ratio. For each case
of cases.json it prints the gain per channel for the sphere of radius 3V/S (the sphere's own
radius; for the bunny, the sphere with its volume-to-area ratio) and, for meshes, the
area-weighted gain over per-face spheres of half the inward-normal thickness.

    python3 validation/finite_body.py          # numpy only; a few seconds

Read in validation/README.md ("Why the small sphere is dark").
"""

import json
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def fresnel_diffuse_reflectance(eta):
    """Egan & Hilgeman's fit of F_dr (Jensen et al. 2001, eq. for A)."""
    return -1.440 / eta**2 + 0.710 / eta + 0.668 + 0.0636 * eta


def tridiagonal_solve(lower, diag, upper, rhs):
    n = len(rhs)
    d, b = diag.copy(), rhs.copy()
    for i in range(1, n):
        w = lower[i - 1] / d[i - 1]
        d[i] -= w * upper[i - 1]
        b[i] -= w * b[i - 1]
    x = np.zeros(n)
    x[-1] = b[-1] / d[-1]
    for i in range(n - 2, -1, -1):
        x[i] = (b[i] - upper[i] * x[i + 1]) / d[i]
    return x


def diffuse_albedo(depth_mm, sigma_s, sigma_a, big_a, sphere):
    """Radiant exitance per unit irradiance of a sphere of radius `depth_mm` (or a half-space
    cut at that depth) under uniform normal irradiance, in diffusion theory."""
    sigma_t = sigma_s + sigma_a
    d_coef = 1.0 / (3.0 * sigma_t)
    h0 = 0.05 / sigma_t
    n = max(int(depth_mm / h0), 50)
    h = depth_mm / n
    r = np.linspace(0.0, depth_mm, n + 1)
    source = sigma_s * np.exp(-sigma_t * (depth_mm - r))
    i = np.arange(1, n)
    if sphere:
        source = source * (depth_mm / np.maximum(r, h)) ** 2  # beams converge: power is conserved
        outer, inner, mid = (r[i] + h / 2) ** 2, (r[i] - h / 2) ** 2, r[i] ** 2
    else:
        outer = inner = mid = np.ones(n - 1)
    lower, diag, upper = np.zeros(n), np.zeros(n + 1), np.zeros(n)
    lower[i - 1] = d_coef * inner / (mid * h * h)
    upper[i] = d_coef * outer / (mid * h * h)
    diag[i] = -d_coef * (outer + inner) / (mid * h * h) - sigma_a
    rhs = -source
    diag[0], upper[0], rhs[0] = -1.0, 1.0, 0.0  # zero flux at the centre (or deep down)
    diag[n], lower[n - 1], rhs[n] = 1.0 + 2.0 * big_a * d_coef / h, -2.0 * big_a * d_coef / h, 0.0
    phi = tridiagonal_solve(lower, diag, upper, rhs)
    return phi[n] / (2.0 * big_a)


def gain(radius_mm, sigma_s, sigma_a, eta):
    """Sphere albedo over half-space albedo, one channel."""
    fdr = fresnel_diffuse_reflectance(eta) if eta > 1.0 else 0.0
    big_a = (1.0 + fdr) / (1.0 - fdr)
    sigma_tr = np.sqrt(3.0 * sigma_a * (sigma_s + sigma_a))
    half_space = diffuse_albedo(30.0 / sigma_tr, sigma_s, sigma_a, big_a, sphere=False)
    return diffuse_albedo(radius_mm, sigma_s, sigma_a, big_a, sphere=True) / half_space


def load_obj(path):
    v, f = [], []
    for line in open(path):
        s = line.split()
        if s and s[0] == "v":
            v.append([float(x) for x in s[1:4]])
        elif s and s[0] == "f":
            f.append([int(x.split("/")[0]) - 1 for x in s[1:4]])
    return np.array(v), np.array(f)


def inward_thickness(v, f):
    """Distance from each face's centroid along its inward normal to the next surface."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    e1, e2 = b - a, c - a
    n = np.cross(e1, e2)
    n /= np.linalg.norm(n, axis=1)[:, None]
    centroid = (a + b + c) / 3.0
    hits = np.full(len(f), np.inf)
    for k in range(len(f)):
        d = -n[k]
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = centroid[k] - a
        u = np.einsum("ij,ij->i", s, p) * inv
        q = np.cross(s, e1)
        w = (q @ d) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        hit = ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (t > 1e-6)
        if hit.any():
            hits[k] = t[hit].min()
    return hits, 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1)


def main():
    cfg = json.load(open(os.path.join(HERE, "cases.json")))
    bunny = load_obj(os.path.join(ROOT, "assets", "bunny.obj"))
    v, f = bunny
    extent = float((v.max(0) - v.min(0)).max())
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    volume = float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)
    thickness, area = inward_thickness(v, f)
    bunny_ratio = 3.0 * volume / (float(area.sum()) * extent)  # 3V/S over the extent
    print(f"bunny: 3V/S = {bunny_ratio:.3f} of its extent; inward thickness median "
          f"{np.median(thickness) / extent:.3f} of it")
    print(f"{'case':24} {'3V/S mm':>8}  gain R/G/B (sphere of 3V/S)   gain R/G/B (per-face thickness)")
    for case in cfg["cases"]:
        mat = cfg["materials"][case["material"]]
        size_mm = case["scale"] * 1000.0
        radius = size_mm * (0.5 if case["mesh"] == "sphere" else bunny_ratio)
        g = [gain(radius, s, a_, case["eta"]) for s, a_ in zip(mat["sigma_s_prime"], mat["sigma_a"])]
        local = ""
        if case["mesh"] == "bunny":
            radii = np.geomspace(0.2, 500.0, 48)
            per_face = np.where(np.isfinite(thickness), 0.5 * thickness / extent * size_mm, radii[-1])
            gl = []
            for s, a_ in zip(mat["sigma_s_prime"], mat["sigma_a"]):
                table = np.array([gain(x, s, a_, case["eta"]) for x in radii])
                gl.append(float((np.interp(np.log(per_face), np.log(radii), table) * area).sum() / area.sum()))
            local = " ".join(f"{x:.3f}" for x in gl)
        print(f"{case['name']:24} {radius:8.1f}  {' '.join(f'{x:.3f}' for x in g):27}  {local}")


if __name__ == "__main__":
    main()
