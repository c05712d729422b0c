//! `lucent bench`: accuracy and speed measurements, printed as tables or JSON lines.

use crate::cli::{BenchArgs, BenchTarget};

mod htsm;

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    match args.what {
        BenchTarget::Formfactor => anyhow::bail!("bench formfactor: not implemented yet"),
        BenchTarget::Htsm => htsm::run(args),
    }
}
