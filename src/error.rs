//! The crate's one error type.
//!
//! Every fallible operation in brdftab returns [`Result`]. Errors carry the context a user needs to
//! fix the input: the file, the field, the byte offset or the line. Library code never panics on
//! input a user can influence; it returns one of these instead.

use std::path::Path;

/// Everything that can go wrong in brdftab.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An operating-system I/O error, with what we were doing (usually the path).
    #[error("{context}: {source}")]
    Io {
        /// What was being done, e.g. the file name.
        context: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },

    /// A model spec (JSON) is invalid: an unknown model or field, a negative or NaN parameter.
    #[error("invalid spec: field `{field}`: {msg}")]
    Spec {
        /// The offending field, dotted path when nested (`terms[1].fresnel.n`).
        field: String,
        /// What is wrong with it.
        msg: String,
    },

    /// JSON that does not parse (spec files, headers).
    #[error("{context}: invalid JSON: {source}")]
    Json {
        /// Where the JSON came from.
        context: String,
        /// The parser's message (with line and column).
        #[source]
        source: serde_json::Error,
    },

    /// A line of text input (stdin pairs, TSV files) that does not parse.
    #[error("{source_name}: line {line}: {msg}")]
    Parse {
        /// Name of the input (`stdin`, a file name).
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        msg: String,
    },

    /// A binary file whose content is malformed (wrong magic, truncated, bad sizes, ...).
    #[error("{file}: {}{}{msg}", field.as_ref().map(|f| format!("field `{f}`: ")).unwrap_or_default(), offset.map(|o| format!("at byte {o}: ")).unwrap_or_default())]
    Format {
        /// The file (or `<memory>`).
        file: String,
        /// The field or section concerned, if any.
        field: Option<String>,
        /// The byte offset concerned, if any.
        offset: Option<u64>,
        /// What is wrong.
        msg: String,
    },

    /// Stored data does not match its checksum.
    #[error(
        "{file}: checksum mismatch in {what} (stored {stored:#018x}, computed {computed:#018x})"
    )]
    Checksum {
        /// The file.
        file: String,
        /// Which block (table and chunk).
        what: Section,
        /// The checksum in the file.
        stored: u64,
        /// The checksum of the data read.
        computed: u64,
    },

    /// A declared symmetry that the source breaks beyond tolerance.
    #[error(
        "source is not {symmetry}: relative difference {error:.3e} > tolerance {tolerance:.1e} at {at}"
    )]
    Symmetry {
        /// The symmetry broken.
        symmetry: SymmetryKind,
        /// Worst relative difference found.
        error: f64,
        /// The tolerance in force.
        tolerance: f64,
        /// Where it was found (a human-readable direction pair).
        at: String,
    },

    /// A name that is already taken (a table in a database, when replacing was not asked for).
    #[error("{container} already holds a table `{name}`")]
    Duplicate {
        /// The database (or file) holding the name.
        container: String,
        /// The name.
        name: String,
    },

    /// An argument out of its valid range or otherwise unusable.
    #[error("invalid argument `{name}`: {msg}")]
    InvalidArgument {
        /// The argument's name (`grid`, `wavelengths`, ...): the library's name of the setting,
        /// never a host's flag (hosts map errors to their own words).
        name: String,
        /// What is wrong.
        msg: String,
    },

    /// A value that cannot be represented by the chosen encoding (e.g. above the f16 range).
    #[error("cannot encode: {msg}")]
    Encode {
        /// What is wrong and, where possible, a hint.
        msg: String,
    },

    /// The operation is not available for this source or build.
    #[error("unsupported: {0}")]
    Unsupported(String),

    /// A named entry does not exist (a table in a database, a metal, ...).
    #[error("not found: {0}")]
    NotFound(String),

    /// The host asked the operation to stop ([`crate::progress::Progress::cancelled`]); a file
    /// it was writing is left as it was.
    #[error("cancelled")]
    Cancelled,
}

/// One of the symmetries a BRDF may have, as [`Error::Symmetry`] names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SymmetryKind {
    /// f(wi, wo) unchanged by a common rotation about the normal.
    Isotropic,
    /// f(wi, wo) = f(wo, wi).
    Reciprocal,
    /// f unchanged by the mirror y → −y.
    Bilateral,
}

impl SymmetryKind {
    /// The three kinds, in the order of [`crate::table::Symmetry`]'s fields.
    pub const ALL: [SymmetryKind; 3] = [
        SymmetryKind::Isotropic,
        SymmetryKind::Reciprocal,
        SymmetryKind::Bilateral,
    ];

    /// `isotropic`, `reciprocal` or `bilateral`.
    pub fn name(self) -> &'static str {
        match self {
            SymmetryKind::Isotropic => "isotropic",
            SymmetryKind::Reciprocal => "reciprocal",
            SymmetryKind::Bilateral => "bilateral",
        }
    }
}

impl std::fmt::Display for SymmetryKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A checksummed block of a store file, as [`Error::Checksum`] (and format errors) name it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Section {
    /// The fixed-size superblock at the start of the file.
    Superblock,
    /// The table of contents.
    Toc,
    /// A table's JSON header.
    Header {
        /// The table's name.
        table: String,
    },
    /// A table's chunk index.
    Index {
        /// The table's name.
        table: String,
    },
    /// One chunk of a table's values.
    Chunk {
        /// The table's name.
        table: String,
        /// The chunk's number.
        chunk: usize,
    },
}

impl std::fmt::Display for Section {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Section::Superblock => f.write_str("superblock"),
            Section::Toc => f.write_str("table of contents"),
            Section::Header { table } => write!(f, "table `{table}` header"),
            Section::Index { table } => write!(f, "table `{table}` index"),
            Section::Chunk { table, chunk } => write!(f, "table `{table}` chunk {chunk}"),
        }
    }
}

/// Shorthand for `std::result::Result<T, brdftab::Error>`.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// An I/O error with the path it concerns.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io {
            context: path.as_ref().display().to_string(),
            source,
        }
    }

    /// A spec error naming `field`. What the message quotes of the input (between backticks:
    /// a model name, an unknown field) is shortened to an [`excerpt`], so a huge spec does not
    /// make a huge message.
    pub fn spec(field: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Spec {
            field: excerpt(&field.into()).into_owned(),
            msg: shorten_quoted(&msg.into()),
        }
    }

    /// A format error in `file`, with optional field and offset.
    pub fn format(
        file: impl Into<String>,
        field: Option<&str>,
        offset: Option<u64>,
        msg: impl Into<String>,
    ) -> Self {
        Error::Format {
            file: file.into(),
            field: field.map(str::to_owned),
            offset,
            msg: msg.into(),
        }
    }

    /// An invalid-argument error.
    pub fn arg(name: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::InvalidArgument {
            name: name.into(),
            msg: msg.into(),
        }
    }

    /// A copy of this error with the same variant and message, for errors that are reported
    /// more than once (a table's sticky chunk failure, [`crate::Brdf::health`]). The wrapped
    /// sources that cannot be cloned are rebuilt from their message: an I/O error keeps its
    /// kind, a JSON error becomes a format error with the same text.
    pub fn replicate(&self) -> Error {
        match self {
            Error::Io { context, source } => Error::Io {
                context: context.clone(),
                source: std::io::Error::new(source.kind(), source.to_string()),
            },
            Error::Spec { field, msg } => Error::spec(field.clone(), msg.clone()),
            Error::Json { context, source } => Error::format(
                context.clone(),
                None,
                None,
                format!("invalid JSON: {source}"),
            ),
            Error::Parse {
                source_name,
                line,
                msg,
            } => Error::Parse {
                source_name: source_name.clone(),
                line: *line,
                msg: msg.clone(),
            },
            Error::Format {
                file,
                field,
                offset,
                msg,
            } => Error::Format {
                file: file.clone(),
                field: field.clone(),
                offset: *offset,
                msg: msg.clone(),
            },
            Error::Checksum {
                file,
                what,
                stored,
                computed,
            } => Error::Checksum {
                file: file.clone(),
                what: what.clone(),
                stored: *stored,
                computed: *computed,
            },
            Error::Symmetry {
                symmetry,
                error,
                tolerance,
                at,
            } => Error::Symmetry {
                symmetry: *symmetry,
                error: *error,
                tolerance: *tolerance,
                at: at.clone(),
            },
            Error::Duplicate { container, name } => Error::Duplicate {
                container: container.clone(),
                name: name.clone(),
            },
            Error::InvalidArgument { name, msg } => Error::arg(name.clone(), msg.clone()),
            Error::Encode { msg } => Error::Encode { msg: msg.clone() },
            Error::Unsupported(m) => Error::Unsupported(m.clone()),
            Error::NotFound(m) => Error::NotFound(m.clone()),
            Error::Cancelled => Error::Cancelled,
        }
    }
}

/// `msg` with every word (a run without spaces) longer than an [`excerpt`] shortened to one —
/// such a word is input echoed back: a model name, a field, a string value — and the whole
/// bounded to a few kilobytes.
fn shorten_quoted(msg: &str) -> String {
    let mut out = String::with_capacity(msg.len().min(4096));
    for (i, word) in msg.split(' ').enumerate() {
        if i > 0 {
            out.push(' ');
        }
        out.push_str(&excerpt(word));
    }
    match out.len() {
        n if n > 2048 => excerpt_to(&out, 2048).into_owned(),
        _ => out,
    }
}

/// `s` as it may appear in a message: whole when short, else its first characters and its
/// length (a 10 MB spec is not echoed whole into an error).
pub fn excerpt(s: &str) -> std::borrow::Cow<'_, str> {
    excerpt_to(s, 120)
}

fn excerpt_to(s: &str, max: usize) -> std::borrow::Cow<'_, str> {
    if s.len() <= max {
        return s.into();
    }
    let mut end = max;
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    format!("{}… ({} bytes)", &s[..end], s.len()).into()
}
