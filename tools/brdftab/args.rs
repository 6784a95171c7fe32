//! The CLI's arguments as the user typed them: which subcommand ran, and a library argument
//! error's field (`max_depth`) named as the flag (`--max-depth`) — the library's errors name
//! settings, never flags (DESIGN: one request layer), so the CLI translates them.

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
