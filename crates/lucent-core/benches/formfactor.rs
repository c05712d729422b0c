//! Criterion micro-benchmarks of the form factor (Mertens et al. 2003, §4): the semi-analytic
//! `form_factor` on a near triangle (receiver at its tip, Mertens fig. 3 at d = 0), a mid-range
//! one (fig. 3 at d = 5 mm) and a far one, plus the one-sample `point_sample` it replaces for
//! distant links; the first two again with the default profile (photon beam diffusion, whose
//! three channels' tables share one pass over the edges). Run with
//! `cargo bench -p lucent-core --bench formfactor`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use lucent_core::bssrdf::{Material, Profile, ProfileKind};
use lucent_core::formfactor::{FormFactorOptions, form_factor, point_sample};
use std::hint::black_box;

fn figure3_triangle(d: f64) -> [DVec3; 3] {
    [DVec3::new(d, 0.0, 0.0), DVec3::new(d + 5.0, -5.0, 0.0), DVec3::new(d + 5.0, 5.0, 0.0)]
}

fn bench(c: &mut Criterion) {
    let profile = Profile::new(&Material::by_name("skimmilk").unwrap(), 1.0);
    let pbd = Profile::of_kind(&Material::by_name("skimmilk").unwrap(), 1.0, ProfileKind::Pbd, false);
    let opts = FormFactorOptions::default();
    let (x_o, n_o) = (DVec3::ZERO, DVec3::Z);
    // Far: a 1 mm triangle 30 mm away, tilted against the receiver's plane.
    let far = [DVec3::new(30.0, 0.0, -1.0), DVec3::new(31.0, 0.0, -1.5), DVec3::new(30.0, 1.0, -1.2)];
    let cases = [("near", figure3_triangle(0.0)), ("mid", figure3_triangle(5.0)), ("far", far)];
    for (name, tri) in cases {
        c.bench_function(&format!("form_factor/{name}"), |b| {
            b.iter(|| form_factor(black_box(&tri), black_box(x_o), n_o, &profile, &opts))
        });
    }
    for (name, tri) in &cases[..2] {
        c.bench_function(&format!("form_factor_pbd/{name}"), |b| {
            b.iter(|| form_factor(black_box(tri), black_box(x_o), n_o, &pbd, &opts))
        });
    }
    c.bench_function("point_sample", |b| {
        b.iter(|| point_sample(black_box(&far), black_box(x_o), n_o, &profile))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
