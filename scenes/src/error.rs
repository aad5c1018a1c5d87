//! Diagnostics shared by every reader (Mitsuba XML, OBJ, PLY) on the way from a scene file to a
//! [`crate::Scene`]. An error stops the load; a warning is collected and returned beside the scene
//! so that callers (CLI, renderer) decide how loudly to print it. Both name the file and the place
//! in it, because a scene that "renders wrong" is far easier to fix when the loader said where.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in an input file something happened.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    pub file: PathBuf,
    pub position: Position,
}

/// The place inside [`Location::file`]. Text formats report lines; binary PLY has none, so it reports
/// the byte offset and which element was being read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Position {
    /// The whole file (e.g. it could not be opened).
    File,
    /// 1-based line number.
    Line(u32),
    /// Byte offset in a binary file, with the element name and the entry's index within it.
    Byte {
        offset: u64,
        element: String,
        index: u64,
    },
}

impl Location {
    pub fn file(file: impl Into<PathBuf>) -> Self {
        Location {
            file: file.into(),
            position: Position::File,
        }
    }

    pub fn line(file: impl Into<PathBuf>, line: u32) -> Self {
        Location {
            file: file.into(),
            position: Position::Line(line),
        }
    }

    pub fn byte(file: impl Into<PathBuf>, offset: u64, element: &str, index: u64) -> Self {
        Location {
            file: file.into(),
            position: Position::Byte {
                offset,
                element: element.to_string(),
                index,
            },
        }
    }

    /// The line number, when the position is a line.
    pub fn line_number(&self) -> Option<u32> {
        match self.position {
            Position::Line(l) => Some(l),
            _ => None,
        }
    }

    pub fn path(&self) -> &Path {
        &self.file
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let file = self.file.display();
        match &self.position {
            Position::File => write!(f, "{file}"),
            Position::Line(l) => write!(f, "{file}:{l}"),
            Position::Byte {
                offset,
                element,
                index,
            } => {
                write!(f, "{file}: byte {offset} (element '{element}' #{index})")
            }
        }
    }
}

/// What went wrong, so that callers and tests can tell failures apart without parsing messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// The file could not be read (missing, permissions...).
    Io,
    /// Not well-formed XML.
    Xml,
    /// Well-formed but not a valid scene/mesh description: bad number, missing attribute, wrong
    /// element, undefined `$parameter`, bad PLY header...
    Syntax,
    /// A face refers to a vertex that does not exist.
    IndexOutOfRange,
    /// A vertex coordinate or normal is NaN or infinite.
    NonFinite,
    /// A binary file ended before the data its header announced.
    Truncated,
    /// A feature the renderer cannot honour, or input Mitsuba itself rejects (unknown plugin,
    /// element, attribute or parameter): an error unless the scene is loaded leniently.
    Unsupported,
    /// An `<include>` or `<ref>` chain that leads back to where it started.
    Cycle,
}

/// A failed load. `context` carries the outer places that led here (e.g. the `<shape>` element
/// that named a broken OBJ file), innermost last-but-one, so the message reads outside-in.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{location}: error: {message}{}", ContextDisplay(.context))]
pub struct SceneError {
    pub kind: ErrorKind,
    pub location: Location,
    pub message: String,
    pub context: Vec<Location>,
}

struct ContextDisplay<'a>(&'a [Location]);

impl fmt::Display for ContextDisplay<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for l in self.0.iter().rev() {
            write!(f, "\n  referenced from {l}")?;
        }
        Ok(())
    }
}

impl SceneError {
    pub fn new(kind: ErrorKind, location: Location, message: impl Into<String>) -> Self {
        SceneError {
            kind,
            location,
            message: message.into(),
            context: Vec::new(),
        }
    }

    /// Records the outer place (e.g. the XML element) that caused this inner failure.
    pub fn referenced_from(mut self, outer: Location) -> Self {
        self.context.push(outer);
        self
    }
}

/// Something the loader ignored or approximated; the scene is still usable.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    pub location: Location,
    pub message: String,
}

impl Warning {
    pub fn new(location: Location, message: impl Into<String>) -> Self {
        Warning {
            location,
            message: message.into(),
        }
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: warning: {}", self.location, self.message)
    }
}
