//! One-point transport estimates `A_E R_d(x_E, x_o)` (Mertens et al. 2003, §4.2: the far-field
//! link coefficient, and the quantity the transport oracle of §5.2 compares) in `f32`, four
//! points at a time.
//!
//! The oracle asks for the estimate between a receiver and an emitter, then between the
//! receiver and the emitter's children, then between the receiver's children and the emitter:
//! twelve dipole evaluations (four points × three channels) per question, each with two
//! exponentials. They are laid out as twelve lanes so the compiler vectorises the square roots,
//! divisions and a polynomial `exp` ([`exp_neg`](crate::fastexp::exp_neg)) on any x86-64 or AArch64 target; the
//! library `expf` is a scalar call and was a tenth of the solve.

use crate::bssrdf::Dipole;
use crate::bssrdf::profile::TABLE_SIZE;
use crate::fastexp::exp_neg;
use crate::formfactor::cubature;
use glam::Vec3;

/// Lanes of one batch: four points × three colour channels (lane `4 k + c` unused for `c = 3`
/// would waste a quarter; instead lane `3 j + c` is point `j`, channel `c`).
const LANES: usize = 12;

/// The profile's coefficients in `f32` for the hot loops (see [`Dipole`] for their meaning;
/// lengths in mesh units).
#[derive(Clone, Debug)]
pub struct DipoleF32 {
    /// `sigma_tr` per channel, per mesh unit.
    pub sigma_tr: [f32; 3],
    /// `z_r` per channel, mesh units.
    pub z_r: [f32; 3],
    /// `z_v` per channel, mesh units.
    pub z_v: [f32; 3],
    /// `alpha' / 4π` per channel.
    pub k: [f32; 3],
    /// 1 where the poles sit on the receiver's normal (Mertens), 0 for the distance form
    /// (poles at the receiver point, `z` away in distance).
    pub normal_weight: f32,
    /// Squared distances added to the real and virtual poles' (`z²` in the distance form, 0
    /// for Mertens), per channel.
    off_r: [f32; 3],
    off_v: [f32; 3],
    /// Squared length (per channel) on which the profile is smooth at the receiver point, for
    /// the oracle's error estimates: `z_r²` for the analytic distance form; a tabulated profile
    /// with single scattering peaks like `1/r` there, so a tenth of `z_r`.
    near_off: [f32; 3],
    /// Whether the analytic poles are part of the profile (all but PBD).
    analytic: bool,
    /// The tabulated part, if any.
    table: Option<TableF32>,
    /// The same coefficients repeated over the [`LANES`] of a batch.
    lanes: Lanes,
}

#[derive(Clone, Copy, Debug)]
struct Lanes {
    sigma_tr: [f32; LANES],
    z_r: [f32; LANES],
    z_v: [f32; LANES],
    k: [f32; LANES],
    off_r: [f32; LANES],
    off_v: [f32; LANES],
}

/// A tabulated profile in `f32`: `r R(r)` per channel on the grid of [`RadialTable`].
#[derive(Clone, Debug)]
struct TableF32 {
    /// Channel `c`'s `TABLE_SIZE + 1` samples start at `c (TABLE_SIZE + 1)`.
    values: Vec<f32>,
    inv_r_max: [f32; 3],
    r_floor: [f32; 3],
}

impl TableF32 {
    /// `R(r)` in channel `c` from the squared distance `s2` to the receiver point.
    #[inline(always)]
    fn radial(&self, c: usize, s2: f32) -> f32 {
        const N: usize = TABLE_SIZE;
        let r = s2.sqrt();
        let x = (r * self.inv_r_max[c]).sqrt() * N as f32;
        if x.is_nan() || x >= N as f32 {
            return 0.0;
        }
        let i = x as usize;
        let f = x - i as f32;
        let base = c * (N + 1) + i;
        let w = self.values[base] * (1.0 - f) + self.values[base + 1] * f;
        w / r.max(self.r_floor[c])
    }
}

impl DipoleF32 {
    /// The `f32` copy of `d`.
    pub fn new(d: &Dipole) -> Self {
        let sigma_tr = d.sigma_tr.map(|v| v as f32);
        let z_r = d.z_r.map(|v| v as f32);
        let z_v = d.z_v.map(|v| v as f32);
        let k = d.alpha_prime.map(|v| (v / (4.0 * std::f64::consts::PI)) as f32);
        let normal_weight = if d.profile.uses_normals() { 1.0 } else { 0.0 };
        let off = |z: [f32; 3]| z.map(|z| (1.0 - normal_weight) * z * z);
        let (off_r, off_v) = (off(z_r), off(z_v));
        let near_off = match &d.tables {
            Some(_) => off(z_r.map(|z| 0.1 * z)),
            None => off_r,
        };
        let table = d.tables.as_ref().map(|t| TableF32 {
            values: t.channels.iter().flat_map(|c| c.r_radial.iter().copied()).collect(),
            inv_r_max: std::array::from_fn(|c| (1.0 / t.channels[c].r_max) as f32),
            r_floor: std::array::from_fn(|c| t.channels[c].r_floor as f32),
        });
        let rep = |a: [f32; 3]| std::array::from_fn(|i| a[i % 3]);
        DipoleF32 {
            sigma_tr,
            z_r,
            z_v,
            k,
            normal_weight,
            off_r,
            off_v,
            near_off,
            analytic: d.has_analytic(),
            table,
            lanes: Lanes {
                sigma_tr: rep(sigma_tr),
                z_r: rep(z_r),
                z_v: rep(z_v),
                k: rep(k),
                off_r: rep(off_r),
                off_v: rep(off_v),
            },
        }
    }

    /// `area R` per lane from the squared distances to the real (`s2_r`) and virtual
    /// (`s2_v`) poles' points (Jensen et al. 2001, eq. 5, with `k = α'/4π`), plus the table.
    #[inline(always)]
    fn rd_lanes(&self, s2_r: &[f32; LANES], s2_v: &[f32; LANES], area: &[f32; LANES]) -> [f32; LANES] {
        let l = &self.lanes;
        let mut out = [0.0f32; LANES];
        if self.analytic {
            for i in 0..LANES {
                let sig = l.sigma_tr[i];
                out[i] = l.k[i]
                    * (pole(l.z_r[i], sig, s2_r[i] + l.off_r[i]) + pole(l.z_v[i], sig, s2_v[i] + l.off_v[i]));
            }
        }
        if let Some(t) = &self.table {
            for i in 0..LANES {
                out[i] += t.radial(i % 3, s2_r[i]);
            }
        }
        for i in 0..LANES {
            out[i] *= area[i];
        }
        out
    }

    /// `R` in channel `c` from the squared distances to the poles' points: the same arithmetic
    /// as one lane of [`DipoleF32::rd_lanes`], so scalar and batched estimates agree exactly.
    #[inline(always)]
    fn rd_one(&self, c: usize, s2_r: f32, s2_v: f32) -> f32 {
        let mut v = 0.0f32;
        if self.analytic {
            let sig = self.sigma_tr[c];
            v = self.k[c]
                * (pole(self.z_r[c], sig, s2_r + self.off_r[c])
                    + pole(self.z_v[c], sig, s2_v + self.off_v[c]));
        }
        if let Some(t) = &self.table {
            v += t.radial(c, s2_r);
        }
        v
    }
}

/// One source's term of `R_d`, `z (1 + σ s) e^{-σ s} / s³`, from the squared distance `s2`.
#[inline(always)]
fn pole(z: f32, sigma_tr: f32, s2: f32) -> f32 {
    let s = s2.sqrt();
    z * (1.0 + sigma_tr * s) * exp_neg(-sigma_tr * s) / (s2 * s)
}

/// The poles of one receiver point (the profile sits at the receiver, §4's inverse
/// interpretation): for Mertens real sources `x_o - z_r n_o` and virtual sources
/// `x_o + z_v n_o` per channel; for the distance-form profiles both at `x_o` (their `z`
/// enters as an added squared distance).
#[derive(Clone, Copy, Debug)]
pub struct ReceiverSources {
    x_r: [Vec3; 3],
    x_v: [Vec3; 3],
}

impl ReceiverSources {
    /// The sources for receiver point `x_o` with unit normal `n_o`.
    #[inline]
    pub fn new(d: &DipoleF32, x_o: Vec3, n_o: Vec3) -> Self {
        let n = d.normal_weight * n_o;
        ReceiverSources {
            x_r: std::array::from_fn(|c| x_o - d.z_r[c] * n),
            x_v: std::array::from_fn(|c| x_o + d.z_v[c] * n),
        }
    }

    /// Whether every pole is farther from `p` than `margin + base + spread z` (its own `z`;
    /// distances include the distance form's added `z²`): the poles of all points within
    /// `base` of the receiver point whose normals stray by at most `spread` stay `margin` away
    /// from `p`. The distance form keeps the `spread z` margin although its poles do not move
    /// with the normal: a curved receiver's leaves lie off its midpoint by about that much.
    #[inline]
    pub fn clear_of(&self, d: &DipoleF32, p: Vec3, margin: f32, base: f32, spread: f32) -> bool {
        (0..3).all(|c| {
            let rr = margin + base + spread * d.z_r[c];
            let rv = margin + base + spread * d.z_v[c];
            (self.x_r[c] - p).length_squared() + d.off_r[c] > rr * rr
                && (self.x_v[c] - p).length_squared() + d.off_v[c] > rv * rv
        })
    }

    /// Distance from `p` to the nearer of the two poles, per channel (with the distance
    /// form's added `z²`): where `R` varies fastest.
    #[inline]
    pub fn nearest(&self, d: &DipoleF32, p: Vec3) -> [f32; 3] {
        std::array::from_fn(|c| {
            ((self.x_r[c] - p).length_squared() + d.near_off[c])
                .min((self.x_v[c] - p).length_squared() + d.near_off[c])
                .sqrt()
        })
    }

    /// One-point form factor `A R(p)` for an emitter of area `area` at `p`.
    #[inline]
    pub fn point_sample(&self, d: &DipoleF32, p: Vec3, area: f32) -> [f32; 3] {
        std::array::from_fn(|c| {
            area * d.rd_one(c, (self.x_r[c] - p).length_squared(), (self.x_v[c] - p).length_squared())
        })
    }

    /// [`ReceiverSources::point_sample`] for four emitters at once (pad with area 0).
    #[inline]
    pub fn point_samples(&self, d: &DipoleF32, p: &[Vec3; 4], area: &[f32; 4]) -> [[f32; 3]; 4] {
        let mut s2_r = [0.0f32; LANES];
        let mut s2_v = [0.0f32; LANES];
        for i in 0..LANES {
            let (j, c) = (i / 3, i % 3);
            s2_r[i] = (self.x_r[c] - p[j]).length_squared();
            s2_v[i] = (self.x_v[c] - p[j]).length_squared();
        }
        unpack(d.rd_lanes(&s2_r, &s2_v, &spread_area(area)))
    }
}

impl ReceiverSources {
    /// `∫_T R_d` over triangle `tri` (area `area`) by Radon's degree-5 rule
    /// ([`crate::formfactor::cubature`]): seven dipole points in two batches. The form
    /// factor's own short cut in `f32`, for where [`ReceiverSources::k_rho`] is small.
    #[inline]
    pub fn triangle_cubature(&self, d: &DipoleF32, tri: &[Vec3; 3], area: f32) -> [f32; 3] {
        let [a, b, c] = tri.map(|p| p.as_dvec3());
        let mut pts = [Vec3::ZERO; 8];
        let mut wts = [0.0f32; 8];
        for (k, (p, w)) in cubature::radon7(a, b, c).into_iter().enumerate() {
            pts[k] = p.as_vec3();
            wts[k] = w as f32 * area;
        }
        let lo = self.point_samples(d, &[pts[0], pts[1], pts[2], pts[3]], &[wts[0], wts[1], wts[2], wts[3]]);
        let hi = self.point_samples(d, &[pts[4], pts[5], pts[6], pts[7]], &[wts[4], wts[5], wts[6], 0.0]);
        std::array::from_fn(|ch| lo.iter().chain(&hi).map(|f| f[ch]).sum())
    }

    /// `k ρ` of an emitter with midpoint `mid` and radius `radius`: the largest over channels
    /// of `(σ_tr + 3/s) ρ`, `s` the distance from `mid` to the nearer source (see
    /// [`cubature::MAX_K_RHO`]).
    #[inline]
    pub fn k_rho(&self, d: &DipoleF32, mid: Vec3, radius: f32) -> f32 {
        let s = self.nearest(d, mid);
        (0..3).map(|c| (d.sigma_tr[c] + 3.0 / s[c]) * radius).fold(0.0, f32::max)
    }
}

/// One emitter of area `area` at `p` seen from four receivers' sources:
/// `[src[j].point_sample(d, p, area); 4]`, batched.
#[inline]
pub fn point_samples_from(src: &[ReceiverSources; 4], d: &DipoleF32, p: Vec3, area: f32) -> [[f32; 3]; 4] {
    let mut s2_r = [0.0f32; LANES];
    let mut s2_v = [0.0f32; LANES];
    for i in 0..LANES {
        let (j, c) = (i / 3, i % 3);
        s2_r[i] = (src[j].x_r[c] - p).length_squared();
        s2_v[i] = (src[j].x_v[c] - p).length_squared();
    }
    unpack(d.rd_lanes(&s2_r, &s2_v, &[area; LANES]))
}

#[inline(always)]
fn spread_area(area: &[f32; 4]) -> [f32; LANES] {
    std::array::from_fn(|i| area[i / 3])
}

#[inline(always)]
fn unpack(v: [f32; LANES]) -> [[f32; 3]; 4] {
    std::array::from_fn(|j| [v[3 * j], v[3 * j + 1], v[3 * j + 2]])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bssrdf::Material;

    #[test]
    fn batches_match_the_f64_dipole() {
        let m = Material::by_name("skimmilk").unwrap();
        let dip = Dipole::for_model_scale(&m, 1.0, 0.05);
        let d = DipoleF32::new(&dip);
        let x_o = Vec3::new(0.1, -0.2, 0.05);
        let n_o = Vec3::new(0.3, 0.4, 0.866).normalize();
        let src = ReceiverSources::new(&d, x_o, n_o);
        let p = [Vec3::new(0.3, 0.1, 0.0), Vec3::new(-0.2, 0.0, 0.1), Vec3::new(0.1, -0.15, 0.05), Vec3::X];
        let area = [0.01, 0.02, 0.003, 0.0];
        let got = src.point_samples(&d, &p, &area);
        for j in 0..4 {
            let want = dip.rd(x_o.as_dvec3(), n_o.as_dvec3(), p[j].as_dvec3());
            for c in 0..3 {
                let w = want[c] * area[j] as f64;
                assert!(
                    (got[j][c] as f64 - w).abs() <= 1e-5 * w.abs() + 1e-30,
                    "{j} {c}: {} vs {w}",
                    got[j][c]
                );
            }
        }
        // The oracle hands estimates from one form on as the other's: they must agree exactly.
        let from = point_samples_from(&[src; 4], &d, p[0], area[0]);
        assert_eq!(from[2], got[0]);
        for j in 0..4 {
            assert_eq!(src.point_sample(&d, p[j], area[j]), got[j]);
        }
    }

    #[test]
    fn triangle_cubature_matches_the_f64_rule() {
        let m = Material::by_name("marble").unwrap();
        let dip = Dipole::for_model_scale(&m, 1.0, 0.01);
        let d = DipoleF32::new(&dip);
        let (x_o, n_o) = (Vec3::new(0.01, 0.02, 0.0), Vec3::new(0.1, -0.2, 1.0).normalize());
        let src = ReceiverSources::new(&d, x_o, n_o);
        let tri = [Vec3::new(0.0, 0.0, 0.001), Vec3::new(0.02, 0.005, 0.0), Vec3::new(0.004, 0.03, -0.002)];
        let t64 = tri.map(|p| p.as_dvec3());
        let normal = (t64[1] - t64[0]).cross(t64[2] - t64[0]);
        let area = 0.5 * normal.length();
        let want = cubature::polygon_integral(&t64, normal.normalize(), x_o.as_dvec3(), n_o.as_dvec3(), &dip);
        let got = src.triangle_cubature(&d, &tri, area as f32);
        for c in 0..3 {
            assert!((got[c] as f64 / want[c] - 1.0).abs() < 1e-5, "{c}: {} vs {}", got[c], want[c]);
        }
        assert!(src.k_rho(&d, (tri[0] + tri[1] + tri[2]) / 3.0, 0.02) > 0.0);
    }
}
