//! Table names and `DB#NAME` sources: the one rule every host and every writer keeps.
//!
//! Why a module of its own: a name reaches the library by many roads — the `NAME` of a
//! `DB#NAME` source or output, a bake's `name` setting, a file's stem, a table imported under
//! another name — and the CLI, Python and the C ABI must all refuse the same names with the
//! same words. It depends on nothing but the error type, so the file helpers
//! (`files`) and the store share it without an import circle.
//!
//! A table name holds a character other than white space (an empty or blank name is invisible
//! in `db list`), and no `#` (it ends the path of `DB#NAME`), no `/` (a
//! `DB#NAME` whose name part has a `/` is read as a path with a `#` in a directory, so such a
//! table could be written but never opened by name), no `\` (the same on Windows, where it
//! separates directories: a database written on Linux must open on Windows by every name) and
//! no control character (NUL, tab, newline, ...: invisible or cut short in listings, C strings
//! and terminals).
//!
//! Names are checked where they are made — [`check`]: a put, a rename, an import's new name, a
//! bake's or a save's name, an output's `DB#NAME`. A table an earlier version stored under a
//! name with `\` is kept as it is: copied when its database is rewritten, removed or renamed
//! by name, and found by a `DB#NAME` that is read ([`parse_input`]) on Unix; on Windows, where
//! such a `DB#NAME` is a path, through the calls that take the name apart (`Store::table`,
//! `brdftab db rename DB OLD NEW`, which gives it a name of the rule).
//!
//! # A `#` in a file's own name
//!
//! A string is split at its last `#` into `DB` and `NAME` ([`parse_source`]), which alone would
//! make a file named `a#b.btdb` (or `scans/x#2.bsdf`) impossible to open: it would be read as
//! table `b.btdb` of a database `a`. So a string that is **read** is first looked up whole: if
//! something exists on disk under the whole string, that is the file read, and only otherwise is
//! it split ([`parse_input`]; [`path_of`] and `store::db::split_source` follow it, and so does
//! every host's open). A file on disk wins even over a database of the split's name holding such
//! a table. An **output** keeps the string rule ([`parse_source`]): `-o a#b.btdb` writes table
//! `b.btdb` into the database `a`, the documented `DB#NAME` output, whatever exists — where a
//! bake writes must not depend on which files happen to be there.

use std::ffi::OsStr;
use std::path::Path;

use crate::error::{Error, Result};

/// Checks a table name against the rule above; the error names `field` (`name`, or the
/// `source`/`output` the name was read from).
pub fn check(field: &str, name: &str) -> Result<()> {
    match name.contains('\\') {
        true => Err(refused(field, name, "contains `\\`")),
        false => check_stored(field, name),
    }
}

/// The rule of a name that a database holds already: [`check`]'s but for `\`, which earlier
/// versions allowed (such a table is read, copied and renamed, never made anew).
pub(crate) fn check_stored(field: &str, name: &str) -> Result<()> {
    let bad = if name.is_empty() {
        Some("is empty")
    } else if name.chars().all(char::is_whitespace) {
        Some("is only white space")
    } else if name.contains('#') {
        Some("contains `#`")
    } else if name.contains('/') {
        Some("contains `/`")
    } else if name.chars().any(char::is_control) {
        Some("contains a control character")
    } else {
        None
    };
    match bad {
        None => Ok(()),
        Some(why) => Err(refused(field, name, why)),
    }
}

fn refused(field: &str, name: &str, why: &str) -> Error {
    Error::arg(
        field,
        format!(
            "table name {name:?} {why}: a table name has a character other than white space, \
             and no `#`, `/`, `\\` or control characters"
        ),
    )
}

/// Splits a SOURCE or output string `DB#NAME` into the path and the table name (`None` for a
/// plain path), by the string alone: the rule of outputs (a SOURCE that is read goes through
/// [`parse_input`]). The name is what follows the last `#`, unless it holds a `/` (on Windows
/// also a `\`, its other separator): then the whole string is a path with a `#` in a
/// directory name. An empty name (`x.btdb#`) or one that breaks [`check`] is an
/// [`Error::InvalidArgument`] naming `field`.
pub fn parse_source<'a>(field: &str, source: &'a str) -> Result<(&'a str, Option<&'a str>)> {
    split(field, source, Rule::New)
}

/// Which names a `DB#NAME` split takes: an output's must be one a table may be made with
/// ([`check`]); a SOURCE that is read may name a table stored before `\` was refused.
#[derive(Clone, Copy)]
enum Rule {
    New,
    Stored,
}

fn split<'a>(field: &str, source: &'a str, rule: Rule) -> Result<(&'a str, Option<&'a str>)> {
    match source.rsplit_once('#') {
        Some((_, n)) if n.contains(std::path::is_separator) => Ok((source, None)),
        Some((p, n)) => {
            check_split(field, &format!("{source:?}"), n, rule)?;
            Ok((p, Some(n)))
        }
        None => Ok((source, None)),
    }
}

/// The name of a `DB#NAME` split, `shown` being the whole string as errors quote it.
fn check_split(field: &str, shown: &str, name: &str, rule: Rule) -> Result<()> {
    if name.is_empty() {
        return Err(Error::arg(
            field,
            format!("{shown}: no table name after `#` (DB#NAME)"),
        ));
    }
    match rule {
        Rule::New => check(field, name),
        Rule::Stored => check_stored(field, name),
    }
}

/// Whether SOURCE is inline JSON rather than a path: its first character after white space is
/// `{` (here, beside the `DB#NAME` rule, so that the file helpers and `source` share it).
pub(crate) fn is_inline(source: &OsStr) -> bool {
    match source.to_str() {
        Some(s) => s.trim_start().starts_with('{'),
        None => source
            .as_encoded_bytes()
            .trim_ascii_start()
            .starts_with(b"{"),
    }
}

/// [`parse_input`] of a SOURCE that need not be UTF-8 (a file name on Linux is bytes): a UTF-8
/// string goes through [`parse_input`] itself; another is split by the same rule on its bytes
/// (the last `#`, unless what follows holds a `/`), the path part kept as the bytes it is and
/// the name part required to be UTF-8, as every table name is. Errors show the string lossily.
pub fn parse_input_os<'a>(field: &str, source: &'a OsStr) -> Result<(&'a Path, Option<&'a str>)> {
    if let Some(s) = source.to_str() {
        return parse_input(field, s).map(|(p, n)| (Path::new(p), n));
    }
    split_os(field, source, true)
}

/// [`parse_source`] of an output that need not be UTF-8: split by the string rule alone (an
/// output never looks on disk), on the bytes for a string that is not UTF-8, as
/// [`parse_input_os`] splits a SOURCE.
pub fn parse_output_os<'a>(field: &str, output: &'a OsStr) -> Result<(&'a Path, Option<&'a str>)> {
    if let Some(s) = output.to_str() {
        return parse_source(field, s).map(|(p, n)| (Path::new(p), n));
    }
    split_os(field, output, false)
}

/// The `DB#NAME` split of a string that is not UTF-8, on its bytes: the whole string when it
/// has no `#`, when the part after the last `#` holds a separator (`/`; `\` too on Windows),
/// or (`read`) when something exists on disk under the whole string; else the path before the
/// `#` as the bytes it is and the name after it, which must be UTF-8 and pass [`check`] (when
/// `read`, the stored names' rule: a `\` taken, as [`parse_input`] takes it).
fn split_os<'a>(field: &str, source: &'a OsStr, read: bool) -> Result<(&'a Path, Option<&'a str>)> {
    let whole = Ok((Path::new(source), None));
    let bytes = source.as_encoded_bytes();
    let Some(i) = bytes.iter().rposition(|&b| b == b'#') else {
        return whole;
    };
    let name = &bytes[i + 1..];
    let separator = name.iter().any(|&b| std::path::is_separator(b as char));
    if separator || (read && std::fs::metadata(source).is_ok()) {
        return whole;
    }
    let shown = format!("{:?}", source.to_string_lossy());
    let name = std::str::from_utf8(name).map_err(|_| {
        Error::arg(
            field,
            format!("{shown}: the table name after `#` is not UTF-8 (DB#NAME)"),
        )
    })?;
    let rule = if read { Rule::Stored } else { Rule::New };
    check_split(field, &shown, name, rule)?;
    // SAFETY: `bytes` came from `as_encoded_bytes` and is cut immediately before an ASCII `#`,
    // a valid UTF-8 substring, as `from_encoded_bytes_unchecked` requires.
    let path = unsafe { OsStr::from_encoded_bytes_unchecked(&bytes[..i]) };
    Ok((Path::new(path), Some(name)))
}

/// Splits a SOURCE that is read: the whole string when something exists on disk under it (a
/// file named `a#b.btdb`: see the module docs), else [`parse_source`]'s split, whose errors name
/// `field` — but for a name with `\`, which it takes (on Unix: on Windows a `\` after the `#`
/// makes the string a path): a table an earlier version stored so is read by its name.
pub fn parse_input<'a>(field: &str, source: &'a str) -> Result<(&'a str, Option<&'a str>)> {
    if source.contains('#') && std::fs::metadata(Path::new(source)).is_ok() {
        return Ok((source, None));
    }
    split(field, source, Rule::Stored)
}

/// The path part of a SOURCE string, for callers that only look (which file a string reads, a
/// default name): [`parse_input`]'s path, and a string it refuses is taken as a plain path (the
/// call that opens it reports the error).
pub fn path_of(source: &str) -> &str {
    parse_input("source", source).map_or(source, |(p, _)| p)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field_of(e: Error) -> String {
        match e {
            Error::InvalidArgument { name, .. } => name,
            e => panic!("not an argument error: {e}"),
        }
    }

    #[test]
    fn blank_names_are_refused_as_empty_ones() {
        // `bake -o 'db.btdb#   '` wrote a table `db list` showed as an empty column.
        for name in [" ", "   ", "\u{3000}", " \u{a0} "] {
            let e = check("name", name).unwrap_err();
            assert!(e.to_string().contains("white space"), "{name:?}: {e}");
            assert_eq!(field_of(e), "name", "{name:?}");
            assert!(parse_source("output", &format!("db.btdb#{name}")).is_err());
        }
        check("name", " padded ").unwrap();
    }

    #[test]
    fn empty_names_and_control_characters_are_argument_errors_naming_the_field() {
        for name in [
            "", "\0", "a\0b", "a\tb", "line\n", "\u{7f}", "\u{85}", "a#b", "a/b",
        ] {
            let e = check("name", name).unwrap_err();
            assert_eq!(field_of(e), "name", "{name:?}");
        }
        for name in ["matte", "gold 2", "kupfer-ü", "x.y_z"] {
            check("name", name).unwrap();
        }
    }

    #[test]
    fn a_source_with_an_empty_or_bad_name_is_refused_not_read_as_a_path() {
        for s in ["x.btdb#", "x.btdb#\0", "x.btdb#a\nb", "dir/x.btdb#\t"] {
            let e = parse_source("output", s).unwrap_err();
            assert_eq!(field_of(e), "output", "{s:?}");
            assert!(e_msg(s).contains("table name"), "{s:?}: {}", e_msg(s));
        }
        assert_eq!(
            parse_source("source", "x.btdb#m").unwrap(),
            ("x.btdb", Some("m"))
        );
        assert_eq!(
            parse_source("source", "a#b.btdb#m").unwrap(),
            ("a#b.btdb", Some("m"))
        );
        // A `#` in a directory: the whole string is a path.
        assert_eq!(
            parse_source("source", "d#1/x.btdb").unwrap(),
            ("d#1/x.btdb", None)
        );
        assert_eq!(parse_source("source", "x.btdb").unwrap(), ("x.btdb", None));
        assert_eq!(path_of("x.btdb#"), "x.btdb#");
        assert_eq!(path_of("x.btdb#m"), "x.btdb");
    }

    #[test]
    fn a_string_that_names_a_file_as_a_whole_is_read_as_that_file() {
        let d = crate::testkit::TempDir::new("name-hash");
        std::fs::create_dir(d.join("scan#2")).unwrap();
        for f in ["a#b.btdb", "scan#2/x#y.bsdf", "m.btdb#"] {
            let whole = d.file(f);
            // Not there yet: split as DB#NAME (or refused), as an output always is.
            let split = parse_source("source", &whole);
            assert_eq!(
                parse_input("source", &whole).ok(),
                split.as_ref().ok().copied()
            );
            std::fs::write(&whole, b"x").unwrap();
            assert_eq!(
                parse_input("source", &whole).unwrap(),
                (whole.as_str(), None)
            );
            assert_eq!(path_of(&whole), whole);
            // An output keeps the string rule whatever exists.
            assert_eq!(parse_source("output", &whole).ok(), split.ok());
        }
        // A database and a table of the split's name: the plain split when no such file exists.
        let db = d.file("db.btdb");
        std::fs::write(&db, b"x").unwrap();
        let s = format!("{db}#t");
        assert_eq!(parse_input("source", &s).unwrap(), (db.as_str(), Some("t")));
    }

    /// An output that is not UTF-8 splits on its bytes by the string rule, whatever exists on
    /// disk (a SOURCE that is read is looked up whole first).
    // Not on Apple's file systems, which refuse a name that is not UTF-8 (APFS: EILSEQ).
    #[cfg(all(unix, not(target_vendor = "apple")))]
    #[test]
    fn an_output_that_is_not_utf8_splits_by_the_string_rule() {
        use std::os::unix::ffi::OsStrExt;
        let d = crate::testkit::TempDir::new("name-out-os");
        let whole = d.path().join(OsStr::from_bytes(b"caf\xe9.btdb#m"));
        std::fs::write(&whole, b"x").unwrap();
        let db = d.path().join(OsStr::from_bytes(b"caf\xe9.btdb"));
        let s = whole.as_os_str();
        assert_eq!(
            parse_output_os("output", s).unwrap(),
            (db.as_path(), Some("m"))
        );
        assert_eq!(
            parse_input_os("source", s).unwrap(),
            (whole.as_path(), None)
        );
        let dir = OsStr::from_bytes(b"d#\xe9/x.btdb");
        assert_eq!(
            parse_output_os("output", dir).unwrap(),
            (Path::new(dir), None)
        );
        // Refused, the string shown lossily where the message quotes it.
        for (bad, quoted) in [
            (&b"caf\xe9.btdb#"[..], true),
            (b"caf\xe9.btdb#\xe9", true),
            (b"caf\xe9.btdb#a\tb", false),
        ] {
            let e = parse_output_os("output", OsStr::from_bytes(bad)).unwrap_err();
            assert_eq!(e.to_string().contains("caf\u{FFFD}"), quoted, "{e}");
            assert_eq!(field_of(e), "output");
        }
        assert_eq!(
            parse_output_os("output", OsStr::new("x.btdb#m")).unwrap(),
            (Path::new("x.btdb"), Some("m"))
        );
    }

    /// On Windows `\` separates directories as `/` does: a `#` in a directory's name is no
    /// `DB#NAME` split there either (`C:\scans#2\x.btdb` was table `2\x.btdb` of `C:\scans`).
    #[cfg(windows)]
    #[test]
    fn a_backslash_after_the_hash_is_a_path_on_windows() {
        use std::os::windows::ffi::OsStringExt;
        let p = r"C:\scans#2\x.btdb";
        assert_eq!(parse_source("output", p).unwrap(), (p, None));
        assert_eq!(parse_input("source", p).unwrap(), (p, None));
        assert_eq!(
            parse_source("output", r"C:\lib.btdb#t").unwrap(),
            (r"C:\lib.btdb", Some("t"))
        );
        // Not UTF-8 (an unpaired surrogate): the same rule on the bytes.
        let w: Vec<u16> = [0xD800]
            .into_iter()
            .chain("#2\\x.btdb".encode_utf16())
            .collect();
        let odd = std::ffi::OsString::from_wide(&w);
        assert_eq!(
            parse_output_os("output", &odd).unwrap(),
            (Path::new(&odd), None)
        );
        let w: Vec<u16> = [0xD800]
            .into_iter()
            .chain(".btdb#t".encode_utf16())
            .collect();
        let db = std::ffi::OsString::from_wide(&w);
        assert_eq!(parse_output_os("output", &db).unwrap().1, Some("t"));
    }

    /// `\` is refused in a name made anew, on every platform (on Windows `DB#a\b` is a path,
    /// so a table `a\b` written on Linux could not be opened there by name); a SOURCE that is
    /// read still names a table an earlier version stored so.
    #[test]
    fn a_backslash_is_refused_in_new_names_and_read_in_stored_ones() {
        for name in [r"a\b", r"\", r"gold\"] {
            let e = check("name", name).unwrap_err();
            assert!(e.to_string().contains(r"contains `\`"), "{name:?}: {e}");
            assert_eq!(field_of(e), "name", "{name:?}");
            check_stored("name", name).unwrap();
        }
        for bad in ["", " ", "a#b", "a/b", "a\tb"] {
            assert!(check_stored("name", bad).is_err(), "{bad:?}");
        }
        #[cfg(not(windows))]
        {
            let e = parse_source("output", r"x.btdb#a\b").unwrap_err();
            assert_eq!(field_of(e), "output");
            assert_eq!(
                parse_input("source", r"x.btdb#a\b").unwrap(),
                ("x.btdb", Some(r"a\b"))
            );
        }
        #[cfg(windows)]
        for s in [
            parse_source("output", r"x.btdb#a\b"),
            parse_input("source", r"x.btdb#a\b"),
        ] {
            assert_eq!(s.unwrap(), (r"x.btdb#a\b", None));
        }
    }

    fn e_msg(s: &str) -> String {
        parse_source("output", s).unwrap_err().to_string()
    }
}
