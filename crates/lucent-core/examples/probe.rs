use glam::Vec3;
use lucent_core::bssrdf::{Dipole, Material};
use lucent_core::hierarchy::subdivision::{butterfly, octahedron};
use lucent_core::irradiance::{Light, face_irradiance};
use lucent_core::solver::{HierarchicalSolver, Oracle};

fn main() {
    let lv: u32 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(6);
    let sub = butterfly(&octahedron(Vec3::new(1.0, 1.25, 0.9)), lv).unwrap();
    let mesh = sub.mesh;
    let d = Dipole::for_model_scale(&Material::by_name("marble").unwrap(), mesh.extent() as f64, 0.025);
    let ext = mesh.extent();
    let light =
        [Light::Point { position: Vec3::new(1.0, 1.5, 0.8) * ext, intensity: Vec3::splat(ext * ext * 4.0) }];
    let e = face_irradiance(&mesh, &light, d.eta);
    let reps: usize = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(2);
    let mut s = HierarchicalSolver::new(mesh.clone(), sub.hierarchy, d, Oracle::default());
    if std::env::var("INC").is_ok() {
        println!("link {:?}", s.link());
        let rest = mesh.positions.clone();
        let bumped = bumpit(&rest, Vec3::new(0.0, 0.0, 0.9), 0.25, 0.02);
        for i in 0..reps {
            let st = s.update_incremental(if i % 2 == 0 { &bumped } else { &rest }, None);
            let r = s.solve_render(&e);
            println!("inc {:?}\nrender {:?}", st, r.stats);
        }
        return;
    }
    for _ in 0..reps {
        let r = s.solve_on_the_fly(&e);
        println!("T {} {:?}", mesh.triangles.len(), r.stats);
    }
    println!("z_r {:?} sigma_tr {:?} extent {}", d.z_r, d.sigma_tr, ext);
}
#[allow(dead_code)]
fn bumpit(positions: &[Vec3], at: Vec3, radius: f32, h: f32) -> Vec<Vec3> {
    positions
        .iter()
        .map(|&p| {
            let d2 = (p - at).length_squared() / (radius * radius);
            if d2 < 1.0 { p + Vec3::Z * h * (1.0 - d2) * (1.0 - d2) } else { p }
        })
        .collect()
}
