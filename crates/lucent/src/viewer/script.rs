//! Scripted runs (`--frames N --script "..." --screenshot PATH`) for tests and documentation.
//!
//! A script is a `;`-separated list of actions. Each action runs only once the worker has
//! delivered, and the window has drawn, the solution for the state before it, so every action
//! and screenshot sees a settled image. Actions start half-way through the `--frames` budget;
//! the final screenshot is taken after the last action settles and at least N frames ran.
//!
//! | action | meaning |
//! |---|---|
//! | `dent:x,y,z` | dent the surface at the vertex nearest to `(x,y,z)` (normalised mesh units) |
//! | `light:x,y,z` | move the first light to `(x,y,z)` |
//! | `twist:d` | twist about the vertical axis, `d` degrees from the bottom to the top (as `--deform twist:d`) |
//! | `material:name` | switch to a material preset |
//! | `scale:m` | set the model scale, metres |
//! | `camera:yaw,pitch,distance` | place the camera (degrees, degrees, and mesh units from the point looked at, which the normalised mesh's extent 1 makes model-independent; scene files give radii) |
//! | `exposure:k` | set the exposure multiplier |
//! | `clusters:x,y,z` | figure 6.9 view for the face nearest to `(x,y,z)` |
//! | `method:htsm` / `method:mertens` | switch the 3D view's method (HTSM: Shopf 2007) |
//! | `shot:path` | save a screenshot now |
//! | `albedo:r,g,b,mr,mg,mb` | material by slab albedo and mean free paths (mm), as the panel's "apply" |
//! | `save:path` | write the material (with scale, profile, exposure) to a new scene file; an existing file is an error, never overwritten |
//! | `animate:s` | for `s` seconds: noise deformation flowing, the first light orbiting (soak tests) |

use anyhow::{Context as _, bail};
use glam::Vec3;
use std::collections::VecDeque;
use std::path::PathBuf;

/// One scripted action (see the module table).
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Dent near a point.
    Dent(Vec3),
    /// Move the first light.
    Light(Vec3),
    /// Set the twist, degrees from the bottom of the mesh to its top.
    Twist(f32),
    /// Switch material preset.
    Material(String),
    /// Set the model scale (metres).
    Scale(f64),
    /// Place the camera: yaw and pitch in degrees, distance from the point looked at in mesh
    /// units (see [`super::framing::Framing::place`]).
    Camera(f32, f32, f32),
    /// Set the exposure.
    Exposure(f32),
    /// Figure 6.9 view for the face nearest a point.
    Clusters(Vec3),
    /// Switch the method: `true` for HTSM, `false` for the Mertens solve.
    Htsm(bool),
    /// Save a screenshot.
    Shot(PathBuf),
    /// Animate noise and the first light for this many seconds.
    Animate(f64),
    /// Material by colour and distance: slab albedo, then mean free paths in mm.
    Albedo([f32; 3], [f32; 3]),
    /// Save the material to this new scene file.
    Save(PathBuf),
}

/// Parses a script (see the module docs); the error names the bad action.
pub fn parse(script: &str) -> anyhow::Result<Vec<Action>> {
    script
        .split(';')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| parse_action(s).with_context(|| format!("--script action '{s}'")))
        .collect()
}

fn parse_action(s: &str) -> anyhow::Result<Action> {
    let (name, arg) = s.split_once(':').context("expected NAME:ARGUMENTS, e.g. dent:0,0.5,0")?;
    Ok(match name.trim() {
        "dent" => Action::Dent(vec3(arg)?),
        "light" => Action::Light(vec3(arg)?),
        "twist" => Action::Twist(number(arg)?),
        "material" => Action::Material(arg.trim().to_string()),
        "scale" => {
            let m: f64 = number(arg)?;
            if m <= 0.0 {
                bail!("the scale must be > 0 metres");
            }
            Action::Scale(m)
        }
        "camera" => {
            let [yaw, pitch, distance] = numbers::<3>(arg)?;
            if distance <= 0.0 {
                bail!("the camera distance must be > 0");
            }
            Action::Camera(yaw, pitch, distance)
        }
        "exposure" => Action::Exposure(number(arg)?),
        "clusters" => Action::Clusters(vec3(arg)?),
        "method" => match arg.trim().to_ascii_lowercase().as_str() {
            "htsm" => Action::Htsm(true),
            "mertens" | "homogeneous" => Action::Htsm(false),
            other => bail!("unknown method {other:?}: expected htsm or mertens"),
        },
        "shot" if !arg.trim().is_empty() => Action::Shot(PathBuf::from(arg.trim())),
        "albedo" => {
            let v = numbers::<6>(arg)?;
            Action::Albedo([v[0], v[1], v[2]], [v[3], v[4], v[5]])
        }
        "animate" => {
            let seconds: f64 = number(arg)?;
            if !(0.0..=86_400.0).contains(&seconds) {
                bail!("animate takes 0..=86400 seconds, got {seconds}");
            }
            Action::Animate(seconds)
        }
        "save" if !arg.trim().is_empty() => Action::Save(PathBuf::from(arg.trim())),
        "shot" | "save" => bail!("{} needs a file name", name.trim()),
        other => bail!(
            "unknown action '{other}' (known: dent, light, twist, material, scale, camera, \
             exposure, clusters, method, shot, albedo, save, animate)"
        ),
    })
}

fn number<T: std::str::FromStr>(s: &str) -> anyhow::Result<T> {
    s.trim().parse().map_err(|_| anyhow::anyhow!("'{}' is not a number", s.trim()))
}

fn numbers<const N: usize>(s: &str) -> anyhow::Result<[f32; N]> {
    let v: Vec<f32> = s.split(',').map(number).collect::<anyhow::Result<_>>()?;
    let n = v.len();
    let arr: [f32; N] =
        v.try_into().map_err(|_| anyhow::anyhow!("expected {N} comma-separated numbers, got {n}"))?;
    if arr.iter().any(|x| !x.is_finite()) {
        bail!("numbers must be finite");
    }
    Ok(arr)
}

fn vec3(s: &str) -> anyhow::Result<Vec3> {
    Ok(Vec3::from_array(numbers::<3>(s)?))
}

/// The scripted run's progress.
#[derive(Debug)]
pub struct Automation {
    /// Actions still to run.
    pub pending: VecDeque<Action>,
    /// Frames to run at least.
    pub min_frames: u64,
    /// Frames drawn so far.
    pub frame: u64,
    /// Final screenshot, if any.
    pub screenshot: Option<PathBuf>,
}

/// What the app should do this frame.
#[derive(Debug, PartialEq)]
pub enum Step {
    /// Keep drawing.
    Wait,
    /// Apply this action.
    Run(Action),
    /// Take the final screenshot (if any) and exit.
    Finish,
}

impl Automation {
    /// A run of at least `min_frames` frames performing `actions`.
    pub fn new(min_frames: u64, actions: Vec<Action>, screenshot: Option<PathBuf>) -> Self {
        Automation { pending: actions.into(), min_frames, frame: 0, screenshot }
    }

    /// Decides the next step after a frame was drawn; `settled` is true when the image shows
    /// the solution for the current state.
    pub fn step(&mut self, settled: bool) -> Step {
        self.frame += 1;
        if !settled || self.frame < self.min_frames / 2 {
            return Step::Wait;
        }
        match self.pending.pop_front() {
            Some(action) => Step::Run(action),
            None if self.frame >= self.min_frames => Step::Finish,
            None => Step::Wait,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_documented_example() {
        let a = parse("dent:0.1,0.2,0.3; light:0,1,-2;shot:a.png").unwrap();
        assert_eq!(parse("save: m.toml").unwrap(), vec![Action::Save("m.toml".into())]);
        assert!(parse("save:").is_err());
        assert_eq!(
            a,
            vec![
                Action::Dent(Vec3::new(0.1, 0.2, 0.3)),
                Action::Light(Vec3::new(0.0, 1.0, -2.0)),
                Action::Shot("a.png".into()),
            ]
        );
    }

    #[test]
    fn rejects_bad_actions_naming_them() {
        let e = format!("{:#}", parse("dent:1,2").unwrap_err());
        assert!(e.contains("dent:1,2") && e.contains("3 comma-separated"), "{e}");
        assert!(parse("warp:1").is_err());
        assert!(parse("scale:-1").is_err());
    }

    /// Actions wait for a settled image and for half the frame budget; the run finishes only
    /// after the last action settled and the budget is spent.
    #[test]
    fn sequencing() {
        let mut a = Automation::new(4, vec![Action::Twist(1.0)], None);
        assert_eq!(a.step(true), Step::Wait); // frame 1 < 2
        assert_eq!(a.step(false), Step::Wait); // not settled
        assert_eq!(a.step(true), Step::Run(Action::Twist(1.0))); // frame 3
        assert_eq!(a.step(false), Step::Wait);
        assert_eq!(a.step(true), Step::Finish); // frame 5 >= 4
    }
}
