//! The one-point estimate kernel (`solver::point_sample`): `A R(d)` for four emitters and one
//! receiver, three channels each, per profile. Criterion reports the time per call of
//! `point_samples` over 1,024 emitter batches; divide by 4,096 for one three-channel estimate.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use lucent_core::bssrdf::{Dipole, Material, ProfileKind};
use lucent_core::solver::point_sample::{DipoleF32, ReceiverSources};
use rand::{Rng, SeedableRng};
use std::hint::black_box;

const BATCHES: usize = 1024;

fn kernel(c: &mut Criterion) {
    let m = Material::by_name("marble").unwrap();
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    let mut point = || Vec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0;
    let x_o = point();
    let n_o = Vec3::new(0.2, 0.9, 0.1).normalize();
    let emitters: Vec<[Vec3; 4]> = (0..BATCHES).map(|_| [point(), point(), point(), point()]).collect();
    let areas = [1e-3f32, 2e-3, 5e-4, 1e-3];
    let mut group = c.benchmark_group("point_samples");
    group.throughput(Throughput::Elements((4 * BATCHES) as u64));
    for kind in ProfileKind::ALL {
        // Marble at 10 cm on a unit mesh: distances span the profile's whole range.
        let d = DipoleF32::new(&Dipole::with_profile(&m, 50.0, kind, kind != ProfileKind::Mertens));
        let src = ReceiverSources::new(&d, x_o, n_o);
        group.bench_function(kind.name(), |b| {
            b.iter(|| {
                let mut acc = 0.0f32;
                for p in &emitters {
                    let v = src.point_samples(&d, black_box(p), &areas);
                    acc += v[0][0] + v[1][1] + v[2][2] + v[3][0];
                }
                black_box(acc)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, kernel);
criterion_main!(benches);
