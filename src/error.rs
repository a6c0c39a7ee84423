//! Errors. Every error that comes from input names the file, the line where there is one,
//! and what is wrong, on one line (after pbrt-v4's `FileLoc`).

use std::fmt;
use std::path::PathBuf;

/// A place in an input file: the file, and the 1-based line and column when known.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FileLoc {
    /// The file, as the user named it (or as resolved from the scene's folder).
    pub file: PathBuf,
    /// 1-based line, when the problem has one.
    pub line: Option<usize>,
    /// 1-based column, when known.
    pub column: Option<usize>,
}

impl FileLoc {
    /// A whole file, with no line.
    pub fn file(file: impl Into<PathBuf>) -> Self {
        FileLoc { file: file.into(), line: None, column: None }
    }

    /// A line of a file.
    pub fn line(file: impl Into<PathBuf>, line: usize) -> Self {
        FileLoc { file: file.into(), line: Some(line), column: None }
    }

    /// The place of byte `offset` in `source`, the text of `file`. Lines end at `\n`,
    /// `\r\n`, or a lone `\r` (old Mac files), as an editor counts them.
    pub fn at_offset(file: impl Into<PathBuf>, source: &str, offset: usize) -> Self {
        let offset = offset.min(source.len());
        let bytes = source.as_bytes();
        let before = &bytes[..offset];
        // A line ends after a '\n', or after a '\r' that no '\n' follows.
        let ends_line = |i: usize| bytes[i] == b'\n' || (bytes[i] == b'\r' && bytes.get(i + 1) != Some(&b'\n'));
        let line = (0..offset).filter(|&i| ends_line(i)).count() + 1;
        let column = offset - (0..before.len()).rev().find(|&i| ends_line(i)).map_or(0, |p| p + 1) + 1;
        FileLoc { file: file.into(), line: Some(line), column: Some(column) }
    }
}

impl fmt::Display for FileLoc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(column) = self.column {
                write!(f, ":{column}")?;
            }
        }
        Ok(())
    }
}

/// Everything that can go wrong in umbra. Each message is one line; the types of the crates
/// umbra uses underneath do not appear in it.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Bad input at a known place: a scene or mesh that cannot be read as written.
    #[error("{loc}: {message}")]
    Load {
        /// Where.
        loc: FileLoc,
        /// What is wrong, one line.
        message: String,
    },
    /// A file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The system's reason.
        source: std::io::Error,
    },
    /// A file or folder could not be written.
    #[error("{}: could not write it: {source}", path.display())]
    Write {
        /// The file or folder.
        path: PathBuf,
        /// The system's reason.
        source: std::io::Error,
    },
    /// An image could not be encoded or written.
    #[error("{}: {source}", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// The encoder's reason.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A name the engine does not know (a method, a counter): what kind of name, the name,
    /// and every name it knows.
    #[error("unknown {kind} '{name}' (known: {})", .known.join(", "))]
    UnknownName {
        /// What kind of name ("shadow method", "counter").
        kind: String,
        /// The name as given.
        name: String,
        /// The names the engine knows.
        known: Vec<String>,
    },
    /// A setting outside what the engine accepts: which, the value as given, and what it
    /// must be.
    #[error("{setting} {value} is not {allowed}")]
    OutOfRange {
        /// The setting ("gamma", "williams: map size").
        setting: String,
        /// Its value, as written.
        value: String,
        /// What it must be ("in 0.1..=10").
        allowed: String,
    },
    /// A scene built in code that the loader would refuse: the part that is wrong ("camera",
    /// "light 2", "material 'red'", "object 3") and what is wrong with it.
    #[error("{part}: {problem}")]
    InvalidScene {
        /// The part of the scene.
        part: String,
        /// What is wrong, one line.
        problem: String,
    },
    /// A request that the engine cannot carry out and that no other variant describes (a
    /// file the command line will not overwrite, a malformed request to explore's page).
    #[error("{0}")]
    InvalidOption(String),
    /// Work that would need more memory than the engine's budget (`budget`, bytes): nothing
    /// was allocated.
    #[error("{what} would need about {:.1} GiB, more than umbra's memory budget of {:.0} GiB", gib(.bytes), gib(.budget))]
    OverBudget {
        /// What would have been made.
        what: String,
        /// The bytes it would need.
        bytes: u64,
        /// The budget.
        budget: u64,
    },
    /// A method that does not apply to this scene: the stage, and what it needs that the
    /// scene lacks (planar shadows with no receiver).
    #[error("{stage}: {why}")]
    NotApplicable {
        /// The stage's name.
        stage: String,
        /// Why it does not apply, one line.
        why: String,
    },
    /// A stage failed where it should not have: a defect in umbra, not in the input.
    #[error("internal error (a defect in umbra; please report it): {0}")]
    Internal(String),
}

/// Bytes in GiB, for messages.
fn gib(bytes: &u64) -> f64 {
    *bytes as f64 / (1u64 << 30) as f64
}

impl Error {
    /// An input error at `loc`.
    pub fn input(loc: FileLoc, message: impl Into<String>) -> Self {
        Error::Load { loc, message: message.into() }
    }

    /// A setting out of range (see [`Error::OutOfRange`]).
    pub(crate) fn out_of_range(
        setting: impl Into<String>,
        value: impl fmt::Display,
        allowed: impl Into<String>,
    ) -> Self {
        Error::OutOfRange { setting: setting.into(), value: value.to_string(), allowed: allowed.into() }
    }

    /// A scene part that is wrong (see [`Error::InvalidScene`]).
    pub(crate) fn scene(part: impl Into<String>, problem: impl Into<String>) -> Self {
        Error::InvalidScene { part: part.into(), problem: problem.into() }
    }
}

/// A number for a message: plain when it reads well, in scientific notation when it is very
/// large or very small.
pub(crate) fn num(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && !(1e-4..1e7).contains(&a) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// `Result` with umbra's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Finds the item of `all` whose `name` is `s`; otherwise an error naming what was asked for
/// and listing the known names (for every method chosen by name on the command line).
pub(crate) fn parse_named<'a, T>(
    s: &str,
    all: &'a [T],
    name: impl Fn(&T) -> &'static str,
    what: &str,
) -> Result<&'a T> {
    all.iter().find(|m| name(m) == s).ok_or_else(|| Error::UnknownName {
        kind: what.into(),
        name: s.into(),
        known: all.iter().map(|m| name(m).to_string()).collect(),
    })
}

/// `FromStr` and `Display` by name for an enum of methods with `ALL` and `name()`: parsing
/// finds the item named (and lists the known names when none is), showing writes the name.
macro_rules! named {
    ($t:ty, $what:literal) => {
        impl std::str::FromStr for $t {
            type Err = crate::error::Error;
            fn from_str(s: &str) -> crate::error::Result<Self> {
                crate::error::parse_named(s, &Self::ALL, |m| m.name(), $what).cloned()
            }
        }

        impl std::fmt::Display for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}
pub(crate) use named;
