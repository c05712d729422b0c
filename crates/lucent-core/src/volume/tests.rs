use super::*;
use glam::Vec3;
use std::path::PathBuf;

/// A fresh path in the temp directory, unique to this process and test.
fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("lucent_volume_{}_{name}", std::process::id()))
}

#[test]
fn spec_parses_every_source() {
    assert_eq!("veins".parse::<VolumeSpec>().unwrap(), VolumeSpec::Veins { seed: 7, scale: 3.0 });
    assert_eq!("veins:3:5.5".parse::<VolumeSpec>().unwrap(), VolumeSpec::Veins { seed: 3, scale: 5.5 });
    assert_eq!("cube:0.25".parse::<VolumeSpec>().unwrap(), VolumeSpec::Cube { size: 0.25 });
    assert_eq!("uniform:0.5".parse::<VolumeSpec>().unwrap(), VolumeSpec::Uniform { density: 0.5 });
    assert_eq!(
        "raw:C:/data/a:b.raw:8x16x32:u16".parse::<VolumeSpec>().unwrap(),
        VolumeSpec::Raw { path: "C:/data/a:b.raw".into(), dims: [8, 16, 32], format: RawFormat::U16 }
    );
    assert_eq!("file:v.lvol".parse::<VolumeSpec>().unwrap(), VolumeSpec::File { path: "v.lvol".into() });
}

#[test]
fn spec_rejects_nonsense_with_the_spec_in_the_message() {
    for bad in [
        "marble",
        "veins:x",
        "veins:1:-2",
        "veins:1:2:3",
        "cube:0",
        "cube:1.5",
        "uniform",
        "uniform:2",
        "uniform:nan",
        "raw:a.raw:8x8:u8",
        "raw:a.raw:8x8x0:u8",
        "raw:a.raw:8x8x8:i32",
        "raw:8x8x8:u8",
        "file:",
    ] {
        let err = bad.parse::<VolumeSpec>().unwrap_err().to_string();
        assert!(err.contains(bad), "{bad}: {err}");
    }
}

#[test]
fn lvol_round_trips() {
    let v = procedural::embedded_cube([5, 4, 3], 0.5).unwrap();
    let path = temp("round.lvol");
    save_lvol(&path, &v).unwrap();
    let back = load_lvol(&path).unwrap();
    std::fs::remove_file(&path).ok();
    assert_eq!(v, back);
}

#[test]
fn lvol_rejects_bad_files_naming_them() {
    let v = DensityVolume::uniform([4, 4, 4], 0.5).unwrap();
    let path = temp("bad.lvol");
    save_lvol(&path, &v).unwrap();
    let good = std::fs::read(&path).unwrap();
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (good[..good.len() - 4].to_vec(), "expected"),
        ([good.clone(), vec![0; 4]].concat(), "expected"),
        (b"NOPE".iter().chain(&good[4..]).copied().collect(), "magic"),
        (good[..10].to_vec(), "too short"),
        (good[..4].iter().chain(&7u32.to_le_bytes()).chain(&good[8..]).copied().collect(), "version"),
        ([&good[..20], &2.0f32.to_le_bytes()[..], &good[24..]].concat(), "outside [0, 1]"),
        ([&good[..20], &f32::NAN.to_le_bytes()[..], &good[24..]].concat(), "outside [0, 1]"),
    ];
    for (bytes, what) in cases {
        std::fs::write(&path, bytes).unwrap();
        let err = load_lvol(&path).unwrap_err().to_string();
        assert!(err.contains(&path.display().to_string()), "{err}");
        assert!(err.contains(what), "{what}: {err}");
    }
    std::fs::remove_file(&path).ok();
    let err = load_lvol(&temp("missing.lvol")).unwrap_err().to_string();
    assert!(err.contains("missing.lvol"), "{err}");
}

#[test]
fn raw_formats_decode_and_wrong_sizes_are_rejected() {
    let path = temp("grid.raw");
    std::fs::write(&path, [0u8, 51, 255, 102, 0, 0, 0, 0]).unwrap();
    let v = load_raw(&path, [2, 2, 2], RawFormat::U8).unwrap();
    assert_eq!(&v.data[..4], &[0.0, 0.2, 1.0, 0.4]);
    let err = load_raw(&path, [2, 2, 3], RawFormat::U8).unwrap_err().to_string();
    assert!(err.contains("grid.raw") && err.contains("expected 12 bytes"), "{err}");

    let words: Vec<u8> = [0u16, 65535, 13107, 0].iter().flat_map(|w| w.to_le_bytes()).collect();
    std::fs::write(&path, &words).unwrap();
    let v = load_raw(&path, [4, 1, 1], RawFormat::U16).unwrap();
    assert_eq!(v.data, vec![0.0, 1.0, 0.2, 0.0]);

    let floats: Vec<u8> = [0.25f32, 0.5, 1.5, 0.0].iter().flat_map(|f| f.to_le_bytes()).collect();
    std::fs::write(&path, &floats).unwrap();
    let err = load_raw(&path, [2, 2, 1], RawFormat::F32).unwrap_err().to_string();
    assert!(err.contains("grid.raw") && err.contains("voxel 2"), "{err}");
    std::fs::remove_file(&path).ok();
}

#[test]
fn mip_chain_matches_wgpu_sizes_and_preserves_the_mean() {
    // Even sides: each level is an exact 2x2x2 box filter, so the mean is preserved exactly.
    let v = VolumeSpec::default().build([16, 8, 4]).unwrap();
    let chain = v.mip_chain();
    assert_eq!(chain.len(), 5);
    for (level, m) in chain.iter().enumerate() {
        let expect = [16u32, 8, 4].map(|d| (d >> level).max(1));
        assert_eq!(m.dims, expect, "level {level}");
        assert_eq!(m.data.len(), expect.iter().product::<u32>() as usize);
        assert!((m.mean() - v.mean()).abs() < 1e-5, "level {level}");
    }
    assert_eq!(chain.last().unwrap().dims, [1, 1, 1]);
}

#[test]
fn trilinear_sampling_interpolates_between_voxel_centres() {
    let v = DensityVolume::new([2, 1, 1], vec![0.0, 1.0]).unwrap();
    // Voxel centres at x = 0.25 and 0.75; clamp-to-edge outside them.
    assert_eq!(v.sample_linear(Vec3::new(0.25, 0.5, 0.5)), 0.0);
    assert_eq!(v.sample_linear(Vec3::new(0.5, 0.5, 0.5)), 0.5);
    assert_eq!(v.sample_linear(Vec3::new(0.9, 0.5, 0.5)), 1.0);
    assert_eq!(v.sample_linear(Vec3::new(0.0, 0.5, 0.5)), 0.0);
}

#[test]
fn procedural_sources_are_in_range_and_shaped() {
    let veins = VolumeSpec::default().build([32, 32, 32]).unwrap();
    assert!(veins.data.iter().all(|d| (0.0..=1.0).contains(d)));
    // Thin dense veins over a clear background: most voxels are light, some are dense.
    let dense = veins.data.iter().filter(|&&d| d > 0.5).count() as f32 / veins.len() as f32;
    assert!(dense > 0.01 && dense < 0.4, "dense fraction {dense}");
    let other = "veins:8".parse::<VolumeSpec>().unwrap().build([32, 32, 32]).unwrap();
    assert_ne!(veins, other, "the seed changes the pattern");

    let cube = procedural::embedded_cube([10, 10, 10], 0.4).unwrap();
    assert_eq!(cube.voxel(5, 5, 5), 1.0);
    assert_eq!(cube.voxel(0, 5, 5), 0.0);
    // Centres (i + 0.5) / 10 within 0.2 of 0.5: i = 3..=6, a 4^3 cube.
    assert_eq!(cube.data.iter().filter(|&&d| d == 1.0).count(), 64);
}

#[test]
fn constructor_rejects_bad_dims_and_values() {
    assert!(DensityVolume::new([0, 1, 1], vec![]).is_err());
    assert!(DensityVolume::new([2, 1, 1], vec![0.5]).is_err());
    assert!(DensityVolume::new([1, 1, 1], vec![-0.1]).is_err());
    assert!(DensityVolume::uniform([MAX_DIM + 1, 1, 1], 0.0).is_err());
    assert_eq!(mip_level_count([64, 64, 64]), 7);
    assert_eq!(mip_level_count([1, 1, 1]), 1);
    assert_eq!(mip_level_count([5, 3, 1]), 3);
}
