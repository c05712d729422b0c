use super::*;
use crate::bssrdf::Material;
use crate::hierarchy::face_cluster;
use crate::irradiance::Light;
use crate::irradiance::ShadowCaster;
use crate::mesh::deform::{self, Deformer as _};
use crate::mesh::generate;
use crate::shading;
use crate::solver::finite_body::{FiniteBody, ThicknessRays};
use crate::solver::transmission::{CrossBody, Transmission};

fn marble() -> Transport {
    Transport::new(Material::by_name("marble").unwrap(), 0.05)
}

fn key_light() -> Vec<SceneLight> {
    vec![SceneLight::from(Light::Point { position: Vec3::new(1.0, 2.0, 3.0), intensity: Vec3::splat(14.0) })]
}

fn session(mode: SolveMode) -> FrameSession {
    let settings = FrameSettings { mode, ..FrameSettings::default() };
    let mut s = FrameSession::new(generate::icosphere(2), None, marble(), settings);
    s.set_lights(key_light());
    s
}

fn max_rel_diff(a: &[Rgb], b: &[Rgb]) -> f32 {
    let scale = a.iter().map(|v| v.max_element()).fold(0.0f32, f32::max).max(1e-30);
    a.iter().zip(b).map(|(x, y)| (*x - *y).abs().max_element() / scale).fold(0.0, f32::max)
}

/// The session's on-the-fly solve is the solver's on the carried irradiance (with the
/// finite-body gain of its faces) plus the local return at each face, bit for bit.
#[test]
fn on_the_fly_matches_the_solver_called_directly() {
    let mut s = session(SolveMode::OnTheFly);
    let b = s.solve().face_b.clone();
    let mesh = generate::icosphere(2);
    let profile = marble().profile_at(mesh.extent());
    let entering = crate::irradiance::face_entering(&mesh, &key_light(), None, &profile.entry, None);
    let e: Vec<Rgb> = entering.iter().map(|e| e.carried).collect();
    let mut solver = HierarchicalSolver::new(
        mesh.clone(),
        face_cluster::build(&mesh),
        profile.clone(),
        Oracle::for_profile(profile.kind),
    );
    // The session applies the finite-body gain of its pose with the energy bound.
    let caster = ShadowCaster::new(&mesh);
    let fb = FiniteBody::new(&profile);
    let rays = ThicknessRays::trace(&mesh, caster.bvh(), caster.offset());
    let gain = fb.gains_along(&mesh, &rays, caster.offset());
    assert!(gain.iter().all(|g| g.min_element() > 1.0), "a small marble sphere gains");
    // And the slab transmission across the body, with room for it under the bound.
    let cross = CrossBody::new(&profile, &fb, &mesh, &rays, caster.offset(), &gain, Transmission::Curved)
        .with_spread(&profile, &mesh, caster.bvh(), caster.offset());
    solver.set_face_gain(Some(Arc::new(gain)));
    if !cross.is_empty() {
        solver.set_face_term(Some(Arc::new(cross.uniform_terms())));
    }
    let mut direct = solver.solve_on_the_fly(&e).face_b;
    if !cross.is_empty() {
        let cos: Vec<Rgb> = entering.iter().map(|e| e.mean_cos()).collect();
        cross.add(&mut direct, &mut vec![Rgb::ZERO; e.len()], &e, Some(&cos));
    }
    let r = Rgb::from_array(profile.total_diffuse_reflectance().map(|v| v as f32));
    assert!(entering.iter().any(|e| e.local.max_element() > 0.0), "oblique faces return some light locally");
    direct.iter_mut().zip(&entering).for_each(|(b, e)| *b += e.local * Rgb::ONE * r);
    assert_eq!(b, direct);
}

/// Nothing changed: nothing is computed; a camera move is not the session's business.
#[test]
fn an_unchanged_state_is_not_solved_again() {
    let mut s = session(SolveMode::Render);
    assert!(s.solve().fresh);
    assert!(s.is_current());
    let again = s.solve();
    assert!(!again.fresh && again.timings.total_ms() == 0.0);
    s.set_lights(key_light());
    assert!(s.is_current(), "the same lights are no change");
}

/// Render mode: a light change re-gathers on the stored links (no relink) and gives what a new
/// session gives under the new light.
#[test]
fn a_light_change_in_render_mode_reuses_the_links() {
    let mut s = session(SolveMode::Render);
    let links = s.solve().links;
    let other = vec![SceneLight::from(Light::Directional { direction: Vec3::NEG_Y, irradiance: Vec3::ONE })];
    s.set_lights(other.clone());
    let solved = s.solve().clone();
    assert_eq!(solved.links, links);
    assert_eq!(solved.timings.link_ms, 0.0, "no relink for a light change");
    let mut fresh = session(SolveMode::Render);
    fresh.set_lights(other);
    assert_eq!(solved.face_b, fresh.solve().face_b);
}

/// A deformation: incremental and render modes agree with on-the-fly at the new pose within
/// the hierarchical solve's own tolerance, and on-the-fly agrees with a new session.
#[test]
fn a_deformation_is_followed_by_every_mode() {
    let rest = generate::icosphere(2);
    let bent = deform::twist(Vec3::ZERO, Vec3::Y, 0.8).deformed(&rest).positions;
    let mut reference = session(SolveMode::OnTheFly);
    reference.set_positions(&bent);
    let reference = reference.solve().face_b.clone();
    for mode in SolveMode::ALL {
        let mut s = session(mode);
        s.solve();
        s.set_positions(&bent);
        let b = s.solve().face_b.clone();
        let d = max_rel_diff(&b, &reference);
        assert!(d < 0.02, "{mode:?}: {d}");
        if mode == SolveMode::OnTheFly {
            assert_eq!(b, reference);
        }
    }
}

/// A material change makes a new profile, and the result is that of a new session.
#[test]
fn a_material_change_rebuilds_the_profile() {
    for mode in SolveMode::ALL {
        let mut s = session(mode);
        let before = s.solve().face_b.clone();
        let ketchup = Transport::new(Material::by_name("ketchup").unwrap(), 0.05);
        s.set_transport(ketchup.clone());
        let after = s.solve().face_b.clone();
        assert_ne!(before, after);
        let mut fresh = session(mode);
        fresh.set_transport(ketchup);
        let d = max_rel_diff(&after, &fresh.solve().face_b);
        assert!(d < 0.02, "{mode:?}: {d}");
    }
}

/// The exact method solves without links; HTSM has no per-face solve.
#[test]
fn exact_and_htsm() {
    let mut s = session(SolveMode::OnTheFly);
    let hierarchical = s.solve().face_b.clone();
    s.set_settings(FrameSettings { method: Method::Exact, ..*s.settings() });
    let exact = s.solve();
    assert_eq!(exact.links, None);
    let d = max_rel_diff(&exact.face_b.clone(), &hierarchical);
    assert!(d < 0.02, "{d}");
    s.set_settings(FrameSettings { method: Method::Htsm, ..*s.settings() });
    let htsm = s.solve();
    assert!(htsm.fresh && htsm.face_b.is_empty() && htsm.vertex_radiance.is_empty());
}

/// Changes made while HTSM is chosen reach the CPU solve when it is chosen again.
#[test]
fn changes_made_under_htsm_are_solved_later() {
    let mut s = session(SolveMode::Render);
    s.solve();
    s.set_settings(FrameSettings { method: Method::Htsm, ..*s.settings() });
    s.solve();
    let bent = deform::twist(Vec3::ZERO, Vec3::Y, 0.8).deformed(&generate::icosphere(2)).positions;
    s.set_positions(&bent);
    s.solve();
    s.set_settings(FrameSettings { method: Method::Hierarchical, ..*s.settings() });
    let b = s.solve().face_b.clone();
    let mut fresh = session(SolveMode::Render);
    fresh.set_positions(&bent);
    assert_eq!(b, fresh.solve().face_b);
}

#[test]
fn names_parse_and_bad_ones_list_the_choices() {
    for m in SolveMode::ALL {
        assert_eq!(m.name().parse::<SolveMode>(), Ok(m));
    }
    for m in Method::ALL {
        assert_eq!(m.name().to_uppercase().parse::<Method>(), Ok(m));
    }
    let e = "fast".parse::<SolveMode>().unwrap_err();
    assert_eq!(e, "unknown mode \"fast\"; expected one of render, incremental, refit, on-the-fly");
}

/// Moving the eye redoes what depends on it (view-ray single scattering and the body's chord
/// along the view ray) and nothing else.
#[test]
fn moving_the_eye_redoes_only_single_scattering() {
    let mut s = session(SolveMode::Render);
    s.set_eye(Some(Vec3::new(0.0, 0.0, 5.0)));
    let a = s.solve().clone();
    s.set_eye(Some(Vec3::new(5.0, 0.0, 0.0)));
    let b = s.solve().clone();
    assert!(b.fresh);
    assert_eq!((b.timings.link_ms, b.timings.gather_ms, b.timings.irradiance_ms), (0.0, 0.0, 0.0));
    assert!(b.timings.single_scattering_ms > 0.0);
    assert_eq!(a.face_b, b.face_b);
    assert_eq!(a.vertex_single.len(), a.vertex_radiance.len());
    assert_ne!(a.vertex_single, b.vertex_single);
    assert!(a.vertex_single.iter().all(|s| s.min_element() >= 0.0));
    assert!(a.vertex_single.iter().any(|s| s.max_element() > 0.0));
    // Without an eye: `B / (c π)` alone, as solved.
    s.set_eye(None);
    let c = s.solve().clone();
    assert!(c.vertex_single.is_empty());
    let diffuse = shading::diffuse_radiance(&s.mesh().face_to_vertex(&c.face_b), s.profile());
    assert_eq!(c.vertex_radiance, diffuse);
    // A 5 cm marble sphere is a half-space to the chord but where it is seen edge-on, on the
    // side the light reaches (beyond it, the light that crossed leaves by the round part's
    // lobe, `shading::transmitted_exit`).
    let light = Vec3::new(1.0, 2.0, 3.0);
    let lit: Vec<bool> =
        s.mesh().positions.iter().map(|p| p.normalize().dot((light - *p).normalize()) > 0.2).collect();
    for seen in [&a, &b] {
        let ratio: Vec<f32> = seen
            .vertex_radiance
            .iter()
            .zip(&diffuse)
            .zip(&lit)
            .filter(|(_, lit)| **lit)
            .map(|((r, d), _)| (*r / *d).max_element())
            .collect();
        let near_one = ratio.iter().filter(|r| (**r - 1.0).abs() < 0.01).count();
        assert!(near_one * 10 > ratio.len() * 9, "{near_one} of {}", ratio.len());
    }
}

/// On a small ketchup sphere (red: a 4 mm mean free path on a 10 mm radius) the diffuse
/// radiance each vertex sends towards the eye is `B / (c π)` times the sphere's chord factor
/// (`shading::exit_chord`): `1 - e^{-σ_t 2 R μ_t}` over its mean, on its lit side. Faceting
/// moves it by a few per cent.
#[test]
fn a_small_sphere_sends_its_diffuse_light_along_its_chords() {
    let mesh = generate::icosphere(4);
    let mut ketchup = Material::by_name("ketchup").unwrap();
    ketchup.eta = 1.0;
    let transport = Transport::new(ketchup, 0.02);
    let mut s = FrameSession::new(mesh, None, transport, FrameSettings::default());
    s.set_lights(key_light());
    let eye = Vec3::new(0.0, 0.0, 6.0);
    s.set_eye(Some(eye));
    let solved = s.solve().clone();
    let diffuse = shading::diffuse_radiance(&s.mesh().face_to_vertex(&solved.face_b), s.profile());
    let chord = shading::exit_chord::ExitChord::new(s.profile()).unwrap();
    // Unit sphere: thickness 2 along the normal, slabness 0.
    let mean = chord.mean(2.0, 0.0);
    let sigma_t = s.profile().sigma_t.map(|v| v as f32);
    let mut checked = 0;
    for (v, p) in s.mesh().positions.iter().enumerate() {
        let mu_o = p.normalize().dot((eye - *p).normalize());
        // Seen, and lit: on the dark side the little light there is the sphere's transmitted
        // light, which leaves by its own lobe (`shading::transmitted_exit`).
        let lit = p.normalize().dot((Vec3::new(1.0, 2.0, 3.0) - *p).normalize()) > 0.0;
        if mu_o < 0.2 || !lit {
            continue;
        }
        // eta = 1: the view ray goes straight on; its chord in a unit sphere is 2 μ.
        let expected = Rgb::from_array(std::array::from_fn(|c| -(-sigma_t[c] * 2.0 * mu_o).exp_m1())) / mean;
        let got = solved.vertex_radiance[v] / diffuse[v];
        assert!(
            ((got - expected).abs() / expected).max_element() < 0.05,
            "μ_o {mu_o}: {got} against {expected}"
        );
        checked += 1;
    }
    assert!(checked > 500, "{checked}");
}

/// Light that crossed a round body flows on along its surface and leaves tilted that way
/// (`shading::transmitted_exit`): on a small ketchup sphere lit from below, the dark side's
/// rim (50-80 degrees from the antipode) looks dimmer than a normal-centred exit (the slab's,
/// `--ablate round-exit`) says from the lit side, where the light leaves tilted away from the
/// eye, and brighter from beyond it.
#[test]
fn light_that_crossed_a_sphere_leaves_tilted_on() {
    let mesh = generate::icosphere(4);
    let mut ketchup = Material::by_name("ketchup").unwrap();
    ketchup.eta = 1.0;
    let light = vec![SceneLight::from(Light::Directional { direction: Vec3::Z, irradiance: Vec3::ONE })];
    let rim_red = |eye: Vec3, tilt: bool| {
        let mut settings = FrameSettings::default();
        settings.ablate.round_exit = !tilt;
        let mut s = FrameSession::new(mesh.clone(), None, Transport::new(ketchup.clone(), 0.02), settings);
        s.set_lights(light.clone());
        s.set_eye(Some(eye));
        let radiance = s.solve().vertex_radiance.clone();
        let mut sum = 0.0;
        for (v, p) in s.mesh().positions.iter().enumerate() {
            let n = p.normalize();
            let from_antipode = n.z.clamp(-1.0, 1.0).acos().to_degrees();
            if (50.0..80.0).contains(&from_antipode) && n.x > 0.5 && n.dot((eye - *p).normalize()) > 0.2 {
                sum += radiance[v].x;
            }
        }
        sum
    };
    let lit_side = Vec3::new(6.0, 0.0, -2.0);
    let beyond = Vec3::new(0.0, 0.0, 6.0);
    let (dimmer, brighter) =
        (rim_red(lit_side, true) / rim_red(lit_side, false), rim_red(beyond, true) / rim_red(beyond, false));
    println!(
        "the rim's red with the tilt over without: from the lit side {dimmer:.3}, from beyond {brighter:.3}"
    );
    // Measured 0.59 and 1.46 (against the slab's lobe): the walk's tilt there is 0.13-0.14, and
    // the lobe `1 + 7.5 μ̄ μ_o (ω·t)` spans about 0.4-1.6 over these views, on most of the rim's
    // light.
    assert!(dimmer > 0.4 && dimmer < 0.85, "from the lit side: {dimmer}");
    assert!(brighter > 1.15 && brighter < 1.6, "from beyond: {brighter}");
}

/// With the split view terms (the viewer's), a camera move draws the transmitted light's exit
/// lobe as a fresh per-eye solve does: a skim-milk sphere lit from behind, at index 1 and at
/// the presets' 1.3, seen from beyond after a move, vertex for vertex.
#[test]
fn a_split_camera_move_draws_the_light_that_crossed() {
    use crate::shading::view_basis::ViewTerms;
    let mesh = generate::icosphere(3);
    let light = vec![SceneLight::from(Light::Directional {
        direction: Vec3::new(0.3, -0.3, 0.9).normalize(),
        irradiance: Vec3::ONE,
    })];
    let (eye_a, eye_b) = (Vec3::new(0.0, 1.0, 5.0), Vec3::new(2.5, 1.0, 4.5));
    for eta in [1.0, 1.3] {
        let mut milk = Material::by_name("skimmilk").unwrap();
        milk.eta = eta;
        let session = || {
            let mut s = FrameSession::new(
                mesh.clone(),
                None,
                Transport::new(milk.clone(), 0.02),
                FrameSettings::default(),
            );
            s.set_lights(light.clone());
            s
        };
        let mut split = session();
        split.set_view_terms(ViewTerms::Split);
        split.set_eye(Some(eye_a));
        split.solve();
        split.set_eye(Some(eye_b));
        let moved = split.solve().vertex_radiance.clone();
        let mut fresh = session();
        fresh.set_eye(Some(eye_b));
        let want = fresh.solve().vertex_radiance.clone();
        let mut err: Vec<f32> = mesh
            .positions
            .iter()
            .enumerate()
            .filter(|(_, p)| p.normalize().dot((eye_b - **p).normalize()) > 0.2 && p.z > 0.0)
            .map(|(v, _)| (moved[v].element_sum() / want[v].element_sum() - 1.0).abs())
            .collect();
        err.sort_by(f32::total_cmp);
        let (median, p90) = (err[err.len() / 2], err[err.len() * 9 / 10]);
        println!("eta {eta}: {} vertices on the far side, median {median:.4}, 90th {p90:.4}", err.len());
        // Measured 0.0000 and at most 0.0004; without the exit lobe on the split the far side
        // read 16% off at the median and 24% at the 90th percentile (index 1).
        assert!(median < 0.005 && p90 < 0.03, "eta {eta}: median {median}, 90th {p90}");
    }
}

/// The validation's directional key light.
fn validation_light() -> Vec<SceneLight> {
    vec![SceneLight::from(Light::Directional {
        direction: Vec3::new(-0.5, -0.7, -0.5).normalize(),
        irradiance: Vec3::ONE,
    })]
}

/// A session on `bunny` (marble) in `mode` with two bounces, lit by [`validation_light`].
fn bounced_bunny(bunny: &crate::mesh::Mesh, mode: SolveMode) -> FrameSession {
    let settings = FrameSettings { mode, bounces: 2, ..FrameSettings::default() };
    let mut s = FrameSession::new(bunny.clone(), None, marble(), settings);
    s.set_lights(validation_light());
    s
}

/// Bounces between parts trace their rays once: a light change reuses them (render mode: the
/// same `B` as a new session under that light), a deformation past the refit's reach traces
/// them again (on the fly: the same `B` as a new session at that pose, which stale rays would
/// not give).
#[test]
fn bounce_rays_are_kept_until_the_mesh_moves() {
    let bunny = crate::mesh::embedded::bunny();
    let bounced = |mode| bounced_bunny(&bunny, mode);
    let mut s = bounced(SolveMode::Render);
    let first = s.solve().face_b.clone();
    let mut unbounced = FrameSession::new(bunny.clone(), None, marble(), FrameSettings::default());
    unbounced.set_lights(validation_light());
    assert_ne!(first, unbounced.solve().face_b, "the bunny's parts light each other");

    let other = vec![SceneLight::from(Light::Directional {
        direction: Vec3::new(0.6, -0.8, 0.0),
        irradiance: Vec3::ONE,
    })];
    s.set_lights(other.clone());
    let relit = s.solve().face_b.clone();
    let mut fresh = bounced(SolveMode::Render);
    fresh.set_lights(other);
    assert_eq!(relit, fresh.solve().face_b);

    let bent = deform::twist(Vec3::ZERO, Vec3::Y, 0.8).deformed(&bunny).positions;
    let mut s = bounced(SolveMode::OnTheFly);
    s.solve();
    s.set_positions(&bent);
    let moved = s.solve().face_b.clone();
    let mut fresh = bounced(SolveMode::OnTheFly);
    fresh.set_positions(&bent);
    assert_eq!(moved, fresh.solve().face_b);
}

/// A bump growing on the bunny's ear over an animation: each frame refits the bounce rays and
/// the finite-body gain's rays of the frame before (tracing again the faces that turned), and
/// stays close to a new session at that pose, which traces them.
#[test]
fn refitted_bounce_rays_stay_close_to_traced_ones() {
    let bunny = crate::mesh::embedded::bunny();
    let session = || bounced_bunny(&bunny, SolveMode::Render);
    let mut s = session();
    s.solve();
    let (frames, mut refitted) = (12, false);
    for i in 1..=frames {
        let t = i as f32 / frames as f32;
        let pose = deform::bump(Vec3::new(0.0, 9.6, -1.3), 1.5, 0.5 * t).deformed(&bunny).positions;
        s.set_positions(&pose);
        let got = s.solve().face_b.clone();
        let mut fresh = session();
        fresh.set_positions(&pose);
        let want = fresh.solve().face_b.clone();
        let mut rel: Vec<f32> =
            got.iter().zip(&want).map(|(g, w)| ((g.x + g.y + g.z) / (w.x + w.y + w.z) - 1.0).abs()).collect();
        rel.sort_by(f32::total_cmp);
        let (median, p99, max) = (rel[rel.len() / 2], rel[rel.len() * 99 / 100], rel[rel.len() - 1]);
        // Measured: median under 3.1e-5, 99th percentile under 2.0%, worst 13% (faces that see
        // the ear edge-on, where one of 64 bounce rays hits or misses the moved part).
        assert!(median < 1e-3 && p99 < 0.04 && max < 0.3, "frame {i}: {median:.2e} / {p99:.2e} / {max:.2e}");
        refitted |= max > 0.0;
    }
    assert!(refitted, "some frame refits rather than traces");
}

/// The bounces' geometric tail (`session/bounces.rs`) stands for the bounces after the set
/// number: three bounces with it meet the whole series (eight bounces, past which what is left
/// is below a thousandth of `B` here) closer than three alone, over the mesh and face by face.
#[test]
fn the_bounce_tail_stands_for_the_bounces_left_out() {
    let bunny = crate::mesh::embedded::bunny();
    let solve = |bounces, tail: bool| {
        let mut settings = FrameSettings { bounces, ..FrameSettings::default() };
        settings.ablate.bounce_tail = !tail;
        let mut s = FrameSession::new(bunny.clone(), None, marble(), settings);
        s.set_lights(validation_light());
        s.solve().face_b.clone()
    };
    let series = solve(8, false);
    let sum = |b: &Rgb| b.x + b.y + b.z;
    // The area-weighted total's relative error and the 99th percentile of the faces'.
    let errors = |b: &[Rgb]| {
        let area = |f: usize| bunny.face_area(f);
        let total: f32 = (0..b.len()).map(|f| (sum(&b[f]) - sum(&series[f])) * area(f)).sum::<f32>()
            / (0..b.len()).map(|f| sum(&series[f]) * area(f)).sum::<f32>();
        let mut rel: Vec<f32> = b.iter().zip(&series).map(|(g, w)| (sum(g) / sum(w) - 1.0).abs()).collect();
        rel.sort_by(f32::total_cmp);
        (total, rel[rel.len() * 99 / 100])
    };
    let (cut, tailed) = (errors(&solve(3, false)), errors(&solve(3, true)));
    println!(
        "three bounces: total {:.2e}, p99 {:.2e}; with the tail: {:.2e}, {:.2e}",
        cut.0, cut.1, tailed.0, tailed.1
    );
    assert!(cut.0 < 0.0, "three bounces alone leave light out: {}", cut.0);
    // Measured: the total 1.5e-4 short -> 2.0e-5 short, the 99th percentile 7.7e-3 -> 3.9e-3
    // (one ratio for the mesh; a face's own bounces settle at their own pace).
    assert!(tailed.0.abs() < 0.25 * cut.0.abs() && tailed.1 < 0.6 * cut.1, "{cut:?} -> {tailed:?}");
}
