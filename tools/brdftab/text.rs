//! Lines of numbers, as the CLI's `eval` and `pdf` read them from stdin.
//!
//! The format is shared by every host that pipes direction pairs through text: one record per
//! line, numbers separated by white space, blank lines and lines that start with `#` skipped (a
//! `#` after a record's numbers is not a comment: that line is an error). Errors name the input
//! and the 1-based line.

use std::io::BufRead;

use glam::DVec3;

use brdftab::{Error, Result};

/// Writes `text` to stdout and flushes; a failed write is an error, not a panic (`println!`
/// panics on a closed pipe: `brdftab models | head -1`). `main` ends quietly when the error
/// is a closed pipe.
pub fn print_out(text: &str) -> brdftab::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| brdftab::Error::io("stdout", e))
}

/// `println!` through [`print_out`]: evaluates to its `Result` (use `?`).
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => {
        $crate::text::print_out(&format!("{}\n", format_args!($($t)*)))
    };
}

/// Parses a line of exactly `N` numbers; `None` for blank and `#` lines. `name` and `lineno`
/// go into the error.
pub fn parse_numbers<const N: usize>(
    line: &str,
    name: &str,
    lineno: usize,
) -> Result<Option<[f64; N]>> {
    let err = |msg: String| Error::Parse {
        source_name: name.into(),
        line: lineno,
        msg,
    };
    let t = line.trim();
    if t.is_empty() || t.starts_with('#') {
        return Ok(None);
    }
    let mut v = [0.0; N];
    let mut k = 0;
    for tok in t.split_whitespace() {
        if k == N {
            return Err(err(format!("expected {N} numbers, got more")));
        }
        v[k] = tok.parse().map_err(|_| {
            err(format!(
                "`{}` is not a number",
                brdftab::error::excerpt(tok)
            ))
        })?;
        k += 1;
    }
    if k < N {
        return Err(err(format!("expected {N} numbers, got {k}")));
    }
    Ok(Some(v))
}

/// Calls `f(wi, wo)` for every `wix wiy wiz wox woy woz` line of `input`; stops at the first
/// error (of parsing, reading, or of `f`).
pub fn for_each_pair(
    input: impl BufRead,
    name: &str,
    mut f: impl FnMut(DVec3, DVec3) -> Result<()>,
) -> Result<()> {
    for (i, line) in input.lines().enumerate() {
        let line = line.map_err(|e| Error::io(name, e))?;
        if let Some(v) = parse_numbers::<6>(&line, name, i + 1)? {
            f(DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_skip_comments_and_errors_name_the_line() {
        let mut seen = Vec::new();
        for_each_pair(
            "# c\n\n0 0 1 0 0 1\n1 0 1 0 1 1\n".as_bytes(),
            "in",
            |a, b| {
                seen.push((a, b));
                Ok(())
            },
        )
        .unwrap();
        assert_eq!(seen.len(), 2);
        assert_eq!(seen[1].0, DVec3::new(1.0, 0.0, 1.0));
        let e = for_each_pair("0 0 1\n".as_bytes(), "in", |_, _| Ok(())).unwrap_err();
        assert!(matches!(e, Error::Parse { line: 1, .. }), "{e}");
        let e = parse_numbers::<2>("1 x", "in", 7).unwrap_err();
        assert!(e.to_string().contains("line 7") && e.to_string().contains("`x`"));
        assert!(parse_numbers::<2>("1 2 3", "in", 1).is_err());
    }
}
