//! Scene files: examples, defaults, lights, materials, paths and errors.

use super::*;
use lucent_core::irradiance::Light;

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes")
}

#[test]
fn example_scenes_parse() {
    for name in ["candle.toml", "bunny_courtyard.toml", "bunny_spot.toml", "bunny_jade.toml"] {
        let s = SceneFile::load(&examples().join(name)).unwrap_or_else(|e| panic!("{e:#}"));
        assert!(!s.lights.is_empty() || s.environment.is_some(), "{name}");
    }
    let jade = SceneFile::load(&examples().join("bunny_jade.toml")).unwrap();
    assert_eq!(
        jade.material.as_ref().and_then(MaterialSpec::by_colour),
        Some(([0.55, 0.8, 0.6], [1.5, 3.0, 2.0]))
    );
    let (albedo, _) = jade.material().unwrap().albedo_mfp();
    assert!((albedo[1] - 0.8).abs() < 1e-3, "{albedo:?}");
    let s = SceneFile::load(&examples().join("bunny_courtyard.toml")).unwrap();
    let env = s.environment().unwrap().expect("has an environment");
    assert_eq!((env.reflection.width, env.reflection.height), (256, 128));
    assert_eq!(env.reflection_rgba().len(), 256 * 128);
    assert!(env.environment.sh.coeffs[0].min_element() > 0.0);
}

#[test]
fn empty_file_is_the_default_scene() {
    let s = SceneFile::parse("", PathBuf::new()).unwrap();
    assert_eq!(s.mesh_source(), MeshSource::Builtin("bunny".into()));
    assert_eq!(s.material().unwrap().name, "Skimmilk");
    assert_eq!(s.scale, 0.05);
    assert!(s.lights.is_empty() && s.environment.is_none() && s.deform.is_empty());
}

#[test]
fn lights_convert_with_intensity_at_the_centre() {
    let s = SceneFile::parse(
        r#"
        [[light]]
        type = "point"
        position = [0.0, 3.0, 4.0]
        color = [1.0, 0.5, 0.25]
        intensity = 2.0
        shadows = false

        [[light]]
        type = "spot"
        position = [0.0, 2.0, 0.0]
        direction = [0.0, -2.0, 0.0]
        cone_angle = 45.0
        "#,
        PathBuf::new(),
    )
    .unwrap();
    let lights = s.lights(Vec3::ZERO);
    // 25 = squared distance to the centre: the light gives intensity * color there.
    assert_eq!(
        lights[0],
        SceneLight {
            light: Light::Point {
                position: Vec3::new(0.0, 3.0, 4.0),
                intensity: Vec3::new(50.0, 25.0, 12.5),
            },
            shadows: false,
        }
    );
    let Light::Spot { direction, cone_angle, soft_edge, intensity, .. } = lights[1].light else {
        panic!("a spot");
    };
    assert_eq!(direction, -Vec3::Y);
    assert!((cone_angle - std::f32::consts::FRAC_PI_4).abs() < 1e-6);
    assert_eq!(soft_edge, 0.2);
    assert_eq!(intensity, Vec3::splat(4.0));
    assert!(lights[1].shadows);
}

#[test]
fn custom_material_and_paths() {
    let s = SceneFile::parse(
        r#"
        mesh = "models/thing.obj"
        material = { sigma_s_prime = [1.0, 1.0, 1.0], sigma_a = [0.01, 0.02, 0.03] }
        "#,
        PathBuf::from("/scenes"),
    )
    .unwrap();
    assert_eq!(s.mesh_source(), MeshSource::File(PathBuf::from("/scenes/models/thing.obj")));
    let m = s.material().unwrap();
    assert_eq!((m.sigma_a[2], m.eta), (0.03, 1.3));
}

fn error(text: &str) -> String {
    format!("{:#}", SceneFile::parse(text, PathBuf::new()).unwrap_err())
}

#[test]
fn bad_scenes_give_clear_errors() {
    // Syntax and type errors carry toml's line numbers.
    let e = error("scale = 0.1\nexposure = \"bright\"\n");
    assert!(e.contains("line 2"), "{e}");
    let e = error("scale = 0.1\n[[light]]\ntype = \"laser\"\nposition = [0, 0, 0]\n");
    assert!(e.contains("line 3") && e.contains("laser"), "{e}");
    let e = error("colour = 1\n");
    assert!(e.contains("colour"), "{e}");
    let e = error("material = { sigma_s_prime = [1.0, 1.0, 1.0] }\n");
    assert!(e.contains("sigma_a"), "{e}");
    // Range errors name the field.
    assert!(error("scale = -1\n").contains("scale"));
    assert!(error("material = \"jelly\"\n").contains("jelly"));
    let e = error("[[light]]\ntype = \"spot\"\nposition = [0,1,0]\ndirection = [0,0,0]\n");
    assert!(e.contains("light 1") && e.contains("direction"), "{e}");
    let e = error("[[light]]\ntype = \"spot\"\nposition = [0,1,0]\ndirection = [0,-1,0]\nsoft_edge = 2\n");
    assert!(e.contains("soft_edge"), "{e}");
    assert!(error("deform = [\"twist\"]\n").contains("twist"));
    assert!(error("deform = [\"bump:1,2\"]\n").contains("bump takes 5 numbers"));
    assert!(error("[camera]\nfov = 200\n").contains("fov"));
}

#[test]
fn meshes_and_deformations_resolve() {
    let s = SceneFile::load(&examples().join("candle.toml")).unwrap();
    let mesh = s.load_mesh().unwrap();
    assert!(!mesh.triangles.is_empty());
    assert_eq!(s.deformations().unwrap(), vec![Deformation::Twist { degrees: 40.0 }]);
    assert_eq!(s.camera().fov_y_deg, 35.0);
    for name in BUILTIN_MESHES {
        let s = SceneFile::parse(&format!("mesh = \"{name}\"\n"), PathBuf::new()).unwrap();
        assert!(!s.load_mesh().unwrap().triangles.is_empty(), "{name}");
    }
    let s = SceneFile::parse("mesh = \"teapot\"\n", PathBuf::new()).unwrap();
    assert!(format!("{:#}", s.load_mesh().unwrap_err()).contains("teapot"));
    let s = SceneFile::parse("mesh = \"gone.obj\"\n", PathBuf::from("d")).unwrap();
    assert!(format!("{:#}", s.load_mesh().unwrap_err()).contains("gone.obj"));
}

#[test]
fn missing_files_are_named() {
    let e = format!("{:#}", SceneFile::load(Path::new("no/such/scene.toml")).unwrap_err());
    assert!(e.contains("no/such/scene.toml"), "{e}");
    let s = SceneFile::parse("[environment]\npath = \"missing.exr\"\n", PathBuf::from("somewhere")).unwrap();
    let e = format!("{:#}", s.environment().unwrap_err());
    assert!(e.contains("missing.exr"), "{e}");
}
