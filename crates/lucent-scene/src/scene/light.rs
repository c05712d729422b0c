//! A scene's lights in every syntax a user writes them: the scene file's `[[light]]` table
//! ([`LightSpec`], with its range checks), the command line's `--light KIND:x,y,z`
//! ([`parse_light`]), the default key and back lights ([`default_lights`]) and
//! the turn of `--orbit-light` ([`orbit_lights`]). The light itself, and how it lights a point,
//! is `lucent_core::irradiance::Light` (Mertens §5.3); everything here past the syntax reads it
//! through its accessors, so a new kind of light is a variant there and its syntax here.

use super::{one, white, yes};
use anyhow::{Context, Result, bail};
use glam::Vec3;
use lucent_core::Rgb;
use lucent_core::irradiance::{Light, SceneLight};
use lucent_core::mesh::Mesh;
use serde::Deserialize;

fn default_cone() -> f32 {
    30.0
}
fn default_soft_edge() -> f32 {
    0.2
}

/// One `[[light]]` table, selected by `type`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum LightSpec {
    /// An isotropic point light.
    Point {
        /// Position, mesh units.
        position: [f32; 3],
        /// Colour (linear RGB, >= 0). Default white.
        #[serde(default = "white")]
        color: [f32; 3],
        /// Irradiance (times `color`) that the light gives a surface facing it at the centre of
        /// the mesh's bounding box (>= 0), so brightness does not depend on the mesh's units.
        /// Default 1.
        #[serde(default = "one")]
        intensity: f32,
        /// Whether the mesh shadows itself from this light. Default true.
        #[serde(default = "yes")]
        shadows: bool,
    },
    /// A distant light.
    #[serde(alias = "dir")]
    Directional {
        /// The direction the light travels (non-zero).
        direction: [f32; 3],
        /// Colour (linear RGB, >= 0). Default white.
        #[serde(default = "white")]
        color: [f32; 3],
        /// Irradiance (times `color`) on a surface facing the light (>= 0). Default 1.
        #[serde(default = "one")]
        intensity: f32,
        /// Whether the mesh shadows itself from this light. Default true.
        #[serde(default = "yes")]
        shadows: bool,
    },
    /// A spot light: a point light limited to a cone.
    Spot {
        /// Position, mesh units.
        position: [f32; 3],
        /// The direction the spot points (non-zero).
        direction: [f32; 3],
        /// Colour (linear RGB, >= 0). Default white.
        #[serde(default = "white")]
        color: [f32; 3],
        /// Irradiance (times `color`) on the spot's axis at the distance of the mesh's
        /// bounding-box centre (>= 0). Default 1.
        #[serde(default = "one")]
        intensity: f32,
        /// Cone half-angle, degrees (0..180). Default 30.
        #[serde(default = "default_cone")]
        cone_angle: f32,
        /// Fraction of the cone angle over which the light fades out (0..1). Default 0.2.
        #[serde(default = "default_soft_edge")]
        soft_edge: f32,
        /// Whether the mesh shadows itself from this light. Default true.
        #[serde(default = "yes")]
        shadows: bool,
    },
}

impl LightSpec {
    /// The light for the irradiance computation. Point and spot intensities are set so the
    /// light gives `intensity * color` at the distance of `center` (mesh units; the centre of
    /// the mesh's bounding box).
    pub fn light(&self, center: Vec3) -> SceneLight {
        match *self {
            LightSpec::Point { position, color, intensity, shadows } => {
                let p = Vec3::from_array(position);
                SceneLight {
                    light: Light::Point {
                        position: p,
                        intensity: Rgb::from_array(color) * intensity * d2(p, center),
                    },
                    shadows,
                }
            }
            LightSpec::Directional { direction, color, intensity, shadows } => SceneLight {
                light: Light::Directional {
                    direction: Vec3::from_array(direction).normalize(),
                    irradiance: Rgb::from_array(color) * intensity,
                },
                shadows,
            },
            LightSpec::Spot { position, direction, color, intensity, cone_angle, soft_edge, shadows } => {
                let p = Vec3::from_array(position);
                SceneLight {
                    light: Light::Spot {
                        position: p,
                        direction: Vec3::from_array(direction).normalize(),
                        intensity: Rgb::from_array(color) * intensity * d2(p, center),
                        cone_angle: cone_angle.to_radians(),
                        soft_edge,
                    },
                    shadows,
                }
            }
        }
    }

    /// Checks the ranges that the types do not express; the error names the key and its range.
    pub fn validate(&self) -> Result<()> {
        let finite = |v: &[f32; 3]| v.iter().all(|x| crate::ranges::COORDINATE.contains(x));
        let (color, intensity) = match self {
            LightSpec::Point { position, color, intensity, .. } => {
                if !finite(position) {
                    bail!("position must be within {:?} mesh units", crate::ranges::COORDINATE);
                }
                (color, *intensity)
            }
            LightSpec::Directional { direction, color, intensity, .. } => {
                check_direction(direction)?;
                (color, *intensity)
            }
            LightSpec::Spot { position, direction, color, intensity, cone_angle, soft_edge, .. } => {
                if !finite(position) {
                    bail!("position must be within {:?} mesh units", crate::ranges::COORDINATE);
                }
                check_direction(direction)?;
                if !(*cone_angle > 0.0 && *cone_angle < 180.0) {
                    bail!("cone_angle must be within 0..180 degrees, got {cone_angle}");
                }
                if !(0.0..=1.0).contains(soft_edge) {
                    bail!("soft_edge must be within 0..1, got {soft_edge}");
                }
                (color, *intensity)
            }
        };
        use crate::ranges::{INTENSITY, check};
        for c in color {
            check("color component", *c, &INTENSITY).map_err(anyhow::Error::msg)?;
        }
        check("intensity", intensity, &INTENSITY).map_err(anyhow::Error::msg)?;
        Ok(())
    }
}

fn d2(p: Vec3, center: Vec3) -> f32 {
    (p - center).length_squared().max(1e-12)
}

fn check_direction(d: &[f32; 3]) -> Result<()> {
    let v = Vec3::from_array(*d);
    if !d.iter().all(|x| crate::ranges::COORDINATE.contains(x)) || v.length_squared() == 0.0 {
        bail!("direction must be non-zero with components within {:?}, got {d:?}", crate::ranges::COORDINATE);
    }
    Ok(())
}

/// A key light in front of the object (towards the default camera), above and to the right, and
/// a back light behind and above that shows the translucency of thin parts (Mertens fig. 6.3);
/// each gives irradiance 1 at the object's centre. The CLI and the viewer both start with these.
pub fn default_lights(mesh: &Mesh) -> [Light; 2] {
    let (center, radius) = lucent_core::camera::bounding_sphere(&mesh.positions);
    let key = center + Vec3::new(1.0, 1.1, 1.8) * radius;
    let back = center + Vec3::new(-0.3, 0.6, -2.2) * radius;
    [point_light(key, center), point_light(back, center)]
}

/// A white point light whose irradiance at the object's centre distance is 1 (arbitrary but
/// consistent units), so images look alike whatever the mesh units.
fn point_light(position: Vec3, center: Vec3) -> Light {
    let d2 = position.distance_squared(center).max(1e-12);
    Light::Point { position, intensity: Vec3::splat(d2) }
}

/// Parses three comma-separated numbers; errors start with `label` and end with `usage`.
pub fn parse_three(label: &str, text: &str, usage: &str) -> Result<Vec3> {
    let v: Vec<f32> = text
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| anyhow::anyhow!("{label}: {e}; {usage}"))?;
    let [x, y, z] = v[..] else {
        bail!("{label}: {} numbers given; {usage}", v.len());
    };
    Ok(Vec3::new(x, y, z))
}

/// Parses `point:x,y,z` (position, mesh units) or `dir:x,y,z` (direction the light travels).
/// Point lights give irradiance 1 at the distance of `center`; directional lights give 1.
pub fn parse_light(spec: &str, center: Vec3) -> Result<Light> {
    let usage = "expected point:x,y,z (position, mesh units) or dir:x,y,z (direction of travel)";
    let (kind, rest) = spec.split_once(':').with_context(|| format!("--light {spec:?}: {usage}"))?;
    let p = parse_three(&format!("--light {spec:?}"), rest, usage)?;
    let range = crate::ranges::COORDINATE;
    if !p.to_array().iter().all(|c| range.contains(c)) {
        bail!("--light {spec:?}: coordinates must be within {}..={}", range.start(), range.end());
    }
    match kind.trim().to_ascii_lowercase().as_str() {
        "point" => Ok(point_light(p, center)),
        "dir" | "directional" => {
            if p.length_squared() == 0.0 {
                bail!("--light {spec:?}: a direction cannot be zero");
            }
            Ok(Light::Directional { direction: p.normalize(), irradiance: Vec3::ONE })
        }
        other => bail!("--light {spec:?}: unknown kind {other:?}; {usage}"),
    }
}

/// The lights turned by `angle` radians about the vertical axis through `center` (positions
/// and directions, whatever the kind), for `--orbit-light`.
pub fn orbit_lights(lights: &[SceneLight], center: Vec3, angle: f32) -> Vec<SceneLight> {
    let q = glam::Quat::from_rotation_y(angle);
    lights
        .iter()
        .map(|l| {
            let mut light = l.light;
            if let Some(p) = light.position() {
                light.set_position(center + q * (p - center));
            }
            if let Some(d) = light.direction() {
                light.set_direction(q * d);
            }
            SceneLight { light, shadows: l.shadows }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lights_parse_and_bad_ones_are_rejected() {
        let c = Vec3::ZERO;
        assert_eq!(
            parse_light("point:0,3,4", c).unwrap(),
            Light::Point { position: Vec3::new(0.0, 3.0, 4.0), intensity: Vec3::splat(25.0) }
        );
        assert_eq!(
            parse_light("dir: 0, -2, 0", c).unwrap(),
            Light::Directional { direction: Vec3::NEG_Y, irradiance: Vec3::ONE }
        );
        for bad in ["point:1,2", "spot:1,2,3", "point", "dir:0,0,0", "point:a,b,c", "point:1,2,inf"] {
            let e = parse_light(bad, c).unwrap_err().to_string();
            assert!(e.contains(bad), "{bad}: {e}");
        }
    }

    /// Orbiting keeps the distance to the centre and turns about +Y.
    #[test]
    fn orbit_turns_about_the_vertical_axis() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        let l = [SceneLight::from(Light::Point { position: c + Vec3::X, intensity: Vec3::ONE })];
        let turned = orbit_lights(&l, c, std::f32::consts::FRAC_PI_2);
        let Light::Point { position, .. } = turned[0].light else { panic!() };
        assert!((position - (c - Vec3::Z)).length() < 1e-6, "{position}");
        // A spot turns its position and its axis; a distant light its direction.
        let spot = Light::Spot {
            position: c + Vec3::X,
            direction: Vec3::X,
            intensity: Vec3::ONE,
            cone_angle: 0.5,
            soft_edge: 0.2,
        };
        let dir = Light::Directional { direction: Vec3::X, irradiance: Vec3::ONE };
        let turned = orbit_lights(&[spot.into(), dir.into()], c, std::f32::consts::FRAC_PI_2);
        let Light::Spot { position, direction, cone_angle, .. } = turned[0].light else { panic!() };
        assert!((position - (c - Vec3::Z)).length() < 1e-6 && (direction + Vec3::Z).length() < 1e-6);
        assert_eq!(cone_angle, 0.5);
        let Some(direction) = turned[1].light.direction() else { panic!() };
        assert!((direction + Vec3::Z).length() < 1e-6, "{direction}");
    }
}
