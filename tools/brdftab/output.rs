//! Output paths checked before any work: a render, a slice or an export that could not be
//! written (a wrong extension, a missing directory) is refused at once, not after the work.

use std::path::Path;

use brdftab::{Error, Result};

/// Refuses `path` (given as `flag`) unless it ends in one of `exts` (lowercase, no dot; any
/// case matches), its directory exists and it is absent or a regular file
/// ([`brdftab::store::check_output`]: a named pipe would block the write, a device be replaced).
pub fn check(path: impl AsRef<Path>, flag: &str, exts: &[&str]) -> Result<()> {
    let path = path.as_ref();
    brdftab::store::check_output(path)?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if !exts.iter().any(|e| ext.as_deref() == Some(*e)) {
        let list: Vec<String> = exts.iter().map(|e| format!(".{e}")).collect();
        return Err(Error::arg(
            flag,
            format!("{} must end in {}", path.display(), list.join(" or ")),
        ));
    }
    match path.parent() {
        // A file on the way (`lib.btdb/x.png`) is not a directory that does not exist.
        Some(dir) if !dir.as_os_str().is_empty() && !dir.is_dir() => Err(Error::arg(
            flag,
            match dir.exists() {
                true => format!("{}: {} is not a directory", path.display(), dir.display()),
                false => format!(
                    "{}: directory {} does not exist",
                    path.display(),
                    dir.display()
                ),
            },
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extension_and_directory() {
        assert!(check("a.PNG", "-o", &["png", "exr"]).is_ok());
        assert!(check("a.jpg", "-o", &["png", "exr"]).is_err());
        assert!(check("a", "-o", &["exr"]).is_err());
        assert!(check("/no/such/dir/a.exr", "-o", &["exr"]).is_err());
        let file = std::env::current_exe().unwrap();
        let e = check(file.join("a.exr"), "-o", &["exr"])
            .unwrap_err()
            .to_string();
        assert!(
            e.ends_with(&format!("{} is not a directory", file.display())),
            "{e}"
        );
        let e = check("a.png", "--exr", &["exr"]).unwrap_err().to_string();
        assert!(e.contains("--exr") && e.contains(".exr"), "{e}");
    }
}
