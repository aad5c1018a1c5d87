//! Diagnostics of the Mitsuba loader: plain warnings (an approximation the renderer makes, always
//! allowed) and "strict" findings (what Mitsuba itself rejects, or a plugin the renderer does not
//! implement): errors by default, warnings saying what was done instead under `lenient`.

use std::fmt::Display;

use crate::error::{ErrorKind, Location, SceneError, Warning};

pub(crate) struct Diag {
    pub lenient: bool,
    pub warnings: Vec<Warning>,
}

impl Diag {
    pub fn new(lenient: bool) -> Self {
        Diag {
            lenient,
            warnings: Vec::new(),
        }
    }

    /// An approximation: always a warning.
    pub fn warn(&mut self, loc: &Location, msg: impl Into<String>) {
        self.warnings.push(Warning::new(loc.clone(), msg));
    }

    /// `what` cannot be rendered as Mitsuba would (unknown or unsupported plugin, element or
    /// property). Strict: an error naming the place and the `--lenient` way out. Lenient: a
    /// warning saying what was done instead (`instead`: "skipped", "replaced by diffuse 0.5"...).
    pub fn unsupported(
        &mut self,
        loc: &Location,
        what: impl Display,
        instead: impl Display,
    ) -> Result<(), SceneError> {
        if self.lenient {
            self.warn(loc, format!("{what}; {instead}"));
            Ok(())
        } else {
            Err(SceneError::new(
                ErrorKind::Unsupported,
                loc.clone(),
                format!("{what}; use --lenient to render without it (--lenient: {instead})"),
            ))
        }
    }
}

pub(crate) fn err(loc: &Location, kind: ErrorKind, msg: impl Into<String>) -> SceneError {
    SceneError::new(kind, loc.clone(), msg)
}

pub(crate) fn syntax(loc: &Location, msg: impl Into<String>) -> SceneError {
    err(loc, ErrorKind::Syntax, msg)
}
