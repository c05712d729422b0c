//! Deformers for animated meshes: the topology stays fixed, only positions move.
//!
//! They drive the deformable-object cases of Mertens et al. 2003 (§4, incremental and
//! on-the-fly modes: the hierarchy's topology is reused and only geometry changes). Each
//! deformer reads the *rest* positions and writes the deformed ones, so an animation computes
//! every frame from the rest pose and no error accumulates.
//!
//! [`Deformation`] is the command-line form (`twist:DEG`, `bump:x,y,z,radius,height`,
//! `noise:amplitude,frequency`), parsed with [`FromStr`] and animated by a parameter `t`.

use super::Mesh;
use glam::{Quat, Vec3};
use noise::{NoiseFn, Perlin};
use rayon::prelude::*;
use std::fmt;
use std::str::FromStr;

/// Largest vertex displacement since rays were traced, as a share of the mesh's extent then, up
/// to which a deformed mesh moves their hits with it instead of tracing them again (the bounce
/// rays between parts, the rays that measure the body under each face). A refit keeps each
/// ray's hit face, so it misses what the deformation newly hides or reveals.
pub const RETRACE_DISPLACEMENT: f32 = 0.02;

/// The pose that rays were traced at (see [`RETRACE_DISPLACEMENT`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TracedPose {
    /// Vertex positions when traced, mesh units.
    positions: Vec<Vec3>,
    /// The mesh's extent when traced, mesh units.
    extent: f32,
}

impl TracedPose {
    /// The pose of `mesh` now.
    pub fn of(mesh: &Mesh) -> Self {
        TracedPose { positions: mesh.positions.clone(), extent: mesh.extent() }
    }

    /// Whether `mesh` (with the vertices traced) is still within [`RETRACE_DISPLACEMENT`] of
    /// this pose, so that rays traced then may be refitted to it.
    pub fn holds(&self, mesh: &Mesh) -> bool {
        let reach = RETRACE_DISPLACEMENT * self.extent;
        self.positions.len() == mesh.positions.len()
            && mesh
                .positions
                .par_iter()
                .zip(&self.positions)
                .all(|(p, q)| p.distance_squared(*q) <= reach * reach)
    }
}

/// A position-only deformation of a rest mesh.
pub trait Deformer {
    /// Writes the deformed positions of `rest` into `out` (resized to
    /// `rest.positions.len()`); `rest` is not modified.
    fn apply(&self, rest: &Mesh, out: &mut Vec<Vec3>);

    /// `rest` with its positions deformed (same triangles).
    fn deformed(&self, rest: &Mesh) -> Mesh {
        let mut positions = Vec::new();
        self.apply(rest, &mut positions);
        Mesh::new(positions, rest.triangles.clone())
    }
}

/// Displaces vertices within `radius` of `center` along their rest vertex normal by
/// `height * (1 - (d / radius)^2)^2`, `d` the distance to `center`: full height at the centre,
/// falling smoothly (zero value and slope) to nothing at `radius`. Negative `height` dents.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bump {
    /// Centre of the bump, mesh units (usually on or near the surface).
    pub center: Vec3,
    /// Radius of influence, mesh units, > 0.
    pub radius: f32,
    /// Displacement at the centre along the vertex normal, mesh units; negative = dent.
    pub height: f32,
}

/// A [`Bump`] deformer.
pub fn bump(center: Vec3, radius: f32, height: f32) -> Bump {
    Bump { center, radius, height }
}

impl Bump {
    /// The falloff weight in [0, 1] at distance `d` from the centre.
    pub fn weight(&self, d: f32) -> f32 {
        if self.radius <= 0.0 || d >= self.radius {
            return 0.0;
        }
        let x = d / self.radius;
        (1.0 - x * x).powi(2)
    }
}

impl Deformer for Bump {
    fn apply(&self, rest: &Mesh, out: &mut Vec<Vec3>) {
        let normals = rest.vertex_normals();
        out.clear();
        rest.positions
            .par_iter()
            .zip(&normals)
            .map(|(&p, &n)| p + self.height * self.weight(p.distance(self.center)) * n)
            .collect_into_vec(out);
    }
}

/// Rotates each vertex about the axis through `axis_origin` along `axis_dir` by the angle
/// `angle_per_unit_length * s`, where `s = (p - axis_origin) . axis_dir / |axis_dir|` is the
/// signed coordinate along the axis: points at the origin's level stay, the angle grows
/// linearly along the axis (right-handed about `axis_dir`). Distances to the axis and
/// coordinates along it are preserved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Twist {
    /// A point on the axis, mesh units; the level of zero rotation.
    pub axis_origin: Vec3,
    /// Direction of the axis (any non-zero length; normalised when applied).
    pub axis_dir: Vec3,
    /// Rotation per mesh unit along the axis, radians per mesh unit.
    pub angle_per_unit_length: f32,
}

/// A [`Twist`] deformer.
pub fn twist(axis_origin: Vec3, axis_dir: Vec3, angle_per_unit_length: f32) -> Twist {
    Twist { axis_origin, axis_dir, angle_per_unit_length }
}

impl Deformer for Twist {
    fn apply(&self, rest: &Mesh, out: &mut Vec<Vec3>) {
        out.clear();
        let Some(axis) = self.axis_dir.try_normalize() else {
            out.extend_from_slice(&rest.positions);
            return;
        };
        rest.positions
            .par_iter()
            .map(|&p| {
                let r = p - self.axis_origin;
                let s = r.dot(axis);
                self.axis_origin + Quat::from_axis_angle(axis, self.angle_per_unit_length * s) * r
            })
            .collect_into_vec(out);
    }
}

/// Displaces each vertex along its rest vertex normal by
/// `amplitude * perlin(frequency * p + offset)` (3-D Perlin noise of the `noise` crate, values
/// in about [-1, 1]). Moving `offset` over time animates the surface; the result is a pure
/// function of (rest mesh, parameters), so equal offsets give identical positions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// Peak displacement, mesh units.
    pub amplitude: f32,
    /// Spatial frequency, noise lattice cells per mesh unit.
    pub frequency: f32,
    /// Offset in noise space (lattice cells), the animation parameter.
    pub offset: Vec3,
    /// Seed of the Perlin permutation table. Default [`Noise::SEED`].
    pub seed: u32,
}

impl Noise {
    /// The default seed (the `noise` crate's `Perlin::DEFAULT_SEED`).
    pub const SEED: u32 = Perlin::DEFAULT_SEED;
}

/// A [`Noise`] deformer with the default seed.
pub fn noise(amplitude: f32, frequency: f32, offset: Vec3) -> Noise {
    Noise { amplitude, frequency, offset, seed: Noise::SEED }
}

/// The `noise` crate's 3-D Perlin noise at `p`, for any finite `p`. Its noise repeats every 256
/// units (the hash masks each lattice coordinate with 0xff) but it panics where a lattice
/// coordinate leaves `isize`: wrapping first gives the same value and never panics.
pub(crate) fn perlin_periodic(perlin: &Perlin, p: [f64; 3]) -> f64 {
    perlin.get(p.map(|x| x.rem_euclid(256.0)))
}

impl Deformer for Noise {
    fn apply(&self, rest: &Mesh, out: &mut Vec<Vec3>) {
        let perlin = Perlin::new(self.seed);
        let normals = rest.vertex_normals();
        out.clear();
        rest.positions
            .par_iter()
            .zip(&normals)
            .map(|(&p, &n)| {
                let q = (self.frequency * p + self.offset).as_dvec3();
                p + (self.amplitude as f64 * perlin_periodic(&perlin, q.to_array())) as f32 * n
            })
            .collect_into_vec(out);
    }
}

/// A deformation as given on the command line, animated by a parameter `t`
/// (see [`Deformation::apply`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Deformation {
    /// `twist:DEG`: a [`Twist`] about the vertical (+y) axis through the centre of the rest
    /// mesh's bounding box, turning by `degrees` in total from the bottom to the top of the
    /// box (so it does not depend on the mesh's scale); the middle height stays in place.
    Twist {
        /// Total twist over the mesh height, degrees.
        degrees: f32,
    },
    /// `bump:x,y,z,radius,height`: a [`Bump`] (all in mesh units).
    Bump(Bump),
    /// `noise:amplitude,frequency`: a [`Noise`] displacement; amplitude in mesh units,
    /// frequency in noise cells per mesh unit.
    Noise {
        /// Peak displacement, mesh units.
        amplitude: f32,
        /// Noise cells per mesh unit.
        frequency: f32,
    },
}

impl Deformation {
    /// Writes the positions of `rest` deformed at animation parameter `t` into `out`.
    /// For twist and bump `t` scales the deformation (0 = rest pose, 1 = as specified); for
    /// noise it is the noise offset `(t, t, t)`, so the displacement pattern flows through the
    /// surface while its amplitude stays the same.
    pub fn apply(&self, rest: &Mesh, t: f32, out: &mut Vec<Vec3>) {
        match *self {
            Deformation::Twist { degrees } => {
                let (lo, hi) = rest.bounds();
                let h = hi.y - lo.y;
                let k = if h > 0.0 { degrees.to_radians() / h } else { 0.0 };
                twist(0.5 * (lo + hi), Vec3::Y, t * k).apply(rest, out)
            }
            Deformation::Bump(b) => Bump { height: t * b.height, ..b }.apply(rest, out),
            Deformation::Noise { amplitude, frequency } => {
                noise(amplitude, frequency, Vec3::splat(t)).apply(rest, out)
            }
        }
    }
}

/// A [`Deformation`] string that could not be parsed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "invalid deformation '{input}': {reason} (expected twist:DEGREES, bump:x,y,z,radius,height or noise:amplitude,frequency)"
)]
pub struct DeformationParseError {
    /// The string given.
    pub input: String,
    /// What is wrong with it.
    pub reason: String,
}

/// The largest twist accepted, degrees either way: three full turns. More folds the surface
/// through itself many times, which no translucency model can show and costs minutes to link.
pub const MAX_TWIST_DEGREES: f32 = 1080.0;
/// The largest length a deformation takes (bump centre, radius and height, noise amplitude),
/// mesh units.
pub const MAX_DEFORM_LENGTH: f32 = 1e6;
/// The highest noise frequency, per mesh unit.
pub const MAX_NOISE_FREQUENCY: f32 = 1e6;

impl FromStr for Deformation {
    type Err = DeformationParseError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = |reason: String| DeformationParseError { input: s.to_string(), reason };
        let (kind, args) =
            s.split_once(':').ok_or_else(|| err("missing ':' after the deformation kind".into()))?;
        let values = args
            .split(',')
            .map(|v| {
                let v = v.trim();
                match v.parse::<f32>() {
                    Ok(x) if x.is_finite() => Ok(x),
                    _ => Err(err(format!("'{v}' is not a finite number"))),
                }
            })
            .collect::<Result<Vec<f32>, _>>()?;
        let expect = |n: usize| {
            if values.len() == n {
                Ok(())
            } else {
                Err(err(format!(
                    "{kind} takes {n} number{}, got {}",
                    if n == 1 { "" } else { "s" },
                    values.len()
                )))
            }
        };
        let within = |what: &str, v: f32, range: std::ops::RangeInclusive<f32>| {
            crate::limits::check_range(what, v, &range).map_err(err)
        };
        match kind.trim().to_ascii_lowercase().as_str() {
            "twist" => {
                expect(1)?;
                within("twist angle (degrees)", values[0], -MAX_TWIST_DEGREES..=MAX_TWIST_DEGREES)?;
                Ok(Deformation::Twist { degrees: values[0] })
            }
            "bump" => {
                expect(5)?;
                if values[3] <= 0.0 {
                    return Err(err(format!("bump radius must be > 0, got {}", values[3])));
                }
                let names = ["bump centre", "bump centre", "bump centre", "bump radius", "bump height"];
                for (what, &v) in names.into_iter().zip(&values) {
                    within(what, v, -MAX_DEFORM_LENGTH..=MAX_DEFORM_LENGTH)?;
                }
                Ok(Deformation::Bump(bump(Vec3::new(values[0], values[1], values[2]), values[3], values[4])))
            }
            "noise" => {
                expect(2)?;
                if values[1] <= 0.0 {
                    return Err(err(format!("noise frequency must be > 0, got {}", values[1])));
                }
                within("noise amplitude", values[0], -MAX_DEFORM_LENGTH..=MAX_DEFORM_LENGTH)?;
                within("noise frequency", values[1], 0.0..=MAX_NOISE_FREQUENCY)?;
                Ok(Deformation::Noise { amplitude: values[0], frequency: values[1] })
            }
            other => Err(err(format!("unknown deformation kind '{other}'"))),
        }
    }
}

impl fmt::Display for Deformation {
    /// The string form accepted by [`FromStr`].
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Deformation::Twist { degrees } => write!(f, "twist:{degrees}"),
            Deformation::Bump(b) => {
                write!(f, "bump:{},{},{},{},{}", b.center.x, b.center.y, b.center.z, b.radius, b.height)
            }
            Deformation::Noise { amplitude, frequency } => write!(f, "noise:{amplitude},{frequency}"),
        }
    }
}
