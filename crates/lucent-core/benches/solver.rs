//! Criterion benchmarks of the hierarchical solve (Mertens et al. 2003, §5.5) on the
//! 2048-triangle butterfly model (marble at 2.5 cm): on-the-fly, linking, and a render-mode
//! frame (pull, gather, push over stored links). `lucent bench solver` prints the table 3 rows.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use lucent_core::bssrdf::{Material, Profile};
use lucent_core::hierarchy::subdivision::{butterfly, octahedron};
use lucent_core::irradiance::{Light, face_irradiance};
use lucent_core::solver::{HierarchicalSolver, Oracle};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let sub = butterfly(&octahedron(Vec3::new(1.0, 1.25, 0.9)), 4).expect("closed base mesh");
    let mesh = sub.mesh;
    let d = Profile::for_model_scale(&Material::by_name("marble").unwrap(), mesh.extent() as f64, 0.025);
    let light = [Light::Point { position: Vec3::new(2.0, 3.0, 1.6), intensity: Vec3::splat(10.0) }];
    let e = face_irradiance(&mesh, &light, &d.entry);
    let mut s = HierarchicalSolver::new(mesh, sub.hierarchy, d, Oracle::default());
    let mut g = c.benchmark_group("solver_2048");
    g.sample_size(10);
    g.bench_function("on_the_fly", |b| b.iter(|| black_box(s.solve_on_the_fly(&e))));
    g.bench_function("link", |b| b.iter(|| black_box(s.clone().link())));
    s.link();
    g.bench_function("render", |b| b.iter(|| black_box(s.solve_render(&e))));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
