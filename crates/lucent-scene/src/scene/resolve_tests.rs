use super::*;

fn candle() -> Option<PathBuf> {
    Some(format!("{}/../../examples/scenes/candle.toml", env!("CARGO_MANIFEST_DIR")).into())
}

/// Flags given explicitly win over the scene file; the rest comes from the file.
#[test]
fn flags_override_the_scene_file() {
    let s = Scene::resolve(&Overrides { scene: candle(), ..Default::default() }).unwrap();
    assert_eq!(s.material().name, "Wax");
    assert_eq!((s.scale(), s.exposure, s.camera.yaw_deg), (0.1, 1.0, 20.0));
    assert_eq!(s.lights.len(), 2);
    assert!(s.lights[0].shadows && !s.lights[1].shadows);
    assert_eq!(s.deform, vec![Deformation::Twist { degrees: 40.0 }]);

    let s = Scene::resolve(&Overrides {
        scene: candle(),
        material: Some("marble".into()),
        scale: Some(0.2),
        exposure: Some(2.0),
        yaw: Some(-10.0),
        lights: vec!["dir:0,-1,0".into()],
        deform: Some("twist:10".into()),
        no_shadows: true,
        ..Default::default()
    })
    .unwrap();
    assert_eq!(s.material().name, "Marble");
    assert_eq!((s.scale(), s.exposure, s.camera.yaw_deg, s.camera.pitch_deg), (0.2, 2.0, -10.0, 10.0));
    assert_eq!(s.lights.len(), 1);
    assert!(!s.lights[0].shadows && !s.settings.environment_shadows);
    assert_eq!(s.deform, vec![Deformation::Twist { degrees: 10.0 }]);
}

/// `--albedo`/`--mfp` invert to a material at eta 1.3, said on one line.
#[test]
fn colour_flags_make_the_material_and_say_so() {
    let colour = Some(([0.8, 0.6, 0.4], [1.0, 0.5, 0.25]));
    let s = Scene::resolve(&Overrides { colour, ..Default::default() }).unwrap();
    let m = s.material();
    assert_eq!(*m, Material::from_albedo_mfp("custom", [0.8, 0.6, 0.4], [1.0, 0.5, 0.25], 1.3).unwrap());
    let line = colour_material_line([0.8, 0.6, 0.4], [1.0, 0.5, 0.25], m);
    assert!(line.starts_with("material: albedo 0.800,0.600,0.400 mfp 1,0.5,0.25 mm -> sigma_s' "), "{line}");
    assert!(line.ends_with(" mm^-1 (eta 1.3)") && !line.contains('\n'), "{line}");
    let tiny = Material::from_albedo_mfp("t", [0.001; 3], [1e3; 3], 1.3).unwrap();
    let tiny_line = colour_material_line([0.001; 3], [1e3; 3], &tiny);
    assert!(tiny_line.contains("sigma_s' 1.3"), "{tiny_line}");
}

#[test]
fn defaults_without_a_scene() {
    let s = Scene::resolve(&Overrides::default()).unwrap();
    assert_eq!((s.material().name.as_str(), s.scale(), s.exposure), ("Skimmilk", 0.05, 1.0));
    assert_eq!(s.lights.len(), 2, "the default key and back lights");
    assert!(s.lights.iter().all(|l| l.shadows), "default lights cast shadows");
    assert!(s.environment.is_none() && s.deform.is_empty());
    assert_eq!(s.settings(SolveMode::Render).mode, SolveMode::Render, "the caller's default mode");
    // An environment alone needs no extra light.
    let o = Overrides { env: Some("forest".into()), env_rotation: Some(45.0), ..Default::default() };
    let s = Scene::resolve(&o).unwrap();
    assert!(s.lights.is_empty());
    assert_eq!(s.environment.unwrap().environment.rotation_deg, 45.0);
}

/// Three bounces between parts by default, none with a profile that does not bound energy on
/// thin parts (the paper's `mertens`); a flag or scene key sets them for any profile.
#[test]
fn bounces_default_by_profile() {
    let bounces = |o: Overrides| Scene::resolve(&o).unwrap().settings.bounces;
    assert_eq!(bounces(Overrides::default()), crate::ranges::DEFAULT_BOUNCES);
    for kind in ProfileKind::ALL {
        let with = || Overrides { profile: Some(kind), ..Default::default() };
        let default = if kind.bounces_by_default() { crate::ranges::DEFAULT_BOUNCES } else { 0 };
        assert_eq!(bounces(with()), default, "{kind}");
        assert_eq!(bounces(Overrides { bounces: Some(2), ..with() }), 2, "{kind}");
    }
    let mertens = Overrides { profile: Some("mertens".parse().unwrap()), ..Default::default() };
    assert_eq!(bounces(mertens), 0, "the paper's profile, as a user names it");
    assert_eq!(bounces(Overrides { scene: candle(), ..Default::default() }), crate::ranges::DEFAULT_BOUNCES);
}

/// `refine`: auto splits the embedded bunny in marble at 10 cm (3.9 mm edges, 12 mean free
/// paths) once and leaves it in skim milk at 5 cm (3.7) and in a dense material whose transport
/// is local; a count forces it; HTSM is never split, the exact method only when asked; a bad
/// scene value is one error naming the file, the value and the range.
#[test]
fn refine_splits_coarse_meshes_of_opaque_materials() {
    let bunny = lucent_core::mesh::embedded::bunny().triangles.len();
    let faces = |o: Overrides| {
        let s = Scene::resolve(&o).unwrap();
        (s.refine_levels, s.mesh.triangles.len())
    };
    let marble = || Overrides { material: Some("marble".into()), scale: Some(0.1), ..Default::default() };
    assert_eq!(faces(marble()), (1, 4 * bunny));
    let skim = Overrides { material: Some("skimmilk".into()), scale: Some(0.05), ..Default::default() };
    assert_eq!(faces(skim), (0, bunny));
    assert_eq!(faces(Overrides { refine: Some(Refine::Levels(0)), ..marble() }), (0, bunny));
    assert_eq!(faces(Overrides { refine: Some(Refine::Levels(2)), ..marble() }), (2, 16 * bunny));
    assert_eq!(faces(Overrides { method: Some(Method::Htsm), ..marble() }), (0, bunny));
    // The exact method splits only when asked, and says what auto would have split.
    let exact = |refine| Overrides { method: Some(Method::Exact), refine, ..marble() };
    let declined = |o: Overrides| Scene::resolve(&o).unwrap().refine_declined;
    assert_eq!((faces(exact(None)), declined(exact(None))), ((0, bunny), 1));
    assert_eq!(
        (faces(exact(Some(Refine::Levels(1)))), declined(exact(Some(Refine::Levels(1))))),
        ((1, 4 * bunny), 0)
    );
    // sigma_s' = sigma_a = 100 mm^-1 at 5 cm: 400 mean free paths an edge, but transport
    // reaches 0.05 mm, far below every face: auto leaves it (the session takes the local limit
    // at the vertices); asked, it splits.
    let dir = std::env::temp_dir().join(format!("lucent-refine-dense-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("dense.toml");
    let dense = "material = { sigma_s_prime = [100, 100, 100], sigma_a = [100, 100, 100] }\nscale = 0.05\n";
    std::fs::write(&path, dense).unwrap();
    let file = |refine| Overrides { scene: Some(path.clone()), refine, ..Default::default() };
    assert_eq!(faces(file(None)), (0, bunny));
    assert_eq!(faces(file(Some(Refine::Levels(1)))), (1, 4 * bunny));
    std::fs::remove_dir_all(&dir).ok();

    let dir = std::env::temp_dir().join(format!("lucent-refine-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("split.toml");
    let file = || Overrides { scene: Some(path.clone()), ..Default::default() };
    std::fs::write(&path, "material = \"marble\"\nscale = 0.1\nrefine = 0\n").unwrap();
    assert_eq!(faces(file()), (0, bunny));
    std::fs::write(&path, "material = \"marble\"\nscale = 0.1\nrefine = \"auto\"\n").unwrap();
    assert_eq!(faces(file()), (1, 4 * bunny));
    for bad in ["7", "-1", "\"often\""] {
        std::fs::write(&path, format!("refine = {bad}\n")).unwrap();
        let e = format!("{:#}", Scene::resolve(&file()).err().unwrap());
        assert!(e.contains("split.toml") && e.contains("0..=3") && e.contains(bad.trim_matches('"')), "{e}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
