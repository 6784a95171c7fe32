//! Checks and helpers for the files a command reads and writes (a low room: it knows paths,
//! not formats).
//!
//! - A SOURCE must be a regular file ([`require_regular`]): opening a FIFO blocks until a writer
//!   appears, and a directory, socket or device is never a material. The file type is read with
//!   `stat` (which does not open, and so cannot block) before any `open`; every reader of a
//!   file (tables, databases, MERL, RGL, spec files) asks first.
//! - An output must not be one of the command's inputs ([`refuse_input`]): `convert p.bsdf
//!   p.bsdf` would replace a measurement with its lossy resample. Files are compared by device
//!   and inode (a symlink, a hard link or another spelling of the same path is caught too).
//! - An output must be absent or a regular file ([`check_output`]): the rename of an atomic
//!   write would replace a FIFO or a device (as root, `/dev/null` itself) with a plain file.
//! - Outputs are written atomically through a temporary file beside them ([`temp_path`],
//!   [`write_atomic`]); an output directory that does not exist is reported with the user's
//!   path, and temporary files that killed writers left behind are removed by the next write.
//! - The rename that ends an atomic write ([`rename_over`]) is retried for up to 2 s on Windows
//!   while it is refused: Windows refuses to replace a file that any handle holds open, and
//!   every reader holds one for as long as its read takes.
//! - A database reached through a symbolic link is updated where the link points
//!   ([`resolve_links`]): the rename of an atomic write would otherwise replace the link with a
//!   file, and the database itself would not get the change.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result, excerpt};

/// Refuses `path` unless it is a regular file (after following symlinks). Every reader asks
/// this before its open, so a file that is missing is reported here, in the same words whatever
/// reads it (a table, a database, a MERL or RGL file, a spec, an `.npy`): an
/// [`Error::NotFound`] `PATH: no such file`; a path that cannot be looked up (a directory on
/// the way without permission) is an [`Error::Io`] naming it.
pub fn require_regular(path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    let m = match std::fs::metadata(path) {
        Ok(m) => m,
        Err(e) => return Err(read_error(path, e)),
    };
    if m.is_file() {
        return Ok(());
    }
    Err(Error::Unsupported(format!(
        "{}: not a regular file ({}); a SOURCE must be a file",
        excerpt(&path.display().to_string()),
        kind_name(&m.file_type())
    )))
}

/// The error of a file that could not be read: a missing file is an [`Error::NotFound`] `PATH:
/// no such file` (also a path through a file, `x.btdb/y`), anything else an [`Error::Io`]
/// naming the path.
pub fn read_error(path: &Path, e: std::io::Error) -> Error {
    use std::io::ErrorKind::{NotADirectory, NotFound};
    match e.kind() {
        NotFound | NotADirectory => Error::NotFound(format!(
            "{}: no such file",
            excerpt(&path.display().to_string())
        )),
        _ => Error::io(path, e),
    }
}

/// True when `path` is a regular file (after following symlinks); checked without opening it.
pub fn is_regular(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.is_file())
}

fn kind_name(t: &std::fs::FileType) -> &'static str {
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_socket() {
            return "a socket";
        }
        if t.is_block_device() || t.is_char_device() {
            return "a device";
        }
    }
    "not a file"
}

/// True when `a` and `b` name the same existing file (same device and inode on Unix; equal
/// canonical paths elsewhere).
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (a.canonicalize(), b.canonicalize()) {
            (Ok(x), Ok(y)) => x == y,
            _ => false,
        }
    }
}

/// The file a SOURCE reads, if it names one: the path of `FILE`, `DB#NAME`, a `.json`
/// spec file, a MERL or RGL file; `None` for inline JSON. A string the `DB#NAME` rule refuses
/// is taken as a plain path (the open reports the error).
pub fn source_file(source: &std::ffi::OsStr) -> Option<&Path> {
    if crate::store::name::is_inline(source) {
        return None;
    }
    Some(crate::store::name::parse_input_os("source", source).map_or(Path::new(source), |(p, _)| p))
}

/// Refuses to write `output` when it is the file one of `inputs` (SOURCEs or paths) reads:
/// the write would replace the input with a resample of itself.
pub fn refuse_input<S: AsRef<std::ffi::OsStr>>(output: &Path, inputs: &[S]) -> Result<()> {
    for input in inputs {
        let input = input.as_ref();
        if let Some(f) = source_file(input)
            && same_file(output, f)
        {
            return Err(Error::arg(
                "output",
                format!(
                    "{} is the input {}: writing it would replace the input while it is read \
                     (write to another file)",
                    output.display(),
                    excerpt(&input.to_string_lossy())
                ),
            ));
        }
    }
    Ok(())
}

/// An output path must name a file that is absent or a regular file (links followed): a write
/// goes to a new file renamed over `path`, which would replace a named pipe, a device (as
/// root, `/dev/null` itself) or a socket with a plain file, and a directory cannot be replaced.
/// Checked by every writer of the library (before its temporary file) and by tools before
/// long work.
///
/// # Errors
/// [`Error::Unsupported`] naming `path` and what it is.
pub fn check_output(path: &Path) -> Result<()> {
    if path.as_os_str().is_empty() {
        return Err(Error::Unsupported(
            "an empty output path: name the file to write".into(),
        ));
    }
    let kind = match std::fs::metadata(path) {
        Ok(m) if m.is_file() => return Ok(()),
        Ok(m) => kind_name(&m.file_type()),
        Err(_) if path.file_name().is_none() => "a directory",
        Err(_) => return Ok(()),
    };
    Err(Error::Unsupported(match kind {
        "a directory" => format!("{}: is a directory (name a file to write)", path.display()),
        _ => format!(
            "{}: is {kind}, not a regular file: an output written there would replace it or \
             block on it (name a regular file)",
            path.display()
        ),
    }))
}

/// The temporary file an atomic write of `path` goes through: `.NAME.tmp.PID.NANOS` in the
/// same directory (so the final rename stays on one file system).
///
/// Checks first that `path` may be written ([`check_output`]) and that the directory exists,
/// so those errors name the user's path and not the temporary file, and removes the temporary
/// files of `path` that earlier writers killed before they could clean up left behind (on
/// Linux: those whose PID is no longer running).
pub fn temp_path(path: &Path) -> Result<PathBuf> {
    check_output(path)?;
    let dir = parent(path);
    let fname = path
        .file_name()
        .ok_or_else(|| {
            Error::Unsupported(format!(
                "{}: names no file (an output must name a file)",
                path.display()
            ))
        })?
        .to_string_lossy()
        .into_owned();
    check_dir(path, &dir)?;
    let prefix = format!(".{fname}.tmp.");
    sweep_stale(&dir, &prefix);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    Ok(dir.join(format!("{prefix}{}.{nanos}", std::process::id())))
}

/// Writes `bytes` to `path` atomically (through [`temp_path`], renamed into place; the
/// temporary file is removed on failure). A `path` that is a symbolic link is written where it
/// points ([`resolve_links`]): the link stays a link, as a shell's `>` leaves it.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let path = &resolve_links(path)?;
    let tmp = temp_path(path)?;
    let r = std::fs::write(&tmp, bytes)
        .map_err(|e| Error::io(path, e))
        .and_then(|()| rename_over(&tmp, path).map_err(|e| Error::io(path, e)));
    if r.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    r
}

/// Renames the finished temporary file `tmp` over `path`, the last step of every atomic write.
/// On Windows `std::fs::rename` (`MoveFileExW`, then a POSIX-semantics rename that NTFS on
/// Windows 10 1607+ alone accepts) is refused while any handle holds `path` open — a reader of
/// the same database reading it into memory, an antivirus scan — so a refusal is retried for up
/// to [`RENAME_PATIENCE`] before it is the error (session 44: under Wine 8 every writer of
/// `tests/concurrency.rs` failed so while a reader kept opening the database). On Unix a rename
/// replaces an open file, and is done once.
pub(crate) fn rename_over(tmp: &Path, path: &Path) -> std::io::Result<()> {
    #[cfg(windows)]
    return retry_while_refused(RENAME_PATIENCE, || std::fs::rename(tmp, path));
    #[cfg(not(windows))]
    std::fs::rename(tmp, path)
}

/// How long [`rename_over`] retries a refused rename on Windows: readers hold a database's
/// handle for the time of one read (milliseconds for a database of a few MB); Go's `cmd/go`
/// (`robustio`) gives the same errors 2 s as well.
#[cfg_attr(not(windows), allow(dead_code))]
pub(crate) const RENAME_PATIENCE: std::time::Duration = std::time::Duration::from_secs(2);

/// Runs `op` until it succeeds, fails otherwise than refused (`PermissionDenied`: Windows'
/// `ERROR_ACCESS_DENIED`; or `ERROR_SHARING_VIOLATION`), or `patience` has passed since its
/// first try (then with its last error), sleeping 1, 2, 4, ... ms (at most 50 ms) between
/// tries.
#[cfg_attr(not(windows), allow(dead_code))] // used on Windows; tested everywhere
fn retry_while_refused(
    patience: std::time::Duration,
    mut op: impl FnMut() -> std::io::Result<()>,
) -> std::io::Result<()> {
    const ERROR_SHARING_VIOLATION: i32 = 32;
    let start = std::time::Instant::now();
    let mut wait = std::time::Duration::from_millis(1);
    loop {
        match op() {
            Err(e)
                if (e.kind() == std::io::ErrorKind::PermissionDenied
                    || (cfg!(windows) && e.raw_os_error() == Some(ERROR_SHARING_VIOLATION)))
                    && start.elapsed() < patience =>
            {
                std::thread::sleep(wait);
                wait = (wait * 2).min(std::time::Duration::from_millis(50));
            }
            r => return r,
        }
    }
}

/// The file a change of `path` must replace: `path`, or where it is a symbolic link the file
/// it points to (followed link by link, relative targets from the link's directory; the target
/// need not exist yet). A database updated through a link then stays the one file, and its
/// writers, whichever name they use, take one lock; every other output written through a link
/// (a table file, a `.bsdf`, a MERL file, a raw table, an `.npy`) replaces the file, not the
/// link.
///
/// # Errors
/// A link that cannot be read, or a chain of more than 40 links ([`Error::Io`] naming `path`).
pub fn resolve_links(path: &Path) -> Result<PathBuf> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&p).map_err(|e| Error::io(&p, e))?;
                p = if target.is_absolute() {
                    target
                } else {
                    parent(&p).join(target)
                };
            }
            _ => return Ok(p),
        }
    }
    Err(Error::io(
        path,
        std::io::Error::other("more than 40 symbolic links"),
    ))
}

/// An output `path` that can be written: [`check_output`], and its directory exists
/// ([`check_dir`]). What a database's writers check before any work (and before a lock file
/// is made beside it).
pub fn check_writable(path: &Path) -> Result<()> {
    check_output(path)?;
    check_dir(path, &parent(path))
}

/// An output's directory must exist (checked up front: the error then names `path`).
pub fn check_dir(path: &Path, dir: &Path) -> Result<()> {
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => Err(Error::Unsupported(format!(
            "{}: {} is not a directory",
            path.display(),
            dir.display()
        ))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(Error::NotFound(format!(
            "{}: directory {} does not exist",
            path.display(),
            dir.display()
        ))),
        Err(e) => Err(Error::io(path, e)),
    }
}

/// Removes `dir/PREFIX<pid>.*` files whose writer process is gone (Linux, where `/proc` tells;
/// elsewhere nothing is removed). Best effort: errors are ignored.
fn sweep_stale(dir: &Path, prefix: &str) {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(rest) = name.to_str().and_then(|n| n.strip_prefix(prefix)) else {
            continue;
        };
        let Some(pid) = rest.split('.').next().and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        let is_file = e.file_type().is_ok_and(|t| t.is_file());
        if is_file && pid != std::process::id() && !proc.join(pid.to_string()).exists() {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

fn parent(p: &Path) -> PathBuf {
    match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_refused_rename_is_retried_until_it_succeeds_or_the_patience_runs_out() {
        use std::io::{Error, ErrorKind};
        use std::time::{Duration, Instant};
        let mut tries = 0;
        let r = super::retry_while_refused(Duration::from_secs(2), || {
            tries += 1;
            match tries {
                1..=3 => Err(Error::from(ErrorKind::PermissionDenied)),
                _ => Ok(()),
            }
        });
        assert_eq!((r.is_ok(), tries), (true, 4));
        // Refused for ever: the last refusal, once the patience has passed (and not long after:
        // the last sleep is at most 50 ms).
        let (start, patience) = (Instant::now(), Duration::from_millis(100));
        tries = 0;
        let r = super::retry_while_refused(patience, || {
            tries += 1;
            Err(Error::from(ErrorKind::PermissionDenied))
        });
        let took = start.elapsed();
        assert_eq!(r.unwrap_err().kind(), ErrorKind::PermissionDenied);
        assert!(
            took >= patience && took < Duration::from_secs(2),
            "{took:?}"
        );
        assert!(tries > 1);
        // Any other error is returned at once.
        tries = 0;
        let r = super::retry_while_refused(Duration::from_secs(2), || {
            tries += 1;
            Err(Error::from(ErrorKind::NotFound))
        });
        assert_eq!((r.unwrap_err().kind(), tries), (ErrorKind::NotFound, 1));
    }

    use super::*;

    #[test]
    fn outputs_must_be_absent_or_regular_files() {
        let d = std::env::temp_dir().join(format!("brdftab-out-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let f = d.join("f");
        assert!(check_output(&f).is_ok()); // absent
        std::fs::write(&f, b"x").unwrap();
        assert!(check_output(&f).is_ok());
        #[allow(unused_mut)] // a device only on Unix
        let mut refused = vec![d.as_path(), Path::new("")];
        #[cfg(unix)]
        refused.push(Path::new("/dev/null"));
        for p in refused {
            let e = check_output(p).unwrap_err().to_string();
            assert!(
                e.contains("not a regular file") || e.contains("directory") || e.contains("empty"),
                "{e}"
            );
        }
        #[cfg(unix)]
        fifo_outputs_stay_fifos(&d);
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Every atomic writer goes through `temp_path`: a FIFO stays one.
    #[cfg(unix)]
    fn fifo_outputs_stay_fifos(d: &Path) {
        let fifo = d.join("pipe");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = write_atomic(&fifo, b"x").unwrap_err().to_string();
        assert!(e.contains("is a FIFO, not a regular file"), "{e}");
        use std::os::unix::fs::FileTypeExt;
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    }

    #[test]
    fn directories_are_refused_and_missing_files_are_not_found() {
        let d = std::env::temp_dir();
        let e = require_regular(&d).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
        let missing = d.join("brdftab-no-such-file.btdb");
        let e = require_regular(&missing).unwrap_err();
        assert!(matches!(e, Error::NotFound(_)), "{e}");
        assert_eq!(
            e.to_string(),
            format!("not found: {}: no such file", missing.display())
        );
    }

    #[cfg(unix)]
    #[test]
    fn links_resolve_to_their_target_and_loops_are_an_error() {
        use std::os::unix::fs::symlink;
        let d = crate::testkit::TempDir::new("links");
        let a = d.join("a.btdb");
        assert_eq!(
            resolve_links(&a).unwrap(),
            a,
            "a path that does not exist is itself"
        );
        std::fs::create_dir(d.join("sub")).unwrap();
        symlink("../a.btdb", d.join("sub/l1")).unwrap(); // relative to the link's directory
        symlink(d.join("sub/l1"), d.join("l2")).unwrap();
        assert_eq!(
            resolve_links(&d.join("l2")).unwrap(),
            d.join("sub/../a.btdb")
        );
        symlink("loop", d.join("loop")).unwrap();
        assert!(resolve_links(&d.join("loop")).is_err());
    }

    #[test]
    fn the_same_file_under_two_names_is_caught() {
        let d = crate::testkit::TempDir::new("paths");
        let a = d.join("a.btdb");
        std::fs::write(&a, b"x").unwrap();
        let other = d.path().join(".").join("a.btdb");
        assert!(same_file(&a, &other));
        let src = format!("{}#t", other.display());
        assert!(refuse_input(&a, &[&src]).is_err());
        assert!(refuse_input(&d.join("b.btdb"), &[&src]).is_ok());
        assert!(refuse_input(&a, &[r#"{"model": "lambert"}"#]).is_ok());
    }
}
