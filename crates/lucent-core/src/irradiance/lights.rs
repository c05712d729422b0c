//! Point, directional and spot lights (Mertens §5.3 "point/spot lights"; the spot light of their
//! figure 6.5), and the light a face midpoint receives from one of them before shadowing.

use crate::Rgb;
use crate::bssrdf::Entry;
use glam::Vec3;

/// A light source. Radiometric units are arbitrary but consistent (think W and W/m^2); positions
/// are in mesh units and irradiance from a positional light falls off as `1 / d^2` with `d` in
/// mesh units.
///
/// Code outside this file reads a light through its accessors, so that a new kind is one
/// variant here: a light is either positional ([`Light::position`] is `Some`; a camera at that
/// position sees what it lights) or distant ([`Light::position`] is `None` and
/// [`Light::direction`] is `Some`), has a [`Light::power`], and may be limited to a
/// [`Light::cone`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// An isotropic point light at `position` (mesh units) with radiant `intensity` per channel
    /// (W/sr); irradiance falls off as `1 / d^2` with `d` in mesh units.
    Point { position: Vec3, intensity: Rgb },
    /// A distant light shining *along* `direction` (need not be unit), giving `irradiance`
    /// (W/m^2 per channel) on a surface facing it.
    Directional { direction: Vec3, irradiance: Rgb },
    /// A point light at `position` (mesh units) that emits only into a cone around `direction`
    /// (the way it shines; need not be unit). On the axis its radiant intensity is `intensity`
    /// (W/sr per channel). `cone_angle` is the cone's half-angle in radians (0..π); the intensity
    /// fades to zero over the outer `soft_edge` fraction (0..1) of that angle with a smoothstep
    /// in angle (0 gives a hard edge). See [`spot_falloff`].
    Spot { position: Vec3, direction: Vec3, intensity: Rgb, cone_angle: f32, soft_edge: f32 },
}

/// A light in a scene, with whether it casts shadows (ray cast against the mesh; see
/// [`super::shadow::ShadowCaster`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneLight {
    /// The light.
    pub light: Light,
    /// Whether faces occluded from the light by the mesh itself receive nothing from it.
    /// Default `true`.
    pub shadows: bool,
}

impl From<Light> for SceneLight {
    /// A light that casts shadows.
    fn from(light: Light) -> Self {
        SceneLight { light, shadows: true }
    }
}

/// Light arriving at a point, before the surface's orientation and Fresnel term apply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incident {
    /// Unit vector from the point towards the light.
    pub to_light: Vec3,
    /// Distance to the light in mesh units (`f32::INFINITY` for a directional light): the length
    /// a shadow ray must be free over.
    pub distance: f32,
    /// Irradiance on a surface facing the light squarely (per channel).
    pub irradiance: Rgb,
}

/// The spot light's angular falloff: 1 inside `cone_angle * (1 - soft_edge)`, 0 outside
/// `cone_angle`, and a smoothstep `t^2 (3 - 2t)` of the angle between (`t` = 1 at the inner
/// angle). `cos_angle` is the cosine between the spot axis and the direction to the point.
pub fn spot_falloff(cos_angle: f32, cone_angle: f32, soft_edge: f32) -> f32 {
    let angle = cos_angle.clamp(-1.0, 1.0).acos();
    let inner = cone_angle * (1.0 - soft_edge.clamp(0.0, 1.0));
    if angle >= cone_angle {
        0.0
    } else if angle <= inner {
        1.0
    } else {
        let t = (cone_angle - angle) / (cone_angle - inner);
        t * t * (3.0 - 2.0 * t)
    }
}

/// The cone a light is limited to (a spot light's), in the terms every renderer of it needs:
/// the subsurface irradiance ([`Light::incident`]), the mesh pass's highlight and HTSM's passes
/// (`lucent-gpu`) read a light's shape from [`Light::position`], [`Light::direction`],
/// [`Light::power`] and [`Light::cone`], never from its variant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// The cone's axis, the way the light shines, as the light holds it (need not be unit; a
    /// zero axis is a light that reaches nothing).
    pub axis: Vec3,
    /// Half-angle, radians (0..π).
    pub half_angle: f32,
    /// Fraction (0..1) of the half-angle over which the intensity fades out (see
    /// [`spot_falloff`]; 0 is a hard edge).
    pub soft_edge: f32,
}

/// The kind of a [`Light`], for editors and file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LightKind {
    /// [`Light::Point`].
    Point,
    /// [`Light::Spot`].
    Spot,
    /// [`Light::Directional`].
    Directional,
}

impl LightKind {
    /// Every kind, in the order editors list them.
    pub const ALL: [LightKind; 3] = [LightKind::Point, LightKind::Spot, LightKind::Directional];

    /// The kind's name (as scene files spell it).
    pub fn name(self) -> &'static str {
        match self {
            LightKind::Point => "point",
            LightKind::Spot => "spot",
            LightKind::Directional => "directional",
        }
    }
}

/// Spot cone half-angle a light gets when it becomes a spot, radians (30 degrees).
const DEFAULT_CONE: f32 = std::f32::consts::FRAC_PI_6;
/// Soft edge a light gets when it becomes a spot (fraction of the cone angle).
const DEFAULT_SOFT_EDGE: f32 = 0.2;

impl Light {
    /// Point, spot or directional.
    pub fn kind(&self) -> LightKind {
        match self {
            Light::Point { .. } => LightKind::Point,
            Light::Spot { .. } => LightKind::Spot,
            Light::Directional { .. } => LightKind::Directional,
        }
    }

    /// Position, mesh units (`None` for a directional light).
    pub fn position(&self) -> Option<Vec3> {
        match *self {
            Light::Point { position, .. } | Light::Spot { position, .. } => Some(position),
            Light::Directional { .. } => None,
        }
    }

    /// The direction the light shines (`None` for a point light, which shines everywhere).
    pub fn direction(&self) -> Option<Vec3> {
        match *self {
            Light::Spot { direction, .. } | Light::Directional { direction, .. } => Some(direction),
            Light::Point { .. } => None,
        }
    }

    /// The cone the light is limited to (`None` for lights that shine into every direction they
    /// face: point and directional).
    pub fn cone(&self) -> Option<Cone> {
        match *self {
            Light::Spot { direction, cone_angle, soft_edge, .. } => {
                Some(Cone { axis: direction, half_angle: cone_angle, soft_edge })
            }
            Light::Point { .. } | Light::Directional { .. } => None,
        }
    }

    /// Strength per channel: radiant intensity (W/sr; point, spot on its axis) or irradiance
    /// (W/m^2; directional).
    pub fn power(&self) -> Rgb {
        match *self {
            Light::Point { intensity, .. } | Light::Spot { intensity, .. } => intensity,
            Light::Directional { irradiance, .. } => irradiance,
        }
    }

    /// Moves a positional light (nothing for a directional one).
    pub fn set_position(&mut self, p: Vec3) {
        if let Light::Point { position, .. } | Light::Spot { position, .. } = self {
            *position = p;
        }
    }

    /// Turns a spot or directional light (nothing for a point light).
    pub fn set_direction(&mut self, d: Vec3) {
        if let Light::Spot { direction, .. } | Light::Directional { direction, .. } = self {
            *direction = d;
        }
    }

    /// Sets the strength per channel (see [`Light::power`]).
    pub fn set_power(&mut self, p: Rgb) {
        match self {
            Light::Point { intensity, .. } | Light::Spot { intensity, .. } => *intensity = p,
            Light::Directional { irradiance, .. } => *irradiance = p,
        }
    }

    /// This light as `kind`, keeping what both have (position, direction, strength); a light
    /// becoming positional is placed opposite its direction at `distance` from the origin, one
    /// becoming directed points at the origin, a new spot gets a 30 degree cone.
    pub fn with_kind(&self, kind: LightKind, distance: f32) -> Light {
        let power = self.power();
        let position = self
            .position()
            .unwrap_or_else(|| -self.direction().unwrap_or(Vec3::NEG_Y).normalize_or_zero() * distance);
        let direction = self.direction().unwrap_or(-position);
        match kind {
            LightKind::Point => Light::Point { position, intensity: power },
            LightKind::Directional => Light::Directional { direction, irradiance: power },
            LightKind::Spot => match *self {
                Light::Spot { .. } => *self,
                _ => Light::Spot {
                    position,
                    direction,
                    intensity: power,
                    cone_angle: DEFAULT_CONE,
                    soft_edge: DEFAULT_SOFT_EDGE,
                },
            },
        }
    }

    /// The light arriving at point `p` (mesh units), or `None` where it gets nothing (outside a
    /// spot's cone, or a light with zero direction).
    pub fn incident(&self, p: Vec3) -> Option<Incident> {
        match *self {
            Light::Point { position, intensity } => {
                let d = position - p;
                let d2 = d.length_squared().max(1e-12);
                let dist = d2.sqrt();
                Some(Incident { to_light: d / dist, distance: dist, irradiance: intensity / d2 })
            }
            Light::Directional { direction, irradiance } => {
                let to_light = -direction.try_normalize()?;
                Some(Incident { to_light, distance: f32::INFINITY, irradiance })
            }
            Light::Spot { position, direction, intensity, cone_angle, soft_edge } => {
                let axis = direction.try_normalize()?;
                let d = position - p;
                let d2 = d.length_squared().max(1e-12);
                let dist = d2.sqrt();
                let to_light = d / dist;
                let falloff = spot_falloff(axis.dot(-to_light), cone_angle, soft_edge);
                (falloff > 0.0).then(|| Incident {
                    to_light,
                    distance: dist,
                    irradiance: intensity * (falloff / d2),
                })
            }
        }
    }
}

/// Irradiance transmitted into the surface at `p` with unit normal `n` from one light, without
/// shadows: `E entry(cos) cos` (see [`Entry`]).
pub fn light_irradiance(light: &Light, p: Vec3, n: Vec3, entry: &Entry) -> Rgb {
    let Some(inc) = light.incident(p) else {
        return Rgb::ZERO;
    };
    let cos = n.dot(inc.to_light);
    if cos <= 0.0 {
        return Rgb::ZERO;
    }
    inc.irradiance * cos * entry.at(cos)
}
