//! Errors, one enum per concern. Every message says what to fix.

use std::fmt;

/// A problem in an input file (scene, hardware config, grid) or a CLI value:
/// names the file, the line and column when known, the field and the allowed range.
#[derive(Debug, Clone, PartialEq)]
pub struct FileError {
    /// The file name as the user gave it (or `<embedded default scene>`, `--flag`).
    pub file: String,
    /// 1-based line, when the field could be located in the text.
    pub line: Option<usize>,
    /// 1-based column.
    pub col: Option<usize>,
    /// Dotted path of the field (`camera.focal_length`, `object[2].radius`).
    pub field: String,
    /// What is wrong and what is allowed.
    pub msg: String,
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
            if let Some(c) = self.col {
                write!(f, ":{c}")?;
            }
        }
        if self.field.is_empty() {
            write!(f, ": {}", self.msg)
        } else {
            write!(f, ": field `{}`: {}", self.field, self.msg)
        }
    }
}

impl std::error::Error for FileError {}

/// Every error the library returns.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad input file or argument.
    #[error("{0}")]
    File(#[from] FileError),
    /// A signal overflowed while its overflow mode is `ERROR`.
    #[error(
        "overflow in signal `{signal}` (format {format}, overflow mode ERROR): value {value} is outside [{min}, {max}]; widen the format or choose SAT or WRAP"
    )]
    Overflow {
        /// Name of the signal (`accumulate.frame`).
        signal: String,
        /// Its format, e.g. `UQ12.0`.
        format: String,
        /// The value that did not fit, in the format's LSBs.
        value: i128,
        /// Smallest code.
        min: i64,
        /// Largest code.
        max: i64,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// Encoding an image failed.
    #[error("{path}: cannot write image: {msg}")]
    Image {
        /// The path.
        path: String,
        /// The cause.
        msg: String,
    },
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, Error>;
