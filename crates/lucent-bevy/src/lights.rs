//! Bevy's lights in lucent's units.
//!
//! lucent's radiometry is consistent but unit-free (ARCHITECTURE.md, "Units"): a point light's
//! intensity per unit solid angle with distances in mesh units, a directional light's
//! irradiance. Bevy's lights are photometric, and Bevy's own shaders turn them into luminance
//! (cd/m²) before the camera's exposure. The plugin feeds lucent the same quantities Bevy's
//! shaders use, so lucent's radiance comes out in cd/m² and sits in Bevy's exposure like any
//! other surface:
//!
//! | Bevy light | Bevy unit | lucent light | lucent value |
//! |---|---|---|---|
//! | `PointLight { color, intensity }` | lumens | `Light::Point` | `color × intensity / 4π` (cd: Bevy's own conversion) |
//! | `SpotLight { color, intensity, inner_angle, outer_angle }` | lumens | `Light::Spot` | `color × intensity / 4π` on the axis (Bevy does not concentrate a spot's lumens into its cone either); cone `outer_angle`, soft edge `1 - inner_angle / outer_angle` |
//! | `DirectionalLight { color, illuminance }` | lux | `Light::Directional` | `color × illuminance` (lux) |
//!
//! `color` is taken in linear RGB. Positions and directions go into the body's local (mesh)
//! frame through its `GlobalTransform`; an intensity is divided by the square of the body's
//! scale there (irradiance `I / d²` must not change with the units `d` is measured in).
//!
//! Not mapped: a point or spot light's `range` cut-off and `radius` (lucent's lights are points
//! without a range), the spot's falloff curve (lucent's is a smoothstep in angle, Bevy's a
//! squared linear ramp in cosine; both are 1 inside `inner_angle` and 0 outside `outer_angle`),
//! Bevy's ambient light and environment maps, and `shadow_maps_enabled`: lucent always shadows
//! its own body from every light by ray casts (that flag governs only Bevy's shadow maps on
//! other objects).

use bevy::math::{Affine3A, Vec3 as BVec3};
use bevy::prelude::*;
use lucent_core::irradiance::{Light, SceneLight};

/// A Bevy light in lucent's units, in world space (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MappedLight {
    /// An isotropic point light at `position` (world, m) with intensity `cd` (linear RGB).
    Point { position: [f32; 3], cd: [f32; 3] },
    /// A spot at `position` (world) shining along the unit `axis`, `cd` on its axis, cone
    /// half-angle `cone` (radians, 0..π/2) and soft-edge fraction `soft_edge` (0..1).
    Spot { position: [f32; 3], axis: [f32; 3], cd: [f32; 3], cone: f32, soft_edge: f32 },
    /// A distant light travelling along the unit `direction` with illuminance `lux` (linear RGB).
    Directional { direction: [f32; 3], lux: [f32; 3] },
}

/// Luminous intensity (cd) of an isotropic source of `lumens` in colour `color`: Bevy's
/// conversion `lumens / 4π`, per linear channel.
pub fn candela(color: Color, lumens: f32) -> [f32; 3] {
    let c = color.to_linear();
    let s = lumens / (4.0 * std::f32::consts::PI);
    [c.red * s, c.green * s, c.blue * s]
}

/// Illuminance (lux) per linear channel of a directional light of `lux` in colour `color`.
pub fn illuminance(color: Color, lux: f32) -> [f32; 3] {
    let c = color.to_linear();
    [c.red * lux, c.green * lux, c.blue * lux]
}

impl MappedLight {
    /// A Bevy point light at `transform`.
    pub fn point(light: &PointLight, transform: &GlobalTransform) -> Self {
        MappedLight::Point {
            position: transform.translation().to_array(),
            cd: candela(light.color, light.intensity),
        }
    }

    /// A Bevy spot light at `transform` (it shines along the transform's forward, -Z).
    pub fn spot(light: &SpotLight, transform: &GlobalTransform) -> Self {
        let cone = light.outer_angle.clamp(0.0, std::f32::consts::FRAC_PI_2);
        let soft_edge = if cone > 0.0 { (1.0 - light.inner_angle / cone).clamp(0.0, 1.0) } else { 0.0 };
        MappedLight::Spot {
            position: transform.translation().to_array(),
            axis: transform.forward().as_vec3().to_array(),
            cd: candela(light.color, light.intensity),
            cone,
            soft_edge,
        }
    }

    /// A Bevy directional light at `transform` (it travels along the transform's forward, -Z).
    pub fn directional(light: &DirectionalLight, transform: &GlobalTransform) -> Self {
        MappedLight::Directional {
            direction: transform.forward().as_vec3().to_array(),
            lux: illuminance(light.color, light.illuminance),
        }
    }

    /// The light in the local (mesh) frame of a body at `world_from_local`, as lucent's session
    /// takes it. The body's scale is taken as uniform (the cube root of the determinant).
    pub fn to_local(&self, world_from_local: &Affine3A) -> SceneLight {
        let local_from_world = world_from_local.inverse();
        let scale = world_from_local.matrix3.determinant().abs().cbrt().max(1e-20);
        let at = |p: [f32; 3]| vec3(local_from_world.transform_point3(BVec3::from(p)));
        let along =
            |d: [f32; 3]| vec3(local_from_world.transform_vector3(BVec3::from(d)).normalize_or_zero());
        let scaled = |i: [f32; 3]| vec3(BVec3::from(i) / (scale * scale));
        let light = match *self {
            MappedLight::Point { position, cd } => {
                Light::Point { position: at(position), intensity: scaled(cd) }
            }
            MappedLight::Spot { position, axis, cd, cone, soft_edge } => Light::Spot {
                position: at(position),
                direction: along(axis),
                intensity: scaled(cd),
                cone_angle: cone,
                soft_edge,
            },
            MappedLight::Directional { direction, lux } => {
                Light::Directional { direction: along(direction), irradiance: vec3(BVec3::from(lux)) }
            }
        };
        SceneLight { light, shadows: true }
    }
}

/// Bevy's vector as lucent's (the two crates use different glam versions).
fn vec3(v: BVec3) -> glam::Vec3 {
    glam::Vec3::new(v.x, v.y, v.z)
}

/// Every point, spot and directional light in the world, mapped (in query order).
pub fn gather(
    points: &Query<(&PointLight, &GlobalTransform)>,
    spots: &Query<(&SpotLight, &GlobalTransform)>,
    suns: &Query<(&DirectionalLight, &GlobalTransform)>,
) -> Vec<MappedLight> {
    let mut out = Vec::new();
    out.extend(points.iter().map(|(l, t)| MappedLight::point(l, t)));
    out.extend(spots.iter().map(|(l, t)| MappedLight::spot(l, t)));
    out.extend(suns.iter().map(|(l, t)| MappedLight::directional(l, t)));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_light_of_4pi_lumens_is_one_candela_and_irradiance_follows_the_body_scale() {
        let light = PointLight { intensity: 4.0 * std::f32::consts::PI, color: Color::WHITE, ..default() };
        let at = GlobalTransform::from_translation(BVec3::new(0.0, 2.0, 0.0));
        let m = MappedLight::point(&light, &at);
        let MappedLight::Point { cd, .. } = m else { panic!("not a point light") };
        for c in cd {
            assert!((c - 1.0).abs() < 1e-6, "{cd:?}");
        }
        // A body scaled by 2 sees the light at 1 mesh unit: irradiance 1/2² must stay 1/4.
        let body = Affine3A::from_scale(BVec3::splat(2.0));
        let SceneLight { light: Light::Point { position, intensity }, shadows } = m.to_local(&body) else {
            panic!("not a point light")
        };
        assert!(shadows);
        assert!((position - glam::Vec3::new(0.0, 1.0, 0.0)).length() < 1e-6, "{position}");
        let e = intensity.x / position.length_squared();
        assert!((e - 0.25).abs() < 1e-6, "irradiance {e}");
    }

    #[test]
    fn a_directional_light_keeps_its_lux_and_travels_along_forward_in_the_local_frame() {
        let light = DirectionalLight { illuminance: 3.0, color: Color::srgb(1.0, 0.5, 0.0), ..default() };
        // Looking down -Y: it travels along -Y.
        let t = GlobalTransform::from(Transform::default().looking_to(BVec3::NEG_Y, BVec3::Z));
        let m = MappedLight::directional(&light, &t);
        let body = Affine3A::from_rotation_z(std::f32::consts::FRAC_PI_2);
        let SceneLight { light: Light::Directional { direction, irradiance }, .. } = m.to_local(&body) else {
            panic!("not directional")
        };
        // Rotated +90° about Z, the body sees world -Y as local -X.
        assert!((direction - glam::Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-5, "{direction}");
        let lin = Color::srgb(1.0, 0.5, 0.0).to_linear();
        assert!((irradiance.x - 3.0 * lin.red).abs() < 1e-5);
        assert!((irradiance.y - 3.0 * lin.green).abs() < 1e-5);
        assert_eq!(irradiance.z, 0.0);
    }

    #[test]
    fn a_spot_keeps_its_cone_and_soft_edge() {
        let light = SpotLight { outer_angle: 0.6, inner_angle: 0.3, intensity: 100.0, ..default() };
        let m = MappedLight::spot(&light, &GlobalTransform::IDENTITY);
        let MappedLight::Spot { cone, soft_edge, axis, .. } = m else { panic!("not a spot") };
        assert_eq!(cone, 0.6);
        assert!((soft_edge - 0.5).abs() < 1e-6);
        assert_eq!(axis, [0.0, 0.0, -1.0]);
    }
}
