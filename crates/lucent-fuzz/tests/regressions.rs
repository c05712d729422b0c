//! Every seed loads, every input that ever crashed a loader is replayed (it must now give a
//! clean result, accepted or refused), and a short fuzz run of every target finds nothing.

use lucent_fuzz::targets::{TARGETS, target};
use std::path::Path;

#[test]
fn every_seed_loads() {
    for t in TARGETS {
        for (k, seed) in (t.seeds)().iter().enumerate() {
            let outcome = lucent_fuzz::run_one(t, seed)
                .unwrap_or_else(|c| panic!("{} seed {k}: {}", t.name, c.message));
            assert!(outcome.is_ok(), "{} seed {k} is refused: {:?}", t.name, outcome);
        }
    }
}

#[test]
fn regression_inputs_give_clean_results() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions");
    let mut replayed = 0;
    for dir in std::fs::read_dir(&root).expect("regressions folder").flatten() {
        let name = dir.file_name().to_string_lossy().to_string();
        let t = target(&name).unwrap_or_else(|| panic!("regressions/{name}: no such target"));
        for file in std::fs::read_dir(dir.path()).expect("target folder").flatten() {
            let input = std::fs::read(file.path()).expect("read regression input");
            if let Err(c) = lucent_fuzz::run_one(t, &input) {
                panic!("{}: {}", file.path().display(), c.message);
            }
            replayed += 1;
        }
    }
    assert!(replayed > 0, "no regression inputs found under {}", root.display());
}

/// The CI smoke run: the fuzzer binary itself, with its allocation cap and watchdog, a few
/// thousand inputs per target.
#[test]
fn short_fuzz_run_finds_nothing() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_lucent-fuzz"))
        .args(["--runs", "4000", "--seed", "2024", "--crashes"])
        .arg(std::env::temp_dir().join("lucent-fuzz-smoke"))
        .output()
        .expect("run lucent-fuzz");
    let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}");
    for t in TARGETS {
        assert!(text.lines().any(|l| l.starts_with(t.name)), "{} did not run:\n{text}", t.name);
    }
}

/// Prints what each regression input gives (`--nocapture` to read them).
#[test]
fn regression_outcomes_are_one_line() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions");
    for dir in std::fs::read_dir(&root).expect("regressions folder").flatten() {
        let t = target(&dir.file_name().to_string_lossy()).expect("target");
        for file in std::fs::read_dir(dir.path()).expect("target folder").flatten() {
            let input = std::fs::read(file.path()).expect("read");
            let outcome = lucent_fuzz::run_one(t, &input).expect("no panic");
            let text = match &outcome {
                Ok(s) | Err(s) => s,
            };
            println!("{}/{}: {outcome:?}", t.name, file.file_name().to_string_lossy());
            assert!(!text.contains('\n'), "{}: {text}", file.path().display());
        }
    }
}
