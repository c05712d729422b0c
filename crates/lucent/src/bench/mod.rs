//! `lucent bench`: accuracy and speed measurements, printed as tables or JSON lines.

use crate::cli::{BenchArgs, BenchTarget};

mod albedo;
mod cpu_time;
mod energy;
mod formfactor;
mod htsm;
mod interactive;
mod light_paths;
mod solver;
mod solver_locality;
mod solver_real;

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    match args.what {
        BenchTarget::Albedo => albedo::run(args.json),
        BenchTarget::Energy => energy::run(args),
        BenchTarget::Formfactor => formfactor::run(args.json),
        BenchTarget::Htsm => htsm::run(args),
        BenchTarget::Interactive => interactive::run(args.json),
        BenchTarget::Solver if args.real => {
            if args.sweep || args.table5 {
                anyhow::bail!("--real takes neither --sweep nor --table5");
            }
            if std::env::var_os("LUCENT_BENCH_CENSUS").is_some() {
                return solver_real::census(args.json, args.oracle());
            }
            solver_real::run(args.json, args.oracle())
        }
        BenchTarget::Solver if args.locality => solver_locality::run(args.json),
        BenchTarget::Solver => solver::run(args.json, args.sweep, args.table5, args.oracle()),
    }
}
