//! # lucent-fuzz
//!
//! A mutation fuzzer for every loader lucent exposes to files (OBJ, PLY ASCII and binary, OFF,
//! glTF, GLB, Radiance HDR, OpenEXR, TOML scene, LVOL and raw volumes), on the stable toolchain
//! with no external tool. The binary adds what a fuzzer needs around the loop of this library:
//! a cap on every allocation (a header that makes a loader ask for gigabytes is a finding, not
//! an out-of-memory kill) and a watchdog that reports an input running past a time limit.
//!
//! Without compiler coverage, the corpus grows by a cheap proxy: an input joins it when its
//! outcome (the loader's error message with digits masked, or what loaded) was not seen before,
//! so mutation reaches deeper into each format than from the seeds alone.

pub mod mutate;
pub mod targets;

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use std::collections::HashSet;
use targets::Target;

/// Largest corpus kept per target and thread.
const MAX_CORPUS: usize = 512;

/// What one worker did.
#[derive(Debug, Default, Clone, Copy)]
pub struct Stats {
    /// Inputs run.
    pub executions: u64,
    /// Inputs the loader accepted.
    pub accepted: u64,
    /// Distinct outcomes seen (the corpus heuristic's features).
    pub outcomes: usize,
}

/// A panic that escaped a loader: the input and the message.
#[derive(Debug)]
pub struct Crash {
    pub input: Vec<u8>,
    pub message: String,
}

/// Runs `target` on one input and turns an escaping panic into a [`Crash`]. Loaders catch their
/// dependencies' panics themselves; anything reaching here is a bug in lucent.
pub fn run_one(target: &Target, input: &[u8]) -> Result<Result<String, String>, Crash> {
    std::panic::catch_unwind(|| (target.run)(input)).map_err(|payload| Crash {
        input: input.to_vec(),
        message: lucent_core::limits::panic_message(payload.as_ref()),
    })
}

/// The outcome with digits masked, so that "vertex 12" and "vertex 13" count as one.
fn outcome_key(outcome: &Result<String, String>) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    outcome.is_ok().hash(&mut h);
    let text = match outcome {
        Ok(s) | Err(s) => s,
    };
    text.bytes().filter(|b| !b.is_ascii_digit()).for_each(|b| b.hash(&mut h));
    h.finish()
}

/// Fuzzes `target` for `executions` inputs from `seed`. `before_each` is called with every input
/// before it runs (the binary records it for its watchdog and allocation cap).
pub fn fuzz(
    target: &Target,
    executions: u64,
    seed: u64,
    mut before_each: impl FnMut(&[u8]),
) -> Result<Stats, Crash> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut corpus = (target.seeds)();
    let mut seen = HashSet::new();
    let mut stats = Stats::default();
    let mut input = Vec::new();
    for _ in 0..executions {
        let base = &corpus[rng.random_range(0..corpus.len())];
        let other = &corpus[rng.random_range(0..corpus.len())];
        input.clear();
        input.extend_from_slice(base);
        mutate::mutate(&mut input, other, &mut rng);
        before_each(&input);
        let outcome = run_one(target, &input)?;
        stats.executions += 1;
        stats.accepted += u64::from(outcome.is_ok());
        if seen.insert(outcome_key(&outcome)) && corpus.len() < MAX_CORPUS {
            corpus.push(input.clone());
        }
    }
    stats.outcomes = seen.len();
    Ok(stats)
}
