//! `lucent`: render translucent objects from the command line, benchmark the solvers, or open
//! the interactive viewer.

mod bench;
mod cli;
mod render;
mod render_htsm;
mod scene;
mod view;
mod viewer;

use clap::Parser;

fn main() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = cli::Cli::parse();
    let result = match cli.command.unwrap_or_default() {
        cli::Command::Render(args) => render::run(&args),
        cli::Command::Bench(args) => bench::run(&args),
        cli::Command::View(args) => view::run(&args),
    };
    if let Err(err) = result {
        // One line, with the chain of causes, and a non-zero exit: never a panic.
        eprintln!("lucent: error: {err:#}");
        std::process::exit(1);
    }
}
