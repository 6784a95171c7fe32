//! Database operations on a brdftab file: add, replace, remove, rename, list, get, verify.
//!
//! Every change writes a complete new file next to the old one (copying the other tables' chunks
//! byte for byte, checksums checked, without decoding them), fsyncs it, renames it over the old
//! file and fsyncs the directory. A process killed at any moment therefore leaves the old
//! database or the new one, and an entry already stored is never lost. Writers serialize on an
//! advisory lock file (`.NAME.lock` beside the database) so two concurrent `add`s cannot drop
//! each other's table; readers take no lock and keep the version they opened. A database
//! path that is a symbolic link is updated where it points (`files::resolve_links`): the link
//! stays a link, and writers through it and through the file's own name share the lock.

use std::fs::File;
use std::path::{Path, PathBuf};

use super::{Store, TableHeader, TocEntry, Writer};
use crate::error::{Error, Result};
use crate::progress::Progress;

/// Holds the database's writer lock while alive.
pub struct Lock {
    _file: File,
}

/// Takes the exclusive writer lock of the database at `path` (blocks until free); a symbolic
/// link's is its target's.
pub fn lock(path: &Path) -> Result<Lock> {
    let (f, lp) = lock_file(path)?;
    f.lock().map_err(|e| Error::io(&lp, e))?;
    Ok(Lock { _file: f })
}

/// How often [`lock_with`] tries a lock held by another writer.
const LOCK_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// [`lock`], waiting for a lock held by another writer (another process's bake of the same
/// cached table: minutes) in tries 50 ms apart, between which it asks `progress` to
/// stop ([`crate::progress::Progress::cancelled`]: [`Error::Cancelled`]).
pub fn lock_with(path: &Path, progress: &dyn crate::progress::Progress) -> Result<Lock> {
    let (f, lp) = lock_file(path)?;
    loop {
        match f.try_lock() {
            Ok(()) => return Ok(Lock { _file: f }),
            Err(std::fs::TryLockError::WouldBlock) => {}
            Err(std::fs::TryLockError::Error(e)) => return Err(Error::io(&lp, e)),
        }
        crate::progress::check(progress)?;
        std::thread::sleep(LOCK_POLL);
    }
}

/// The lock file of the database at `path`, open for writing, and its path.
fn lock_file(path: &Path) -> Result<(File, PathBuf)> {
    let path = &crate::files::resolve_links(path)?;
    // A database is written through a new file renamed over it: a pipe or a device there, or
    // a directory that is not one, is refused before the lock, in output terms.
    crate::files::check_writable(path)?;
    let name = path
        .file_name()
        .ok_or_else(|| Error::arg("DB", format!("{} has no file name", path.display())))?
        .to_string_lossy();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let lp = dir.join(format!(".{name}.lock"));
    let f = File::options()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&lp)
        .map_err(|e| Error::io(&lp, e))?;
    Ok((f, lp))
}

/// Opens an existing database, or `None` when the file does not exist.
fn existing(path: &Path) -> Result<Option<Store>> {
    match std::fs::metadata(path) {
        Ok(_) => Store::open(path).map(Some),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(Error::io(path, e)),
    }
}

/// Refuses `name` when the database at `path` holds a table of that name already — what
/// [`put`] refuses without `replace`, checked before the work that makes the table (a bake of
/// seconds to minutes) rather than at its end. A database not created yet holds no name.
pub fn refuse_duplicate(path: impl AsRef<Path>, name: &str) -> Result<()> {
    let path = path.as_ref();
    // What the write at the end would refuse (`x.btdb/lib.btdb` read as "Not a directory (os
    // error 20)"), before the work.
    crate::files::check_writable(&crate::files::resolve_links(path)?)?;
    match existing(path)? {
        Some(s) if s.tables().iter().any(|t| t.name == name) => Err(Error::Duplicate {
            container: path.display().to_string(),
            name: name.to_owned(),
        }),
        _ => Ok(()),
    }
}

/// Refuses to write a one-table file over `path` when it is a database of several tables: `bake
/// x -o lib.btdb` replaced a library of materials with one table, silently, where `convert x
/// lib.btdb` adds a table to it. A file that is no database, or one of a single table (a
/// table file baked before), is replaced as any output is. Checked before the work.
///
/// # Errors
/// [`Error::InvalidArgument`] naming `output`.
pub fn refuse_dropping_tables(path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    let Some(s) = crate::files::is_regular(path)
        .then(|| Store::open(path).ok())
        .flatten()
    else {
        return Ok(());
    };
    match s.tables().len() {
        n @ 2.. => Err(Error::arg(
            "output",
            format!(
                "{0} is a database of {n} tables: a one-table file written there would drop \
                 them all (write {0}#NAME to add a table, or remove the file first)",
                path.display()
            ),
        )),
        _ => Ok(()),
    }
}

/// The host that may ask a change to stop: `None` for the calls without one, which wait for
/// another writer's lock blocked rather than in polls.
type Stop<'a> = Option<&'a dyn Progress>;

/// The writer lock, waited for in polls that ask `stop` when there is one ([`lock_with`]).
fn lock_for(path: &Path, stop: Stop<'_>) -> Result<Lock> {
    match stop {
        Some(p) => lock_with(path, p),
        None => lock(path),
    }
}

/// Copies table `e` of `from` into `w` without decoding (checksums are checked on the way).
fn copy_table(from: &Store, e: &TocEntry, w: &mut Writer, stop: Stop<'_>) -> Result<()> {
    let t = from.table(&e.name)?;
    w.begin_kept_table(t.header().clone())?;
    copy_chunks(&t, w, stop)?;
    w.end_table()
}

/// The encoded chunks of `t`, checksums checked, into the table `w` has begun; asks `stop`
/// before each (a database of many tables is copied whole by every change).
fn copy_chunks(t: &super::StoredTable, w: &mut Writer, stop: Stop<'_>) -> Result<()> {
    for i in 0..t.chunk_count() {
        if let Some(p) = stop {
            crate::progress::check(p)?;
        }
        w.encoded_chunk(&t.raw_chunk(i)?, t.chunk_values(i) as u64)?;
    }
    Ok(())
}

/// Adds table `name` of `from` (another database, or a single-table file's bytes opened with
/// [`Store::from_bytes`]) to the database at `path` as `as_name`, without decoding or
/// re-encoding: what gathers tables baked elsewhere (other processes, other machines) into
/// one database. Every chunk's checksum is checked on the way; `replace` as in [`put`].
pub fn import(
    path: impl AsRef<Path>,
    from: &Store,
    name: &str,
    as_name: &str,
    replace: bool,
) -> Result<()> {
    import_inner(path.as_ref(), from, name, as_name, replace, None)
}

/// [`import`], asking `progress` to stop as [`put_with`] does.
///
/// # Errors
/// Those of [`import`], and [`Error::Cancelled`] (the database as it was).
pub fn import_with(
    path: impl AsRef<Path>,
    from: &Store,
    name: &str,
    as_name: &str,
    replace: bool,
    progress: &dyn Progress,
) -> Result<()> {
    import_inner(path.as_ref(), from, name, as_name, replace, Some(progress))
}

fn import_inner(
    path: &Path,
    from: &Store,
    name: &str,
    as_name: &str,
    replace: bool,
    stop: Stop<'_>,
) -> Result<()> {
    let t = from.table(name)?;
    let mut header = t.header().clone();
    header.name = as_name.to_owned();
    put_inner(path, header, replace, stop, |w| copy_chunks(&t, w, stop))
}

/// Adds a table to the database at `path` (created if absent). `write` receives the writer with
/// the table begun and must supply all its chunks ([`Writer::chunk`] one at a time, or
/// [`Writer::chunks_par`]). With `replace`, an existing table of that name is replaced in place;
/// without it, an existing name is an error.
pub fn put(
    path: impl AsRef<Path>,
    header: TableHeader,
    replace: bool,
    write: impl FnOnce(&mut Writer) -> Result<()>,
) -> Result<()> {
    put_inner(path.as_ref(), header, replace, None, write)
}

/// [`put`] for a host that may ask it to stop ([`Progress::cancelled`]): while it waits for
/// another writer's lock (another process's streamed bake into the same database holds it for
/// the whole bake) and between the chunks of the other tables it copies. `write` asks for
/// itself, as a bake does.
///
/// # Errors
/// Those of [`put`], and [`Error::Cancelled`]: the database is as it was, and no temporary
/// file is left.
pub fn put_with(
    path: impl AsRef<Path>,
    header: TableHeader,
    replace: bool,
    progress: &dyn Progress,
    write: impl FnOnce(&mut Writer) -> Result<()>,
) -> Result<()> {
    put_inner(path.as_ref(), header, replace, Some(progress), write)
}

fn put_inner(
    user: &Path, // the name errors give
    header: TableHeader,
    replace: bool,
    stop: Stop<'_>,
    write: impl FnOnce(&mut Writer) -> Result<()>,
) -> Result<()> {
    // Before the lock file or the database is touched.
    super::name::check("name", &header.name)?;
    let path = &crate::files::resolve_links(user)?;
    let _lock = lock_for(path, stop)?;
    let old = existing(path)?;
    let name = header.name.clone();
    if let Some(s) = &old
        && !replace
        && s.tables().iter().any(|t| t.name == name)
    {
        return Err(Error::Duplicate {
            container: user.display().to_string(),
            name,
        });
    }
    let mut w = Writer::create(path)?;
    type Fill<'a> = Box<dyn FnOnce(&mut Writer) -> Result<()> + 'a>;
    let mut new: Option<(TableHeader, Fill<'_>)> = Some((header, Box::new(write)));
    fn emit(w: &mut Writer, new: &mut Option<(TableHeader, Fill<'_>)>) -> Result<()> {
        if let Some((h, f)) = new.take() {
            w.begin_table(h)?;
            f(w)?;
            w.end_table()?;
        }
        Ok(())
    }
    if let Some(s) = &old {
        for e in s.tables() {
            if e.name == name {
                emit(&mut w, &mut new)?;
            } else {
                copy_table(s, e, &mut w, stop)?;
            }
        }
    }
    emit(&mut w, &mut new)?;
    // The old store dropped before the new file is renamed over it: one that held the file
    // open or mapped (`Store::open_reading`, `Store::open_mapped`; `Store::open` reads it into
    // memory on Windows) would keep Windows from replacing it ("Access denied").
    drop(old);
    w.finish()
}

/// Writes a single-table file from chunks in memory (each with its predictor layout),
/// replacing `path`.
pub fn write_table(
    path: impl AsRef<Path>,
    header: TableHeader,
    chunks: &[(&[f32], crate::codec::Layout)],
) -> Result<()> {
    let mut w = Writer::create(path)?;
    w.begin_table(header)?;
    w.chunks_par(chunks)?;
    w.end_table()?;
    w.finish()
}

/// Removes table `name`. Errors with [`Error::NotFound`] if it or the database is absent
/// (naming the tables the database holds).
pub fn remove(path: impl AsRef<Path>, name: &str) -> Result<()> {
    remove_inner(path.as_ref(), name, None)
}

/// [`remove`], asking `progress` to stop as [`put_with`] does.
///
/// # Errors
/// Those of [`remove`], and [`Error::Cancelled`] (the database as it was).
pub fn remove_with(path: impl AsRef<Path>, name: &str, progress: &dyn Progress) -> Result<()> {
    remove_inner(path.as_ref(), name, Some(progress))
}

fn remove_inner(user: &Path, name: &str, stop: Stop<'_>) -> Result<()> {
    let path = &crate::files::resolve_links(user)?;
    // A missing database is reported before the lock, which would leave its lock file behind.
    crate::files::require_regular(user)?;
    let _lock = lock_for(path, stop)?;
    let s = Store::open(path)?;
    if !s.tables().iter().any(|t| t.name == name) {
        return Err(super::no_table(
            &user.display().to_string(),
            name,
            s.tables(),
        ));
    }
    let mut w = Writer::create(path)?;
    for e in s.tables().iter().filter(|e| e.name != name) {
        copy_table(&s, e, &mut w, stop)?;
    }
    drop(s); // closed before the rename over it (see `put`)
    w.finish()
}

/// Renames table `old` to `new`: the table keeps its place among the others and its chunks
/// byte for byte (checksums checked on the way), only its header's name changes; the database
/// is rewritten atomically as by every other change. `new` must keep the table-name rule
/// ([`super::name::check`]).
///
/// # Errors
/// [`Error::NotFound`] naming the database when it or table `old` is absent (listing the
/// tables it holds), [`Error::Duplicate`] naming the database when it holds a table `new`
/// already (`old` itself included), [`Error::InvalidArgument`] (`name`) for a `new` the rule
/// refuses — each before the database is rewritten.
pub fn rename(path: impl AsRef<Path>, old: &str, new: &str) -> Result<()> {
    rename_inner(path.as_ref(), old, new, None)
}

/// [`rename`], asking `progress` to stop as [`put_with`] does.
///
/// # Errors
/// Those of [`rename`], and [`Error::Cancelled`] (the database as it was).
pub fn rename_with(
    path: impl AsRef<Path>,
    old: &str,
    new: &str,
    progress: &dyn Progress,
) -> Result<()> {
    rename_inner(path.as_ref(), old, new, Some(progress))
}

fn rename_inner(user: &Path, old: &str, new: &str, stop: Stop<'_>) -> Result<()> {
    super::name::check("name", new)?;
    let path = &crate::files::resolve_links(user)?;
    // A missing database is reported before the lock, which would leave its lock file behind.
    crate::files::require_regular(user)?;
    let _lock = lock_for(path, stop)?;
    let s = Store::open(path)?;
    let container = user.display().to_string();
    if !s.tables().iter().any(|t| t.name == old) {
        return Err(super::no_table(&container, old, s.tables()));
    }
    if s.tables().iter().any(|t| t.name == new) {
        let name = new.to_owned();
        return Err(Error::Duplicate { container, name });
    }
    let mut w = Writer::create(path)?;
    for e in s.tables() {
        if e.name != old {
            copy_table(&s, e, &mut w, stop)?;
            continue;
        }
        let t = s.table(old)?;
        let mut header = t.header().clone();
        header.name = new.to_owned();
        w.begin_table(header)?;
        copy_chunks(&t, &mut w, stop)?;
        w.end_table()?;
    }
    drop(s); // closed before the rename over it (see `put`)
    w.finish()
}

/// The tables of the database with their headers.
pub fn list(path: impl AsRef<Path>) -> Result<Vec<(TocEntry, TableHeader)>> {
    let s = Store::open(path)?;
    s.tables()
        .iter()
        .map(|e| Ok((e.clone(), s.table(&e.name)?.header().clone())))
        .collect()
}

/// Checks every checksum and decodes every chunk; returns the number of chunks checked.
pub fn verify(path: impl AsRef<Path>) -> Result<usize> {
    Store::open(path)?.verify()
}

/// Splits SOURCE `DB#NAME` into the path and the optional table name; an empty name
/// (`x.btdb#`) or one [`super::name::check`] refuses is an argument error naming `source`. A
/// string that names an existing file as a whole (`a#b.btdb`) is that file
/// ([`super::name::parse_input`]). SOURCE need not be UTF-8 (a `&str`, `OsStr` or `Path`; split
/// on its bytes: [`super::name::parse_input_os`]).
pub fn split_source<S: AsRef<std::ffi::OsStr> + ?Sized>(
    source: &S,
) -> Result<(&Path, Option<&str>)> {
    super::name::parse_input_os("source", source.as_ref())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Channels;
    use crate::codec::{Codec, Quant};
    use crate::store::Source;

    fn header(name: &str) -> TableHeader {
        let source = Source::Other {
            description: "names".into(),
        };
        let codec = Codec {
            quant: Quant::F32,
            ..Codec::default()
        };
        TableHeader::new(name, source, vec![1, 2, 2, 3], Channels::Rgb, codec)
    }

    fn put_table(path: &Path, name: &str, v: f32) -> Result<()> {
        put(path, header(name), false, |w| w.chunk(&[v; 12]))
    }

    fn names(path: &Path) -> Vec<String> {
        let s = Store::open(path).unwrap();
        s.tables().iter().map(|e| e.name.clone()).collect()
    }

    fn refused(r: Result<()>) {
        match r {
            Err(Error::InvalidArgument { name, msg }) => {
                assert_eq!(name, "name");
                assert!(msg.contains(r"contains `\`"), "{msg}");
            }
            r => panic!("{r:?}"),
        }
    }

    /// Asks to stop from the `after`-th question on.
    struct StopAfter(std::sync::atomic::AtomicUsize, usize);

    impl Progress for StopAfter {
        fn cancelled(&self) -> bool {
            self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed) >= self.1
        }
    }

    /// A change asked to stop while it copies the other tables returns `Cancelled` and leaves
    /// the database byte for byte as it was, with no temporary file beside it; one never asked
    /// asks once per copied chunk.
    #[test]
    fn a_change_stopped_in_its_copy_leaves_the_database_as_it_was() {
        let d = crate::testkit::TempDir::new("db-stop-copy");
        let p = d.path().join("lib.btdb");
        for (i, name) in ["a", "b", "c"].into_iter().enumerate() {
            put_table(&p, name, i as f32).unwrap();
        }
        let bytes = std::fs::read(&p).unwrap();
        let files = || std::fs::read_dir(d.path()).unwrap().count();
        let before = files(); // the database and its lock file
        for after in 0..3 {
            let stop = StopAfter(Default::default(), after);
            let r = put_with(&p, header("d"), false, &stop, |w| w.chunk(&[9.0; 12]));
            assert!(matches!(r, Err(Error::Cancelled)), "{after}: {r:?}");
            let from = Store::open(&p).unwrap();
            let r = import_with(&p, &from, "a", "e", false, &stop);
            assert!(matches!(r, Err(Error::Cancelled)), "{after}: {r:?}");
            drop(from);
            // Removing or renaming one of three copies the other two, one chunk each.
            let stop = StopAfter(Default::default(), after.min(1));
            let r = remove_with(&p, "c", &stop);
            assert!(matches!(r, Err(Error::Cancelled)), "{after}: {r:?}");
            let stop = StopAfter(Default::default(), after);
            let r = rename_with(&p, "a", "z", &stop);
            assert!(matches!(r, Err(Error::Cancelled)), "{after}: {r:?}");
            assert_eq!(
                std::fs::read(&p).unwrap(),
                bytes,
                "{after}: the database untouched"
            );
            assert_eq!(files(), before, "{after}: no temporary file left");
        }
        let never = StopAfter(Default::default(), usize::MAX);
        put_with(&p, header("d"), false, &never, |w| w.chunk(&[9.0; 12])).unwrap();
        let asked = never.0.load(std::sync::atomic::Ordering::Relaxed);
        assert_eq!(
            asked, 3,
            "one question per copied chunk (three one-chunk tables)"
        );
        assert_eq!(names(&p), ["a", "b", "c", "d"]);
    }

    /// A table name with `\` is refused wherever a table is made or renamed — a database
    /// written on Linux opens on Windows by every name — while a table an earlier version
    /// stored so is kept through every rewrite of its database and can be renamed.
    #[test]
    fn a_backslash_is_refused_in_new_names_and_kept_in_stored_ones() {
        let d = crate::testkit::TempDir::new("db-backslash");
        let p = d.path().join("lib.btdb");
        refused(put_table(&p, r"a\b", 1.0));
        assert!(!p.exists(), "refused before the database is written");
        put_table(&p, "ok", 1.0).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        refused(rename(&p, "ok", r"o\k"));
        let from = Store::open(&p).unwrap();
        refused(import(&p, &from, "ok", r"c\d", false));
        assert_eq!(std::fs::read(&p).unwrap(), bytes, "the database untouched");

        // Written as an earlier version wrote it: kept by every rewrite, read by name.
        let mut w = Writer::create(&p).unwrap();
        w.begin_kept_table(header(r"a\b")).unwrap();
        w.chunk(&[2.0; 12]).unwrap();
        w.end_table().unwrap();
        w.finish().unwrap();
        put_table(&p, "c", 3.0).unwrap();
        remove(&p, "c").unwrap();
        assert_eq!(names(&p), [r"a\b"]);
        let s = Store::open(&p).unwrap();
        assert_eq!(s.table(r"a\b").unwrap().read_all().unwrap(), [2.0; 12]);
        #[cfg(not(windows))]
        {
            let source = format!("{}#a\\b", p.display());
            assert_eq!(split_source(&source).unwrap(), (p.as_path(), Some(r"a\b")));
        }
        rename(&p, r"a\b", "a_b").unwrap();
        assert_eq!(names(&p), ["a_b"]);
    }
}
