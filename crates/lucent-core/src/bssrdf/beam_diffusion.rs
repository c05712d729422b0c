// TEMPORARY SHIM (not to be committed): replaced by the pbd branch.
#[derive(Clone, Copy, Debug, Default)]
pub struct Split {
    pub multiple: f64,
    pub single: f64,
}
pub struct BeamDiffusionTable;
impl BeamDiffusionTable {
    pub fn shared(_eta: f64) -> std::sync::Arc<Self> {
        std::sync::Arc::new(BeamDiffusionTable)
    }
    pub fn radial(&self, _rho: f64, r: f64) -> Split {
        Split { multiple: (-r).exp() / (2.0 * std::f64::consts::PI), single: 0.0 }
    }
    pub fn tail(&self, _rho: f64, r: f64) -> Split {
        Split { multiple: (1.0 + r) * (-r).exp() / (2.0 * std::f64::consts::PI), single: 0.0 }
    }
}
