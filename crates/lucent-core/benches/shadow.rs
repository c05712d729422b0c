//! Shadow-ray costs for the leaf irradiance (Mertens §5.3): BVH build, per-frame refit after a
//! deformation, and one shadow ray per face to a point light, on the Stanford bunny (3,674
//! faces, `assets/bunny.obj`) and a 131,072-triangle torus (the size of Mertens' largest model in
//! table 3, 131,736 triangles).
//!
//! `cargo bench -p lucent-core --bench shadow`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use glam::Vec3;
use lucent_core::irradiance::{Light, SceneLight, ShadowCaster, face_irradiance_shadowed};
use lucent_core::mesh::Mesh;
use lucent_core::mesh::bvh::Bvh;
use std::f32::consts::PI;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

/// The bunny from `assets/bunny.obj` (read with tobj so the bench depends on nothing else).
fn bunny() -> Mesh {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/bunny.obj");
    let (models, _) =
        tobj::load_obj(&path, &tobj::GPU_LOAD_OPTIONS).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let m = &models[0].mesh;
    Mesh::new(
        m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
        m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    )
}

/// A torus of `2 n²` triangles around +Y.
fn torus(n: u32) -> Mesh {
    let mut positions = Vec::new();
    for i in 0..n {
        let u = 2.0 * PI * i as f32 / n as f32;
        for j in 0..n {
            let v = 2.0 * PI * j as f32 / n as f32;
            let r = 1.0 + 0.35 * v.cos();
            positions.push(Vec3::new(r * u.cos(), 0.35 * v.sin(), r * u.sin()));
        }
    }
    let idx = |i: u32, j: u32| (i % n) * n + j % n;
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i, j + 1), idx(i + 1, j + 1));
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    Mesh::new(positions, triangles)
}

/// The mesh twisted about +Y (a Mertens fig. 6.7 style deformation), `radians` over its height.
fn twisted(mesh: &Mesh, radians: f32) -> Mesh {
    let (lo, hi) = mesh.bounds();
    let mut m = mesh.clone();
    for p in &mut m.positions {
        let (s, c) = (radians * (p.y - lo.y) / (hi.y - lo.y).max(1e-6)).sin_cos();
        *p = Vec3::new(c * p.x - s * p.z, p.y, s * p.x + c * p.z);
    }
    m
}

fn shadow(c: &mut Criterion) {
    let meshes = [("bunny_3674", bunny()), ("torus_131072", torus(256))];
    let mut group = c.benchmark_group("shadow");
    group.sample_size(10).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    for (name, mesh) in &meshes {
        let (lo, hi) = mesh.bounds();
        let light = SceneLight::from(Light::Point { position: hi + (hi - lo), intensity: Vec3::ONE });
        group.bench_with_input(BenchmarkId::new("build", name), mesh, |b, m| {
            b.iter(|| black_box(Bvh::build(m)))
        });
        // Refit alternates between two poses so every refit moves every box.
        let poses = [twisted(mesh, 0.3), twisted(mesh, -0.3)];
        let mut caster = ShadowCaster::new(mesh);
        caster.rebuild_ratio = f32::INFINITY;
        let mut k = 0;
        group.bench_function(BenchmarkId::new("refit", name), |b| {
            b.iter(|| {
                k ^= 1;
                black_box(caster.update(&poses[k]))
            })
        });
        let caster = ShadowCaster::new(mesh);
        let entry = lucent_core::bssrdf::Entry::fresnel(1.3);
        group.bench_function(BenchmarkId::new("irradiance_unshadowed", name), |b| {
            b.iter(|| black_box(face_irradiance_shadowed(mesh, &[light], None, &entry, None)))
        });
        group.bench_function(BenchmarkId::new("irradiance_shadowed", name), |b| {
            b.iter(|| black_box(face_irradiance_shadowed(mesh, &[light], None, &entry, Some(&caster))))
        });
    }
    group.finish();
}

criterion_group!(benches, shadow);
criterion_main!(benches);
