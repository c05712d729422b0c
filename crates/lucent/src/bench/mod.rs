//! `lucent bench`: accuracy and speed measurements, printed as tables or JSON lines.

use crate::cli::{BenchArgs, BenchTarget};

mod formfactor;
mod htsm;

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    match args.what {
        BenchTarget::Formfactor => formfactor::run(args.json),
        BenchTarget::Htsm => htsm::run(args),
    }
}
