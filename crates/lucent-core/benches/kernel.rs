//! The solver's two hot kernels, per instruction set ([`lucent_core::simd::Isa`]: scalar,
//! AVX2, AVX-512, those this CPU has):
//!
//! * `point_samples/<profile>/<isa>`: the one-point estimate `A R(d)` (Mertens §4.2) for four
//!   emitters and one receiver, three channels each, over 1,024 batches of four. Criterion's
//!   throughput (elements/s) counts three-channel estimates: Gelem/s is estimates per ns.
//! * `point_sums/<profile>/<isa>`: the same estimates as the near field's cubature makes them
//!   (`ReceiverSources::cubature`: Radon's seven points on each of 1,024 triangles, summed per
//!   channel), sixteen points a channel per register on AVX-512 (four a batch elsewhere).
//!   Gelem/s is three-channel estimates per ns, the points' set-up included.
//! * `gather/<isa>`: render mode's `Σ E F` (§5.5) over 8M stored links (32 a receiver, 96 MB
//!   of coefficients and emitter words, more than the caches), one core. Gelem/s is links per
//!   ns. `gather/stream` reads the same 12 bytes a link and does nothing with them: the
//!   bandwidth bound.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{Vec3, Vec3A};
use lucent_core::bssrdf::{Material, Profile, ProfileKind};
use lucent_core::simd::Isa;
use lucent_core::solver::link_coef::{LinkCoef, gather_sum, receiver_scale};
use lucent_core::solver::point_sample::{ProfileF32, ReceiverSources};
use rand::{Rng, SeedableRng};
use std::hint::black_box;

const BATCHES: usize = 1024;

/// Every profile on every instruction set this CPU has, for a receiver at `x_o` with normal
/// `n_o`: the bench's name, the profile and the receiver's poles. Marble at 10 cm on a unit
/// mesh: distances span the profile's whole range.
fn profiles(x_o: Vec3, n_o: Vec3) -> Vec<(String, ProfileF32, ReceiverSources)> {
    let m = Material::by_name("marble").unwrap();
    let mut out = Vec::new();
    for kind in ProfileKind::ALL {
        for isa in Isa::available() {
            let dip = Profile::of_kind(&m, 50.0, kind, kind.has_single_scattering());
            let d = ProfileF32::new(&dip).with_isa(isa);
            let src = ReceiverSources::new(&d, x_o, n_o);
            out.push((format!("{}/{}", kind.name(), isa.name()), d, src));
        }
    }
    out
}

fn point_samples(c: &mut Criterion) {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    let mut point = || Vec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0;
    let x_o = point();
    let n_o = Vec3::new(0.2, 0.9, 0.1).normalize();
    let emitters: Vec<[Vec3; 4]> = (0..BATCHES).map(|_| [point(), point(), point(), point()]).collect();
    let areas = [1e-3f32, 2e-3, 5e-4, 1e-3];
    let mut group = c.benchmark_group("point_samples");
    group.throughput(Throughput::Elements((4 * BATCHES) as u64));
    for (name, d, src) in profiles(x_o, n_o) {
        group.bench_function(name, |b| {
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
    // The same estimates sixteen points to a register, as the near field's cubature makes
    // them: Radon's seven points on each triangle.
    let tris: Vec<([Vec3; 3], f32)> = emitters.iter().map(|p| ([p[0], p[1], p[2]], 1e-3)).collect();
    let mut group = c.benchmark_group("point_sums");
    group.throughput(Throughput::Elements((7 * tris.len()) as u64));
    for (name, d, src) in profiles(x_o, n_o) {
        group.bench_function(name, |b| b.iter(|| black_box(src.cubature(&d, black_box(&tris)))));
    }
    group.finish();
}

fn gather(c: &mut Criterion) {
    const NODES: usize = 1 << 18;
    const PER_RECEIVER: usize = 32;
    const RECEIVERS: usize = 1 << 18;
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
    let e_node: Vec<Vec3A> =
        (0..NODES).map(|_| Vec3A::new(rng.random(), rng.random(), rng.random())).collect();
    // Emitters near the receiver in the node order, as a hierarchy's links mostly are.
    let emitter: Vec<u32> = (0..RECEIVERS * PER_RECEIVER)
        .map(|i| ((i / PER_RECEIVER + rng.random_range(0..4096)) % NODES) as u32)
        .collect();
    let scale = receiver_scale(1.0);
    let coef: Vec<LinkCoef> = (0..emitter.len())
        .map(|_| LinkCoef::pack(Vec3A::new(rng.random(), rng.random(), rng.random()), scale))
        .collect();
    let mut group = c.benchmark_group("gather");
    group.sample_size(20);
    group.throughput(Throughput::Elements(emitter.len() as u64));
    // The roofline: the same bytes streamed and summed, no `E` fetched, nothing converted.
    let words: Vec<u64> = (0..coef.len() as u64).map(|i| i.wrapping_mul(0x9e37_79b9_7f4a_7c15)).collect();
    group.bench_function("stream", |b| {
        b.iter(|| {
            let (mut s0, mut s1) = (0u64, 0u64);
            for (e, w) in emitter.chunks_exact(2).zip(words.chunks_exact(2)) {
                s0 = s0.wrapping_add(e[0] as u64 ^ w[0]);
                s1 = s1.wrapping_add(e[1] as u64 ^ w[1]);
            }
            black_box(s0 ^ s1)
        })
    });
    for isa in Isa::available() {
        group.bench_function(isa.name(), |b| {
            b.iter(|| {
                let mut acc = Vec3A::ZERO;
                for (e, c) in emitter.chunks_exact(PER_RECEIVER).zip(coef.chunks_exact(PER_RECEIVER)) {
                    acc += gather_sum(isa, &e_node, e, c);
                }
                black_box(acc)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, point_samples, gather);
criterion_main!(benches);
