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

/// `eprintln!` as an expression of type `Result<()>`, for the report of a command whose product
/// is a file (DESIGN.md, "stdout and stderr"): where `outln!` would print the product itself.
#[macro_export]
macro_rules! errln {
    ($($t:tt)*) => {{
        eprintln!($($t)*);
        Ok::<(), brdftab::Error>(())
    }};
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

/// A direction typed as one argument, `X,Y,Z` (need not be normalized; `sample --wo`): three
/// finite numbers, not all zero. A NaN, infinite or zero vector is an error naming `flag` — it
/// was taken, and every draw for it silently printed nothing.
pub fn parse_direction(s: &str, flag: &str) -> Result<DVec3> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| Error::arg(flag, format!("`{s}`: expected X,Y,Z")))?;
    let [x, y, z] = v[..] else {
        return Err(Error::arg(flag, format!("`{s}`: expected 3 numbers X,Y,Z")));
    };
    let d = DVec3::new(x, y, z);
    if !d.is_finite() || d == DVec3::ZERO {
        return Err(Error::arg(
            flag,
            format!("`{s}` is not a direction: three finite numbers, not all zero"),
        ));
    }
    Ok(d)
}

/// `x` with `prec` decimals, or `unknown` where it is NaN: the CPU-time figures of `bench` are NaN
/// where no CPU clock can be read (`/proc/.../schedstat` reads 0 in some containers), and
/// printed `NaN ns CPU time` as if it were a measurement.
pub fn or_unknown(x: f64, prec: usize) -> String {
    if x.is_nan() {
        "unknown".into()
    } else {
        format!("{x:.prec$}")
    }
}

/// `x` as typed (its shortest round-trip form), in exponent form when the plain form runs to
/// more than 16 characters (`1e-300`, not `0.000…1` with 300 zeros; `1e300`).
pub fn shortest(x: f64) -> String {
    let plain = x.to_string();
    if plain.len() > 16 {
        format!("{x:e}")
    } else {
        plain
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unknown_figure_is_not_printed_as_nan() {
        assert_eq!(or_unknown(f64::NAN, 1), "unknown");
        assert_eq!(or_unknown(f64::NAN / 1e6, 2), "unknown");
        assert_eq!(or_unknown(12.345, 1), "12.3");
        assert_eq!(or_unknown(224.774, 2), "224.77");
    }

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

    #[test]
    fn a_direction_argument_is_finite_and_not_zero() {
        assert_eq!(
            parse_direction(" 0.3, 0,1", "--wo").unwrap(),
            DVec3::new(0.3, 0.0, 1.0)
        );
        // Not normalized, so any finite scale (the sampler normalizes it).
        assert!(parse_direction("1e300,0,1e300", "--wo").is_ok());
        for bad in ["nan,0,1", "0,0,0", "inf,0,1", "0,-0,0", "1,2", "a,b,c"] {
            let e = parse_direction(bad, "--wo").unwrap_err().to_string();
            assert!(e.contains("--wo") && e.contains(bad), "{bad}: {e}");
        }
    }
}
