//! A receiver's gathered `B` as a local expansion about its midpoint (Mertens et al. 2003,
//! §5.5, with linear and curved receivers): its value, its gradient and its Hessian, what one
//! link of a given steepness adds to them, and the expansion moved to a child's midpoint for
//! the push. [`super::gather`] and [`super::gather_linear`] sum links into it.

use crate::solver::oracle::curvature_along;
use glam::Vec3A;

/// Per channel, the gradient of `B` (per mesh unit of length) at a receiver's midpoint.
pub(crate) type Grad = [Vec3A; 3];

/// Per channel, the Hessian of `B` (per mesh unit of length squared) at a receiver's
/// midpoint, symmetric: its diagonal (xx, yy, zz) and its off-diagonal (yz, xz, xy).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Hess {
    pub(super) diag: Grad,
    pub(super) off: Grad,
}

impl Hess {
    /// `self += o`, channel by channel.
    #[inline]
    fn add(&mut self, o: &Hess) {
        add_grad(&mut self.diag, &o.diag);
        add_grad(&mut self.off, &o.off);
    }

    /// Adds `w[c] dv dvᵀ + iso[c] I` to channel `c`.
    #[inline]
    fn add_link(&mut self, w: Vec3A, iso: Vec3A, dv: Vec3A) {
        let (dd, dx) = (dv * dv, Vec3A::new(dv.y * dv.z, dv.x * dv.z, dv.x * dv.y));
        for c in 0..3 {
            self.diag[c] += dd * w[c] + Vec3A::splat(iso[c]);
            self.off[c] += dx * w[c];
        }
    }

    /// Per channel `½ oᵀ H o`.
    #[inline]
    fn half_quad(&self, o: Vec3A) -> Vec3A {
        let (oo, ox) = (o * o, Vec3A::new(o.y * o.z, o.x * o.z, o.x * o.y));
        Vec3A::new(
            0.5 * self.diag[0].dot(oo) + self.off[0].dot(ox),
            0.5 * self.diag[1].dot(oo) + self.off[1].dot(ox),
            0.5 * self.diag[2].dot(oo) + self.off[2].dot(ox),
        )
    }

    /// Per channel `H o`.
    #[inline]
    fn apply(&self, o: Vec3A) -> Grad {
        std::array::from_fn(|c| {
            let (d, f) = (self.diag[c], self.off[c]);
            Vec3A::new(
                d.x * o.x + f.z * o.y + f.y * o.z,
                f.z * o.x + d.y * o.y + f.x * o.z,
                f.y * o.x + f.x * o.y + d.z * o.z,
            )
        })
    }
}

/// A receiver's gathered `B` as a local expansion about its midpoint: its value, its
/// gradient and (with curved receivers) its Hessian there.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Linear {
    pub(super) value: Vec3A,
    pub(super) grad: Grad,
    pub(super) hess: Hess,
}

impl Linear {
    /// Adds one link's `t = E F` with steepness `slope` from an emitter at `-dv` from the
    /// receiver's midpoint (`dv = m_R - m_E`): its gradient and, if `curved`, its Hessian.
    #[inline]
    pub(super) fn add_link(&mut self, t: Vec3A, slope: f32, dv: Vec3A, curved: bool) {
        let (k, w) = steepness(dv, slope, curved);
        let tk = t * k;
        self.grad[0] += dv * tk.x;
        self.grad[1] += dv * tk.y;
        self.grad[2] += dv * tk.z;
        if curved {
            self.hess.add_link(t * w, tk, dv);
        }
    }

    /// Every term times `s`.
    #[inline]
    pub(super) fn scaled(self, s: f32) -> Self {
        let g = |g: Grad| g.map(|v| v * s);
        Linear {
            value: self.value * s,
            grad: g(self.grad),
            hess: Hess { diag: g(self.hess.diag), off: g(self.hess.off) },
        }
    }

    /// `self += o`.
    #[inline]
    pub(super) fn add(&mut self, o: &Linear) {
        self.value += o.value;
        add_grad(&mut self.grad, &o.grad);
        self.hess.add(&o.hess);
    }

    /// The value at a point `offset` from the midpoint.
    #[inline]
    pub(super) fn value_at(&self, offset: Vec3A) -> Vec3A {
        self.value + along(&self.grad, offset) + self.hess.half_quad(offset)
    }

    /// The same function about a point `offset` from the midpoint.
    #[inline]
    pub(super) fn moved(self, offset: Vec3A) -> Self {
        let mut grad = self.grad;
        add_grad(&mut grad, &self.hess.apply(offset));
        Linear { value: self.value_at(offset), grad, hess: self.hess }
    }
}

/// `g += h`, channel by channel.
#[inline]
fn add_grad(g: &mut Grad, h: &Grad) {
    g.iter_mut().zip(h).for_each(|(g, h)| *g += *h);
}

/// Each channel's gradient of `g` dotted with `offset`.
#[inline]
fn along(g: &Grad, offset: Vec3A) -> Vec3A {
    Vec3A::new(g[0].dot(offset), g[1].dot(offset), g[2].dot(offset))
}

/// For a link of steepness `s = slope` along `D = dv = m_R - m_E`, `|D| = ρ`: the factors
/// `k` and `w` such that the link's `E F` contributes `k E F D` to the receiver's gradient
/// and, with a curved receiver, `E F (w D Dᵀ + k I)` to its Hessian: `F (1 - s t + ½ ((q +
/// s) t² - s |δ|² / ρ²))` with `t = δ.D / ρ²` at an offset `δ`, for a profile of distance
/// alone whose log-curvature `q = ρ² F'' / F` is `s² + a` ([`FALLOFF_POWER`](crate::solver::oracle::FALLOFF_POWER):
/// `F ~ ρ^-a e^(-σ ρ)`). A link without steepness gives `k = w = 0`, whatever `D`.
#[inline]
fn steepness(dv: Vec3A, slope: f32, curved: bool) -> (f32, f32) {
    let inv_d2 = 1.0 / dv.length_squared().max(f32::MIN_POSITIVE);
    let k = -slope * inv_d2;
    let w = if curved && slope > 0.0 { curvature_along(slope) * inv_d2 * inv_d2 } else { 0.0 };
    (k, w)
}
