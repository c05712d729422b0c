//! `lucent`: render translucent objects from the command line, benchmark the solvers, or open
//! the interactive viewer.

mod bench;
mod cli;
mod progress;
mod render;
mod view;
mod viewer;

use clap::Parser;
// Shared with the fuzz harness through the library target.
use lucent::{ranges, scene};

/// Stack of the command's thread and of rayon's workers, bytes.
pub(crate) const STACK_BYTES: usize = 512 << 20;

fn main() {
    return_large_buffers_to_the_os();
    quiet_mesa_without_runtime_dir();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = cli::Cli::try_parse().unwrap_or_else(|e| exit_on_usage_error(e));
    // The hierarchy's traversals recurse once per level, and face clustering of scanned meshes
    // can nest thousands of levels deep (3,240 on the 11K Stanford dragon): give the worker
    // threads and the command's own thread room (only what is touched is committed).
    let _ = rayon::ThreadPoolBuilder::new().stack_size(STACK_BYTES).build_global();
    // The viewer's event loop must stay on the main thread (winit); its solves run on a worker.
    let result = match cli.command.unwrap_or_default() {
        cli::Command::View(args) => view::run(&args),
        command => {
            let worker = std::thread::Builder::new().stack_size(STACK_BYTES).spawn(move || match command {
                cli::Command::Render(args) => render::run(&args),
                cli::Command::Bench(args) => bench::run(&args),
                cli::Command::View(args) => view::run(&args),
            });
            match worker.map(|w| w.join()) {
                Ok(Ok(result)) => result,
                Ok(Err(panic)) => std::panic::resume_unwind(panic),
                Err(e) => Err(anyhow::anyhow!("cannot start the command's thread: {e}")),
            }
        }
    };
    if let Err(err) = result {
        // One line, with the chain of causes, and a non-zero exit: never a panic.
        eprintln!("lucent: error: {err:#}");
        std::process::exit(1);
    }
}

/// `--help` and `--version` print in full; a usage error prints one line (clap's first, which
/// names the flag, the value and the reason) and exits with status 2.
fn exit_on_usage_error(e: clap::Error) -> ! {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion)
        || e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    {
        e.exit();
    }
    // clap's message, without its usage block and hint, on one line.
    let text = e.render().to_string();
    let message: Vec<&str> = text
        .lines()
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("tip:"))
        .collect();
    eprintln!("lucent: {} (see lucent --help)", message.join(" "));
    std::process::exit(2);
}

/// Mesa's software Vulkan driver prints "error: XDG_RUNTIME_DIR is invalid or not set" on a
/// headless machine (a server, CI, a container), where rendering to a file works all the same.
/// Where the variable is unset, point it at a private directory so a first run does not look
/// broken.
fn quiet_mesa_without_runtime_dir() {
    #[cfg(unix)]
    if std::env::var_os("XDG_RUNTIME_DIR").is_none_or(|v| v.is_empty()) {
        use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
        let dir = std::env::temp_dir().join("lucent-runtime");
        let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
        // Only a directory of ours with owner-only access (what Mesa checks for).
        let ours = std::fs::metadata(&dir).is_ok_and(|m| {
            m.is_dir()
                && m.permissions().mode() & 0o077 == 0
                && std::fs::metadata("/proc/self").is_ok_and(|s| s.uid() == m.uid())
        });
        if ours {
            // SAFETY: first thing in `main`, before any thread is spawned.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}

/// glibc raises its mmap threshold (up to 32 MiB) each time a large mapped block is freed, so
/// the link traversal's growing buffers, once freed, end up inside the heap, which is not
/// returned to the system and add to the peak of every later solve. Holding the threshold at
/// its initial 128 KiB keeps large buffers mapped, so freeing them returns the memory.
fn return_large_buffers_to_the_os() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // glibc's `M_MMAP_THRESHOLD`.
        const M_MMAP_THRESHOLD: i32 = -3;
        unsafe extern "C" {
            fn mallopt(param: i32, value: i32) -> i32;
        }
        // SAFETY: `mallopt` only sets an allocator parameter; called before any thread starts.
        unsafe {
            mallopt(M_MMAP_THRESHOLD, 128 << 10);
        }
    }
}
