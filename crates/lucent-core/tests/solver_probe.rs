use glam::Vec3;
use lucent_core::bssrdf::{Dipole, Material};
use lucent_core::formfactor::FormFactorOptions;
use lucent_core::hierarchy::face_cluster;
use lucent_core::irradiance::{Light, face_irradiance};
use lucent_core::mesh::Mesh;
use lucent_core::solver::{HierarchicalSolver, Oracle, exact};

fn blob(levels: u32) -> Mesh {
    let mut pos = vec![
        Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z,
    ];
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut nt = Vec::new();
        for t in &tris {
            let mut m = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
                m[k] = *mid.entry((a, b)).or_insert_with(|| {
                    pos.push(((pos[a as usize] + pos[b as usize]) * 0.5).normalize());
                    pos.len() as u32 - 1
                });
            }
            nt.push([t[0], m[0], m[2]]);
            nt.push([m[0], t[1], m[1]]);
            nt.push([m[2], m[1], t[2]]);
            nt.push([m[0], m[1], m[2]]);
        }
        tris = nt;
    }
    let pos = pos
        .iter()
        .map(|p| Vec3::new(p.x * 1.3, p.y, p.z * 0.8) * (1.0 + 0.15 * (3.0 * p.x).sin() * p.y))
        .collect();
    Mesh::new(pos, tris)
}

fn oracle() -> Oracle {
    let g = |k: &str, d: f32| std::env::var(k).ok().and_then(|v| v.parse().ok()).unwrap_or(d);
    let o = Oracle::default();
    Oracle { eps1: g("EPS1", o.eps1), eps2: g("EPS2", o.eps2), eps_near_cluster: g("EPSN", o.eps_near_cluster), min_flatness: g("FLAT", o.min_flatness), eps_normal: g("EPSNORM", o.eps_normal), mode: if std::env::var("GEOM").is_ok() { lucent_core::solver::oracle::OracleMode::SolidAngle } else { o.mode } }
}

#[test]
fn probe() {
    let mesh = blob(4);
    let h = face_cluster::build(&mesh);
    println!("faces {} clusters {} depth {}", mesh.triangles.len(), h.len(), h.depth());
    let lights = [Light::Point { position: Vec3::new(2.0, 3.0, 1.5), intensity: Vec3::splat(10.0) }];
    for name in std::env::var("MATS").unwrap_or("marble,skimmilk,ketchup".into()).split(',') {
        for scale in std::env::var("SCALES").unwrap_or("0.01,0.1,1".into()).split(',').map(|v| v.parse::<f64>().unwrap()) {
            let mat = Material::by_name(name).unwrap();
            let d = Dipole::for_model_scale(&mat, mesh.extent() as f64, scale);
            let e = face_irradiance(&mesh, &lights, d.eta);
            let t = std::time::Instant::now();
            let ex = exact::solve(&mesh, &d, &e, &FormFactorOptions::default());
            let tex = t.elapsed().as_secs_f64() * 1e3;
            let s = HierarchicalSolver::new(mesh.clone(), h.clone(), d, oracle());
            let sol = s.solve_on_the_fly(&e);
            let vx = mesh.face_to_vertex(&ex);
            let vh = mesh.face_to_vertex(&sol.face_b);
            let mut num = 0.0f64; let mut den = 0.0f64;
            for (a, b) in vx.iter().zip(&vh) {
                for c in 0..3 { num += ((a[c]-b[c]) as f64).powi(2); den += (a[c] as f64).powi(2); }
            }
            let mut pc = [0.0f64; 3]; let mut pd = [0.0f64; 3];
            for (a, b) in vx.iter().zip(&vh) { for c in 0..3 { pc[c] += ((a[c]-b[c]) as f64).powi(2); pd[c] += (a[c] as f64).powi(2); } }
            println!("  per channel {:?}", (0..3).map(|c| format!("{:.3}%", 100.0*(pc[c]/pd[c]).sqrt())).collect::<Vec<_>>());
            println!("{name} {scale}: rel rmse {:.4}% links {} ff {} ms {:.1} exact ms {:.1}", 100.0*(num/den).sqrt(), sol.stats.links, sol.stats.form_factors, sol.stats.total_ms, tex);
        }
    }
}

#[test]
fn coverage() {
    let mesh = blob(3);
    let h = face_cluster::build(&mesh);
    let mat = Material::by_name("ketchup").unwrap();
    let d = Dipole::for_model_scale(&mat, mesh.extent() as f64, 0.01);
    let mut s = HierarchicalSolver::new(mesh.clone(), h.clone(), d, oracle());
    s.link();
    let l = s.links().unwrap();
    let n = mesh.triangles.len();
    let mut bad = 0;
    for leaf in 0..h.len() {
        if !h.nodes[leaf].is_leaf() { continue; }
        let mut cov = vec![0u32; n];
        let mut r = leaf as u32;
        while r != u32::MAX {
            for j in l.recv_start[r as usize] as usize..l.recv_start[r as usize + 1] as usize {
                let e = &h.nodes[l.emitter_of(j)];
                for p in e.leaf_start..e.leaf_end { cov[p as usize] += 1; }
            }
            r = h.nodes[r as usize].parent;
        }
        if cov.iter().any(|&c| c != 1) { bad += 1; }
    }
    println!("bad receivers {bad}");
    assert_eq!(bad, 0);
}
