//! What lucent accepts from files, and the memory it will spend on them.
//!
//! Input plumbing, not a paper section. Every loader (meshes, environment maps, volumes, scene
//! files) reads through [`read_input`], which opens only regular files and refuses any larger
//! than [`MAX_FILE_BYTES`] *before* reading, so a device (`/dev/zero`), a FIFO or a huge file
//! never hangs or exhausts memory. Sizes a file *declares* (an image's width and height, a
//! volume's dimensions, a glTF accessor's count) are checked against [`MAX_DECODED_BYTES`] and
//! against the file's real length ([`plausible_expansion`]) before anything is allocated.
//!
//! The stated budget: loading one input allocates at most about `MAX_DECODED_BYTES` plus a
//! small multiple of the file's size. The fuzz harness (`crates/lucent-fuzz`) enforces a cap on
//! every single allocation while it mutates inputs.

use std::io::Read;
use std::path::Path;

/// The largest input file lucent reads: 2 GiB. The 871K-triangle Stanford dragon is 30 MB as
/// binary PLY and 60 MB as OBJ; a 2048^3 `u8` volume is 8 GiB and is refused.
pub const MAX_FILE_BYTES: u64 = 2 << 30;

/// The most a loader may allocate for one decoded array declared by a file's header: 1 GiB
/// (an 8192 x 4096 float RGB environment map is 400 MB; a 640^3 float volume 1 GB).
pub const MAX_DECODED_BYTES: u64 = 1 << 30;

/// How many times larger than its file a decoded array may be. Compressed formats (EXR's ZIP
/// and RLE, Radiance RGBE run-lengths) reach a few hundred on flat images; a header claiming
/// more than this is corrupt, whatever the budget says.
pub const MAX_EXPANSION: u64 = 4096;

/// Reads a whole input file: a regular file of at most `MAX_FILE_BYTES` (symbolic links are
/// followed). The error is the reason alone (the caller names the file).
pub fn read_input(path: &Path) -> Result<Vec<u8>, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot open: {e}"))?;
    let meta = file.metadata().map_err(|e| format!("cannot read: {e}"))?;
    if !meta.is_file() {
        return Err("not a regular file (devices, pipes and directories are not read)".into());
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(format!(
            "file is {} bytes, more than the {} bytes lucent reads",
            meta.len(),
            MAX_FILE_BYTES
        ));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // `take` guards against a file that grows while it is read.
    file.take(MAX_FILE_BYTES + 1).read_to_end(&mut bytes).map_err(|e| format!("cannot read: {e}"))?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(format!("file grew past {MAX_FILE_BYTES} bytes while it was read"));
    }
    Ok(bytes)
}

/// Checks that `what`, declared by a file of `file_bytes` bytes to decode into `decoded_bytes`,
/// fits the budget and is plausible for the file's size. The error names `what` and both sizes.
pub fn plausible_expansion(what: &str, decoded_bytes: u128, file_bytes: usize) -> Result<(), String> {
    if decoded_bytes > MAX_DECODED_BYTES as u128 {
        return Err(format!(
            "{what} would take {decoded_bytes} bytes, more than the {MAX_DECODED_BYTES}-byte budget"
        ));
    }
    // A small floor keeps tiny, legal, highly compressed images (a 4 x 2 constant map) readable.
    let allowed = (file_bytes as u128).max(4096) * MAX_EXPANSION as u128;
    if decoded_bytes > allowed {
        return Err(format!(
            "{what} declares {decoded_bytes} bytes of data in a {file_bytes}-byte file: the header is corrupt"
        ));
    }
    Ok(())
}

/// `relative` as a path, if it is a plain relative path that stays inside its folder (no root,
/// drive letter, URI scheme or `..`); the error is the reason alone.
pub fn check_relative(relative: &str) -> Result<&Path, String> {
    let rel = Path::new(relative);
    let plain = !relative.is_empty()
        && !relative.contains([':', '\\'])
        && rel
            .components()
            .all(|c| matches!(c, std::path::Component::Normal(_) | std::path::Component::CurDir));
    if plain {
        Ok(rel)
    } else {
        Err(format!("'{relative}' is not a relative path inside the folder of the file that names it"))
    }
}

/// Resolves `relative`, a path a file names (a glTF buffer URI after %-decoding, a mesh or map
/// in a scene file), against `folder`, the naming file's own folder, and refuses anything that
/// would leave it: absolute paths, drive letters and URI schemes, `..`, and links that point
/// outside. The file must exist. The error is the reason alone.
pub fn resolve_inside(folder: &Path, relative: &str) -> Result<std::path::PathBuf, String> {
    let rel = check_relative(relative)?;
    let base = if folder.as_os_str().is_empty() { Path::new(".") } else { folder };
    let path = base.join(rel);
    let target = std::fs::canonicalize(&path).map_err(|e| format!("cannot open {}: {e}", path.display()))?;
    let root = std::fs::canonicalize(base).map_err(|e| format!("cannot resolve {}: {e}", base.display()))?;
    if !target.starts_with(&root) {
        return Err(format!("{} is a link that leads outside its folder", path.display()));
    }
    Ok(path)
}

/// Checks `value` (named `what` in the error, e.g. `--scale` or `twist angle (degrees)`) against
/// `range`; NaN is outside every range. The error is one line naming the value and the range.
pub fn check_range<T: PartialOrd + std::fmt::Display>(
    what: &str,
    value: T,
    range: &std::ops::RangeInclusive<T>,
) -> Result<T, String> {
    if range.contains(&value) {
        Ok(value)
    } else {
        Err(format!("{what} {value} is outside the accepted range {}..={}", range.start(), range.end()))
    }
}

/// The message a panic carried (`&str` or `String` payloads), else `"unknown"`.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown".into())
}

thread_local! {
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f` (a third-party decoder) and turns a panic into `Err(message)` without printing the
/// panic: a dependency's panic text must never reach the user, who gets the caller's one-line
/// error instead. The process-wide panic hook is wrapped once; panics elsewhere print as before.
pub fn catch_quietly<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(|q| q.get()) {
                previous(info);
            }
        }));
    });
    let was = QUIET.with(|q| q.replace(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET.with(|q| q.set(was));
    result.map_err(|payload| panic_message(payload.as_ref()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[cfg(unix)]
    fn devices_and_directories_are_refused_before_reading() {
        let e = read_input(Path::new("/dev/zero")).unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
        let e = read_input(Path::new("/")).unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
    }

    #[test]
    fn paths_must_stay_inside_their_folder() {
        let here = Path::new(env!("CARGO_MANIFEST_DIR"));
        assert!(resolve_inside(here, "Cargo.toml").is_ok());
        assert!(resolve_inside(here, "./src/lib.rs").is_ok());
        for bad in
            ["/etc/passwd", "../../../etc/passwd", "src/../../Cargo.toml", "C:\\x", "file:///etc/passwd", ""]
        {
            let e = resolve_inside(here, bad).unwrap_err();
            assert!(e.contains("relative path inside"), "{bad}: {e}");
        }
        assert!(resolve_inside(here, "missing.bin").unwrap_err().contains("cannot open"));
    }

    #[test]
    fn expansion_is_bounded_by_budget_and_file_size() {
        assert!(plausible_expansion("image", 4096 * 16, 100).is_ok());
        let e = plausible_expansion("image", 333 << 30, 800).unwrap_err();
        assert!(e.contains("budget"), "{e}");
        let e = plausible_expansion("image", 512 << 20, 800).unwrap_err();
        assert!(e.contains("corrupt"), "{e}");
        assert!(plausible_expansion("image", 512 << 20, 1 << 20).is_ok());
    }
}
