//! A baked table's default name: a file's [`stem`], a SOURCE's [`source_stem`], and the rule
//! that a `name` setting repeat a `DB#NAME` output's name ([`refuse_name_conflict`]).

use std::path::Path;

use crate::error::{Error, Result};

/// A `name` setting beside a `DB#NAME` output must repeat NAME: which one the user meant is
/// unknown, and taking either silently wrote a table the other road could not find. The rule of
/// a bake and of [`crate::request::save_table`] (`brdftab import`, Python's `Table.save`).
///
/// # Errors
/// [`Error::InvalidArgument`] naming `name` when `setting` is another name than `db_name`.
pub(crate) fn refuse_name_conflict(setting: Option<&str>, db_name: &str) -> Result<()> {
    match setting {
        Some(n) if n != db_name => Err(Error::arg(
            "name",
            format!(
                "{n:?} conflicts with the output's table name {db_name:?} (DB#NAME names the \
                 table itself: drop the name setting or make them agree)"
            ),
        )),
        _ => Ok(()),
    }
}

/// A file name's stem, the default name of a table (`table` when it has none). `path` is a
/// path, not a `DB#NAME` (a SOURCE's file is [`crate::store::name::path_of`]); a `#` or `\` in
/// the stem (a file named `scan#2.bsdf`, or `a\b.bsdf` on Unix), which a table name cannot
/// hold, becomes `_`.
pub fn stem(path: impl AsRef<Path>) -> String {
    path.as_ref()
        .file_stem()
        .map(|s| s.to_string_lossy().replace(['#', '\\'], "_"))
        .unwrap_or_else(|| "table".into())
}

/// The default name of a table converted from SOURCE: the table's own name for `DB#NAME`, the
/// model's name for an inline spec (`lambert`; not a stem of the JSON text, cut at its last
/// `.`), else its file's [`stem`].
pub fn source_stem(source: impl AsRef<std::ffi::OsStr>) -> String {
    let source = source.as_ref();
    if let Some(s) = source.to_str()
        && s.trim_start().starts_with('{')
    {
        return crate::spec::ModelSpec::parse(s)
            .map_or_else(|_| "table".into(), |s| s.name().to_owned());
    }
    match crate::store::name::parse_input_os("source", source) {
        Ok((_, Some(name))) => name.to_owned(),
        Ok((path, None)) => stem(path),
        Err(_) => stem(Path::new(source)),
    }
}
