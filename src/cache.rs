//! Baked tables kept on disk, keyed by what they were baked from.
//!
//! Why a module: a host that needs a table of a non-table SOURCE (the Mitsuba plugin's JIT
//! variants, a renderer that uploads tables to a device) would bake it on every scene load —
//! 0.7–1.1 s per RGL file. [`bake_cached`] bakes once per (source content, bake settings,
//! library version) and returns the file of the table; later loads open that file.
//!
//! - The key is an xxh3-128 of a tag of the bake's rules (changed when the same settings give
//!   another table), the library's version, the source's kind and content (the bytes
//!   of a file or database, the text of an inline spec) and the settings as JSON (`replace`
//!   and `name` left out: they do not change the table). Editing a file in place changes its
//!   key; a model spec is keyed by its text.
//! - The directory is [`default_dir`] unless given: `$BRDFTAB_CACHE_DIR`, else
//!   `$XDG_CACHE_HOME/brdftab`, else `$HOME/.cache/brdftab`.
//! - Concurrent loads are safe: a bake writes a temporary file and renames it into place
//!   (the library's atomic write), so a reader sees no file or a whole one; and it runs under
//!   a writer lock whose empty `.<key>.btdb.lock` file stays beside the table, so processes
//!   asking for the same key at once bake it once: the others wait and get the hit.
//! - A cached file whose structure no longer reads (emptied, truncated, its header or index
//!   damaged) is not a hit: it is baked again. One whose chunk fails its checksum when read
//!   (found only by decoding it) is re-baked by asking again with `refresh`.
//!
//! ```no_run
//! use brdftab::cache;
//! use brdftab::request::BakeSettings;
//! let hit = cache::bake_cached("paper_white_rgb.bsdf", &BakeSettings::default(), None, false)?;
//! let table = brdftab::open(&hit.path)?;
//! # Ok::<(), brdftab::Error>(())
//! ```

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use xxhash_rust::xxh3::Xxh3;

use crate::error::{Error, Result};
use crate::request::BakeSettings;
use crate::source::{self, SourceKind};

/// Where a table was found or put.
#[derive(Debug, Clone, PartialEq)]
pub struct Cached {
    /// The table file (`<dir>/<key>.btdb`).
    pub path: PathBuf,
    /// It was there already (no bake ran).
    pub hit: bool,
}

/// The cache directory used when none is given: `$BRDFTAB_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/brdftab`, else `$HOME/.cache/brdftab`.
///
/// # Errors
/// [`Error::InvalidArgument`] (field `cache_dir`) when none of the three is set.
pub fn default_dir() -> Result<PathBuf> {
    let var = |k: &str| {
        std::env::var_os(k)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    if let Some(d) = var("BRDFTAB_CACHE_DIR") {
        return Ok(d);
    }
    if let Some(d) = var("XDG_CACHE_HOME") {
        return Ok(d.join("brdftab"));
    }
    if let Some(h) = var("HOME") {
        return Ok(h.join(".cache").join("brdftab"));
    }
    Err(Error::arg(
        "cache_dir",
        "no cache directory: set BRDFTAB_CACHE_DIR (or XDG_CACHE_HOME or HOME)",
    ))
}

/// The cache key of baking `source` with `settings`: 32 hex digits.
///
/// # Errors
/// A source file that cannot be read ([`Error::Io`] naming it).
pub fn key(source: impl AsRef<OsStr>, settings: &BakeSettings) -> Result<String> {
    let source = source.as_ref();
    let mut h = Xxh3::new();
    let mut part = |b: &[u8]| {
        h.update(&(b.len() as u64).to_le_bytes());
        h.update(b);
    };
    // The tag names what a bake of given settings makes: it changes with that, so tables of
    // an older rule are not served (2: adaptive tables of models calibrated, session 20;
    // 3: a model's default bake checks the medium preset's albedo, session 23; 4: that
    // check's error over random pairs from mirror-mixture pairs, session 25; 5: the check also
    // judges the preset's error over random pairs, session 26).
    part(b"brdftab bake cache 5");
    part(env!("CARGO_PKG_VERSION").as_bytes());
    let kind = source::classify(source);
    part(kind.name().as_bytes());
    let inline = kind == SourceKind::Spec && crate::store::name::is_inline(source);
    if inline {
        match source.to_str() {
            Some(s) => part(s.trim().as_bytes()),
            None => part(source.as_encoded_bytes().trim_ascii()),
        }
    } else {
        let (file, name) = match kind {
            SourceKind::Table => crate::store::db::split_source(source)?,
            _ => (Path::new(source), None),
        };
        part(&content_hash(file)?.to_le_bytes());
        part(name.unwrap_or("").as_bytes());
    }
    let mut s = settings.clone();
    s.replace = false;
    s.name = None;
    let json = serde_json::to_string(&s).map_err(|e| Error::arg("settings", e.to_string()))?;
    part(json.as_bytes());
    Ok(format!("{:032x}", h.digest128()))
}

/// xxh3-128 of a file's bytes, read in blocks: no memory map, so another process truncating
/// the file meanwhile changes the hash instead of killing this one (SIGBUS), and on Windows
/// the file is never held in a way that keeps its writer from replacing it.
fn content_hash(path: &Path) -> Result<u128> {
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let meta = f.metadata().map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        return Err(Error::arg(
            "source",
            format!("{}: not a regular file", path.display()),
        ));
    }
    hash_reader(&mut f).map_err(|e| Error::io(path, e))
}

/// xxh3-128 of everything `r` yields, read [`HASH_BLOCK`] bytes at a time.
fn hash_reader(r: &mut impl std::io::Read) -> std::io::Result<u128> {
    let mut h = xxhash_rust::xxh3::Xxh3::new();
    let mut buf = vec![0u8; HASH_BLOCK];
    loop {
        match r.read(&mut buf) {
            Ok(0) => return Ok(h.digest128()),
            Ok(n) => h.update(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
}

/// The block [`content_hash`] reads (1 MiB: a 35 MB MERL file in ~35 reads from the page
/// cache, a few ms).
const HASH_BLOCK: usize = 1 << 20;

/// The table of `source` baked with `settings`, from the cache in `dir` (default:
/// [`default_dir`]) or baked into it now. `refresh` bakes again even when the file is there
/// (for a cached file that failed to open).
///
/// # Errors
/// No cache directory, a directory that cannot be created, and whatever the bake fails with.
pub fn bake_cached(
    source: impl AsRef<OsStr>,
    settings: &BakeSettings,
    dir: Option<&Path>,
    refresh: bool,
) -> Result<Cached> {
    bake_cached_with(source, settings, dir, refresh, &crate::progress::Silent)
}

/// [`bake_cached`], reporting the bake's stages to `progress` (which may stop it:
/// [`Progress::cancelled`](crate::progress::Progress::cancelled); the cache is then left
/// without the table).
pub fn bake_cached_with(
    source: impl AsRef<OsStr>,
    settings: &BakeSettings,
    dir: Option<&Path>,
    refresh: bool,
    progress: &dyn crate::progress::Progress,
) -> Result<Cached> {
    let dir = match dir {
        Some(d) => d.to_path_buf(),
        None => default_dir()?,
    };
    let source = source.as_ref();
    // Settings are checked before any file is read or written.
    settings.request(source)?;
    let path = dir.join(format!("{}.btdb", key(source, settings)?));
    if !refresh && intact(&path) {
        return Ok(Cached { path, hit: true });
    }
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    // One bake per key at a time: a process (or thread) that finds the bake under way waits
    // for it and is then a hit, rather than baking the same table beside it.
    let _lock = crate::store::db::lock_with(&path, progress)?;
    if !refresh && intact(&path) {
        return Ok(Cached { path, hit: true });
    }
    let mut s = settings.clone();
    s.replace = true;
    crate::request::bake(source, &path, &s, progress)?;
    Ok(Cached { path, hit: false })
}

/// Whether the cached table at `path` is there and its structure reads: superblock, table of
/// contents, one table's header and chunk index within the file (what opening it checks; the
/// chunks' checksums are checked when they are decoded).
fn intact(path: &Path) -> bool {
    path.is_file()
        && crate::store::Store::open(path)
            .and_then(|s| s.single())
            .is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::TempDir;

    const SPEC: &str = r#"{"model": "lambert", "kd": 0.5}"#;

    fn small() -> BakeSettings {
        BakeSettings {
            preset: Some("small".into()),
            ..BakeSettings::default()
        }
    }

    /// A reader that yields at most `step` bytes a call and is interrupted once.
    struct Trickle<'a> {
        data: &'a [u8],
        step: usize,
        interrupted: bool,
    }

    impl std::io::Read for Trickle<'_> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if !self.interrupted {
                self.interrupted = true;
                return Err(std::io::ErrorKind::Interrupted.into());
            }
            let n = self.step.min(buf.len()).min(self.data.len());
            buf[..n].copy_from_slice(&self.data[..n]);
            self.data = &self.data[n..];
            Ok(n)
        }
    }

    /// The block-wise hash is the one-shot xxh3-128 of the bytes (so keys of tables cached by
    /// earlier versions, which hashed a map of the file, stay the same) at every size around
    /// the block and however the reads fall.
    #[test]
    fn the_file_hash_is_the_one_shot_hash_of_its_bytes() {
        let mut rng = crate::rng::Pcg32::new(7);
        let d = TempDir::new("cache-hash");
        for n in [
            0,
            1,
            240,
            HASH_BLOCK - 1,
            HASH_BLOCK,
            HASH_BLOCK + 1,
            2 * HASH_BLOCK + 17,
        ] {
            let data: Vec<u8> = (0..n).map(|_| (rng.next_f64() * 256.0) as u8).collect();
            let want = xxhash_rust::xxh3::xxh3_128(&data);
            for step in [1 << 30, 4096, 1000] {
                let mut r = Trickle {
                    data: &data,
                    step,
                    interrupted: false,
                };
                assert_eq!(
                    hash_reader(&mut r).unwrap(),
                    want,
                    "{n} bytes, reads of {step}"
                );
            }
            let f = d.path().join(format!("{n}.bin"));
            std::fs::write(&f, &data).unwrap();
            assert_eq!(content_hash(&f).unwrap(), want, "{n} bytes from a file");
        }
    }

    #[test]
    fn the_key_follows_content_and_settings_not_names() {
        let d = TempDir::new("cache-key");
        let f = d.path().join("m.json");
        std::fs::write(&f, SPEC).unwrap();
        let fs = f.to_string_lossy().to_string();
        let k = key(&fs, &small()).unwrap();
        assert_eq!(k.len(), 32);
        assert_eq!(k, key(&fs, &small()).unwrap());
        let named = BakeSettings {
            name: Some("x".into()),
            replace: true,
            ..small()
        };
        assert_eq!(
            k,
            key(&fs, &named).unwrap(),
            "name and replace do not change a table"
        );
        assert_ne!(k, key(&fs, &BakeSettings::default()).unwrap());
        std::fs::write(&f, r#"{"model": "lambert", "kd": 0.6}"#).unwrap();
        assert_ne!(k, key(&fs, &small()).unwrap(), "edited in place: a new key");
        assert_ne!(key(SPEC, &small()).unwrap(), key(&fs, &small()).unwrap());
        assert!(key(d.path().join("nope.bsdf"), &small()).is_err());
    }

    #[test]
    fn a_cached_file_whose_structure_does_not_read_is_baked_again() {
        // It was a hit, which a host then failed to open.
        let d = TempDir::new("cache-broken");
        let a = bake_cached(SPEC, &small(), Some(d.path()), false).unwrap();
        let whole = std::fs::read(&a.path).unwrap();
        let broken: [&[u8]; 3] = [b"", &whole[..100], &whole[..whole.len() - 1]];
        for bytes in broken {
            std::fs::write(&a.path, bytes).unwrap();
            let b = bake_cached(SPEC, &small(), Some(d.path()), false).unwrap();
            assert!(!b.hit, "{} bytes", bytes.len());
            assert!(crate::open(&b.path).is_ok());
        }
        let c = bake_cached(SPEC, &small(), Some(d.path()), false).unwrap();
        assert!(c.hit);
    }

    #[test]
    fn a_second_call_is_a_hit_and_refresh_bakes_again() {
        let d = TempDir::new("cache-hit");
        let a = bake_cached(SPEC, &small(), Some(d.path()), false).unwrap();
        assert!(!a.hit && a.path.is_file());
        let b = bake_cached(SPEC, &small(), Some(d.path()), false).unwrap();
        assert_eq!(
            b,
            Cached {
                path: a.path.clone(),
                hit: true
            }
        );
        let t = crate::open(&b.path).unwrap();
        let mut f = [0.0f32; 3];
        t.eval(glam::DVec3::Z, glam::DVec3::Z, &mut f);
        assert!((f[0] - 0.5).abs() < 1e-3, "Lambert: f_r = kd, {f:?}");
        drop(t); // Windows refuses to write a file this process holds mapped
        std::fs::write(&a.path, b"not a table").unwrap();
        let c = bake_cached(SPEC, &small(), Some(d.path()), true).unwrap();
        assert!(!c.hit);
        assert!(crate::open(&c.path).is_ok());
        // One table; beside it only the writer's lock file, no temporary file.
        let mut names: Vec<String> = std::fs::read_dir(d.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        let table = a.path.file_name().unwrap().to_string_lossy().into_owned();
        assert_eq!(names, [format!(".{table}.lock"), table]);
    }

    #[test]
    fn threads_asking_for_one_key_at_once_bake_it_once() {
        let d = TempDir::new("cache-race");
        let n = 4;
        let start = std::sync::Barrier::new(n);
        let hits: Vec<Cached> = std::thread::scope(|s| {
            let hs: Vec<_> = (0..n)
                .map(|_| {
                    s.spawn(|| {
                        start.wait();
                        bake_cached(SPEC, &small(), Some(d.path()), false).unwrap()
                    })
                })
                .collect();
            hs.into_iter().map(|h| h.join().unwrap()).collect()
        });
        assert!(hits.iter().all(|c| c.path == hits[0].path));
        let baked = hits.iter().filter(|c| !c.hit).count();
        assert_eq!(baked, 1, "one bake, the others wait for it: {hits:?}");
        assert!(crate::open(&hits[0].path).is_ok());
    }

    #[test]
    fn bad_settings_fail_before_anything_is_written() {
        let d = TempDir::new("cache-bad");
        let bad = BakeSettings {
            preset: Some("huge".into()),
            ..BakeSettings::default()
        };
        let e = bake_cached(SPEC, &bad, Some(&d.path().join("sub")), false).unwrap_err();
        assert!(e.to_string().contains("preset"), "{e}");
        assert!(!d.path().join("sub").exists());
    }

    #[test]
    fn tables_of_an_older_bake_rule_are_not_served() {
        // Default bakes of models check the medium preset's albedo since session 23 (GGX
        // α ≤ 0.02: the adaptive table of a 0.2 % target; Ward, the max-Phong, anisotropic GGX:
        // the medium table calibrated). The plain medium table a cache of rule 2 holds for
        // these settings must not be served: this was rule 2's key of Ward's default bake.
        let ward = r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#;
        let k = key(ward, &BakeSettings::default()).unwrap();
        assert_ne!(k, "b7e31b3ad748f3bc4df40253ddd174f4");
        // Rule 3's key: its check judged random pairs by uniform pairs alone, a lottery for
        // sharp lobes (analysis::mirror_pairs), so a rule-3 decision may differ.
        assert_ne!(k, "7be0f4605e7ec833d43c19f31e5a8f10");
    }
}
