//! Where a frame's time goes, stage by stage: one struct that the session fills for its CPU
//! stages and a front end completes with its raster and write, printed the same way by
//! `lucent render --frames`, the viewer and `lucent bench interactive`.

/// Wall-clock times of one frame's stages, milliseconds (0 for a stage that did not run).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Timings {
    /// Irradiance at the faces: lights with their shadow rays, environment, the shadow BVH's
    /// refit and, on a new mesh's first hierarchical solve, the solver's making (its
    /// hierarchy's build), which runs beside the irradiance and the body.
    pub irradiance_ms: f64,
    /// The body's thickness rays under the faces: the finite-body gain and the exit chord's
    /// per-vertex means (`session/body.rs`).
    pub body_ms: f64,
    /// Profile tables, link creation, refinement or incremental update.
    pub link_ms: f64,
    /// Pulling irradiance up the hierarchy.
    pub pull_ms: f64,
    /// Gathering along the links (the whole O(N²) sum for the exact solver).
    pub gather_ms: f64,
    /// Pushing `B` down to the leaves, the entry face's local light and the per-vertex average.
    pub push_ms: f64,
    /// Bounces between parts: their rays and solves ([`crate::irradiance::interreflection`]).
    pub bounces_ms: f64,
    /// The view terms, what depends on the eye: the body's chord factor
    /// (`shading::exit_chord`) and single scattering along the view ray
    /// (`shading::single_scattering`), or with the split view terms
    /// (`shading::view_basis`) its eye-independent part where the solve changed it, and the
    /// closed forms per eye.
    pub single_scattering_ms: f64,
    /// What the solve spent outside the stages above (its wall clock less their sum: the
    /// hierarchical solve's own bookkeeping, copies of the result), so that the stages add
    /// up to the wall clock.
    pub other_ms: f64,
    /// The GPU raster: upload, draw, tone map and read-back (set by the front end that draws).
    pub raster_ms: f64,
    /// Writing the image (set by the front end that writes one).
    pub write_ms: f64,
}

impl Timings {
    /// The solve proper: pull, gather and push.
    pub fn solve_ms(&self) -> f64 {
        self.pull_ms + self.gather_ms + self.push_ms
    }

    /// Every stage's time, in the order light flows, with the names every front end prints.
    pub fn stages(&self) -> [(&'static str, f64); 9] {
        [
            ("irradiance", self.irradiance_ms),
            ("body", self.body_ms),
            ("link", self.link_ms),
            ("solve", self.solve_ms()),
            ("bounces", self.bounces_ms),
            ("view", self.single_scattering_ms),
            ("other", self.other_ms),
            ("raster", self.raster_ms),
            ("write", self.write_ms),
        ]
    }

    /// Sum of the stages, milliseconds.
    pub fn total_ms(&self) -> f64 {
        self.stages().iter().map(|(_, ms)| ms).sum()
    }

    /// Sum of the CPU stages (all but the raster and the write), milliseconds.
    pub fn cpu_ms(&self) -> f64 {
        self.total_ms() - self.raster_ms - self.write_ms
    }

    /// `irradiance 1.2 ms, body 0.0 ms, ..., total 9.9 ms`: every stage, for one-line reports.
    pub fn line(&self) -> String {
        let stages: Vec<String> = self.stages().iter().map(|(n, ms)| format!("{n} {ms:.1} ms")).collect();
        format!("{}, total {:.1} ms", stages.join(", "), self.total_ms())
    }

    /// The median of each stage over `frames` (each stage's own median; 0 for none).
    pub fn median(frames: &[Timings]) -> Timings {
        let m = |f: fn(&Timings) -> f64| {
            let mut v: Vec<f64> = frames.iter().map(f).collect();
            v.sort_by(f64::total_cmp);
            match v.len() {
                0 => 0.0,
                n if n % 2 == 1 => v[n / 2],
                n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
            }
        };
        Timings {
            irradiance_ms: m(|t| t.irradiance_ms),
            body_ms: m(|t| t.body_ms),
            link_ms: m(|t| t.link_ms),
            pull_ms: m(|t| t.pull_ms),
            gather_ms: m(|t| t.gather_ms),
            push_ms: m(|t| t.push_ms),
            bounces_ms: m(|t| t.bounces_ms),
            single_scattering_ms: m(|t| t.single_scattering_ms),
            other_ms: m(|t| t.other_ms),
            raster_ms: m(|t| t.raster_ms),
            write_ms: m(|t| t.write_ms),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every stage is in the line and the total, and the median is taken stage by stage.
    #[test]
    fn every_stage_counts_and_medians_are_per_stage() {
        let t = Timings {
            irradiance_ms: 1.0,
            body_ms: 2.0,
            link_ms: 3.0,
            pull_ms: 0.5,
            gather_ms: 1.0,
            push_ms: 0.5,
            bounces_ms: 5.0,
            single_scattering_ms: 6.0,
            other_ms: 0.5,
            raster_ms: 7.0,
            write_ms: 8.0,
        };
        assert_eq!(t.total_ms(), 34.5);
        assert_eq!(t.cpu_ms(), 19.5);
        let line = t.line();
        for name in [
            "irradiance 1.0",
            "body 2.0",
            "link 3.0",
            "solve 2.0",
            "bounces 5.0",
            "view 6.0",
            "other 0.5",
            "raster 7.0",
            "write 8.0",
            "total 34.5",
        ] {
            assert!(line.contains(name), "{name} missing from {line}");
        }
        let slow = Timings { body_ms: 10.0, write_ms: 0.0, ..t };
        let m = Timings::median(&[t, slow, t]);
        assert_eq!((m.body_ms, m.write_ms), (2.0, 8.0));
        assert_eq!(Timings::median(&[t, slow]).body_ms, 6.0);
        assert_eq!(Timings::median(&[]), Timings::default());
    }
}
