//! The CLI's arguments as the user typed them: which subcommand ran, and a library argument
//! error's field (`max_depth`) named as the flag (`--max-depth`) — the library's errors name
//! settings, never flags (DESIGN: one request layer), so the CLI translates them.

use std::ffi::{OsStr, OsString};
use std::path::Path;
use std::process::ExitCode;

use clap::{ArgMatches, Command};

/// The names of the subcommand that ran, outermost first (`["db", "add"]`).
pub fn subcommand_path(m: &ArgMatches) -> Vec<String> {
    let mut path = Vec::new();
    let mut m = m;
    while let Some((name, sub)) = m.subcommand() {
        path.push(name.to_owned());
        m = sub;
    }
    path
}

/// An argument error of the library names a request field (`max_depth`) or a value
/// (`source`); when that is the id of an argument of the subcommand that ran, it is named as
/// the user typed it: its flag (`--max-depth`) or its value name (`SOURCE`). Other names pass
/// unchanged.
pub fn as_typed(e: brdftab::Error, cmd: &Command, path: &[String]) -> brdftab::Error {
    let brdftab::Error::InvalidArgument { name, msg } = e else {
        return e;
    };
    let mut sub = cmd;
    for p in path {
        match sub.find_subcommand(p) {
            Some(s) => sub = s,
            None => return brdftab::Error::InvalidArgument { name, msg },
        }
    }
    let name = match sub.get_arguments().find(|a| a.get_id() == name.as_str()) {
        Some(a) => match (a.get_long(), a.get_value_names()) {
            (Some(long), _) => format!("--{long}"),
            (None, Some([v, ..])) => v.to_string(),
            (None, _) => a.get_id().as_str().to_uppercase(),
        },
        None => name,
    };
    brdftab::Error::InvalidArgument { name, msg }
}

/// `--help` and `--version` print to stdout and succeed; every usage error prints one line
/// `error: ...` on stderr and exits 1, like every other error ([`one_line`]).
pub fn clap_exit(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            // Help into a closed pipe (`brdftab --help | head -1`) is still a success.
            let _ = crate::text::print_out(&e.to_string());
            ExitCode::SUCCESS
        }
        // clap's message is the whole help of the command that lacks its subcommand.
        ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let help = e.to_string();
            let usage = help.lines().find(|l| l.starts_with("Usage:"));
            let usage = usage.map(|u| u.replacen("Usage:", "; usage:", 1));
            eprintln!(
                "error: a subcommand is required{} (see --help)",
                usage.unwrap_or_default()
            );
            ExitCode::from(1)
        }
        _ => {
            eprintln!("{}", one_line(&e.to_string()));
            ExitCode::from(1)
        }
    }
}

/// A clap usage error (`error: MSG`, then indented lines — the missing arguments, a tip —,
/// the usage line and a pointer to `--help`, with blank lines between) as the one line
/// `error: MSG ...; tip: ...; usage: ...` every error of the CLI is: a script reads the first
/// line of stderr, and a user still gets the tip and the usage.
pub fn one_line(msg: &str) -> String {
    let mut out = String::from("error:");
    let msg = msg.trim_start().strip_prefix("error:").unwrap_or(msg);
    for line in msg.lines().map(str::trim).filter(|l| !l.is_empty()) {
        if line.starts_with("For more information") {
            continue;
        }
        let (sep, line) = match line.strip_prefix("Usage:") {
            Some(u) => ("; usage:", u),
            None if line.starts_with("tip:") => (";", line),
            None => ("", line),
        };
        out.push_str(sep);
        out.push(' ');
        out.push_str(line.trim());
    }
    out
}

/// A path or SOURCE argument as the user typed it: the bytes of the command line (on Linux a
/// file name need not be UTF-8), passed to the library as an `OsStr`/`Path` and shown with
/// U+FFFD for the bytes that are not UTF-8 (`Display`). Its own type, rather than `OsString`,
/// so that a command prints it as it printed a `String` argument.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PathArg(pub OsString);

impl From<OsString> for PathArg {
    fn from(s: OsString) -> PathArg {
        PathArg(s)
    }
}

impl std::fmt::Display for PathArg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0.to_string_lossy())
    }
}

impl std::ops::Deref for PathArg {
    type Target = Path;

    fn deref(&self) -> &Path {
        Path::new(&self.0)
    }
}

impl AsRef<OsStr> for PathArg {
    fn as_ref(&self) -> &OsStr {
        &self.0
    }
}

impl AsRef<Path> for PathArg {
    fn as_ref(&self) -> &Path {
        Path::new(&self.0)
    }
}

#[cfg(test)]
mod tests {
    #[cfg(unix)]
    #[test]
    fn a_path_argument_keeps_its_bytes_and_shows_them_lossily() {
        use std::os::unix::ffi::OsStringExt;
        let p = super::PathArg::from(std::ffi::OsString::from_vec(b"caf\xe9.btdb".to_vec()));
        assert_eq!(p.0.as_encoded_bytes(), b"caf\xe9.btdb");
        assert_eq!(p.to_string(), "caf\u{FFFD}.btdb");
        assert_eq!(p.extension().and_then(|e| e.to_str()), Some("btdb"));
    }

    #[test]
    fn usage_errors_are_one_line() {
        let msg = "error: unexpected argument '-o' found\n\n  tip: to pass '-o' as a value, use \
                   '-- -o'\n\nUsage: brdftab export [OPTIONS] <SOURCE>\n\nFor more information, \
                   try '--help'.\n";
        assert_eq!(
            super::one_line(msg),
            "error: unexpected argument '-o' found; tip: to pass '-o' as a value, use '-- -o'; \
             usage: brdftab export [OPTIONS] <SOURCE>"
        );
        let msg = "error: the following required arguments were not provided:\n  --name <NAME>\n\n\
                   Usage: brdftab db add --name <NAME> <DB> <SOURCE>\n";
        assert_eq!(
            super::one_line(msg),
            "error: the following required arguments were not provided: --name <NAME>; usage: \
             brdftab db add --name <NAME> <DB> <SOURCE>"
        );
    }
}
