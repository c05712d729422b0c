#!/usr/bin/env python3
"""The multiple-scattering albedo of a sphere against a half-space, by an analog random walk.

An independent check of lucent's finite-body gain (crates/lucent-core/src/bssrdf/walk.rs),
written separately in numpy. A sphere of radius R (mean free paths, isotropic scattering with
albedo rho, a smooth boundary of relative index eta) is lit uniformly: light arrives with the
Lambertian distribution of outside cosines, Fresnel's transmittance weights what enters, and
photons walk until they leave (internal reflection sampled with Fresnel's reflectance) or are
absorbed. What leaves is split as lucent splits it:

* unscattered light is not reflection at all;
* direct single scattering (one scattering, no internal reflection) is what lucent computes along
  the view ray with the real geometry;
* everything else is multiple scattering, what the diffusion profile and its gain carry.

The gain is the sphere's multiple scattering over the half-space's (a sphere of 1e5 mean free
paths, lit at its pole with the same cosines).

    python3 validation/sphere_walk.py RHO ETA R [R ...]     # numpy only

Prints, per radius, the gain with its Monte Carlo standard error. Read in validation/README.md
("Finite bodies by random walk").
"""

import sys

import numpy as np


def fresnel_dielectric(cos_i, eta):
    """Unpolarised Fresnel reflectance for light at cosine cos_i going into relative index eta."""
    cos_i = np.clip(cos_i, 0.0, 1.0)
    sin_t2 = (1.0 - cos_i**2) / eta**2
    out = np.ones_like(cos_i)
    ok = sin_t2 < 1.0
    cos_t = np.sqrt(1.0 - sin_t2[ok])
    ci = cos_i[ok]
    rs = (ci - eta * cos_t) / (ci + eta * cos_t)
    rp = (eta * ci - cos_t) / (eta * ci + cos_t)
    out[ok] = 0.5 * (rs**2 + rp**2)
    return out


def walk(rho, eta, radius, n, rng, pole_only=False):
    """Per-photon multiple-scattering exitance of a sphere of `radius` (optical units)."""
    # Lambertian outside cosines, refracted inside, weighted by Fresnel's transmittance.
    mu_i = np.sqrt((np.arange(n) + rng.random(n)) / n)
    weight = 1.0 - fresnel_dielectric(mu_i, eta)
    mu_t = np.sqrt(np.maximum(1.0 - (1.0 - mu_i**2) / eta**2, 0.0))
    phi = 2.0 * np.pi * rng.random(n)
    s_t = np.sqrt(1.0 - mu_t**2)
    pos = np.zeros((n, 3))
    pos[:, 2] = radius
    d = np.stack([s_t * np.cos(phi), s_t * np.sin(phi), -mu_t], 1)
    scatters = np.zeros(n, int)
    reflected = np.zeros(n, bool)
    alive = np.ones(n, bool)
    out = np.zeros(n)
    while alive.any():
        i = np.nonzero(alive)[0]
        p, di = pos[i], d[i]
        step = -np.log(1.0 - rng.random(len(i)))
        b = np.sum(p * di, 1)
        c = np.sum(p * p, 1) - radius * radius
        t_exit = -b + np.sqrt(np.maximum(b * b - c, 0.0))
        hit = step >= t_exit
        # At the boundary: internal reflection or escape.
        h = i[hit]
        q = p[hit] + di[hit] * t_exit[hit, None]
        normal = q / radius
        mu = np.sum(di[hit] * normal, 1)
        refl = rng.random(len(h)) < fresnel_dielectric(mu, 1.0 / eta)
        rh = h[refl]
        pos[rh] = q[refl]
        d[rh] = di[hit][refl] - 2.0 * mu[refl, None] * normal[refl]
        reflected[rh] = True
        eh = h[~refl]
        multiple = (scatters[eh] >= 2) | ((scatters[eh] == 1) & reflected[eh])
        out[eh] = np.where(multiple, weight[eh], 0.0)
        alive[eh] = False
        # In the medium: scatter isotropically, absorbing by weight; roulette faint photons.
        s = i[~hit]
        pos[s] = p[~hit] + di[~hit] * step[~hit, None]
        weight[s] *= rho
        scatters[s] += 1
        z = 1.0 - 2.0 * rng.random(len(s))
        a = 2.0 * np.pi * rng.random(len(s))
        r = np.sqrt(1.0 - z * z)
        d[s] = np.stack([r * np.cos(a), r * np.sin(a), z], 1)
        faint = s[weight[s] < 0.1]
        dies = rng.random(len(faint)) < 0.5
        alive[faint[dies]] = False
        weight[faint[~dies]] *= 2.0
    return out


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    rho, eta = float(sys.argv[1]), float(sys.argv[2])
    rng = np.random.default_rng(2026)
    n = 200_000
    half = walk(rho, eta, 1e5, n, rng)
    h_mean, h_err = half.mean(), half.std() / np.sqrt(n)
    print(f"rho {rho} eta {eta}: half-space multiple-scattering albedo {h_mean:.5f} +- {h_err:.5f}")
    for radius in map(float, sys.argv[3:]):
        s = walk(rho, eta, radius, n, rng)
        g = s.mean() / h_mean
        err = g * np.hypot(s.std() / np.sqrt(n) / s.mean(), h_err / h_mean)
        print(f"R {radius:8.3f} mfp: gain {g:.4f} +- {err:.4f}")


if __name__ == "__main__":
    main()
