//! Error types. `InputError` is everything the user can fix in the case file or mesh:
//! the binary prints it as one line and exits with code 2, before anything is written.

use std::fmt;
use std::path::{Path, PathBuf};

/// A problem with user input: names the file, and where possible the key and the line.
#[derive(Debug, Clone, PartialEq)]
pub struct InputError {
    pub file: PathBuf,
    pub line: Option<usize>,
    pub key: Option<String>,
    pub message: String,
}

impl InputError {
    pub fn new(file: &Path, message: impl Into<String>) -> Self {
        InputError {
            file: file.to_path_buf(),
            line: None,
            key: None,
            message: message.into(),
        }
    }
    pub fn with_key(mut self, key: impl Into<String>) -> Self {
        self.key = Some(key.into());
        self
    }
    pub fn with_line(mut self, line: Option<usize>) -> Self {
        self.line = line;
        self
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        write!(f, ": ")?;
        if let Some(k) = &self.key {
            write!(f, "key '{k}': ")?;
        }
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for InputError {}

/// Why a run failed. The binary maps it to an exit code: 2 for input, 1 otherwise.
#[derive(Debug)]
pub enum RunError {
    /// The user's input is wrong: one message, exit code 2, nothing written.
    Input(InputError),
    /// PETSc reported an error.
    Petsc(crate::petsc::PetscError),
    /// Anything else (solver did not converge, output could not be written, ...).
    Failed(String),
    /// The contact algorithm did not converge (max_steps reached, or a cycle of active sets): a load step may be cut back.
    NoConvergence(String),
}

impl RunError {
    /// The process exit code that stands for this error.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Input(_) => 2,
            RunError::Petsc(_) | RunError::Failed(_) | RunError::NoConvergence(_) => 1,
        }
    }
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Input(e) => write!(f, "{e}"),
            RunError::Petsc(e) => write!(f, "{e}"),
            RunError::Failed(s) => write!(f, "{s}"),
            RunError::NoConvergence(s) => write!(f, "{s}"),
        }
    }
}

impl From<crate::petsc::PetscError> for RunError {
    fn from(e: crate::petsc::PetscError) -> Self {
        RunError::Petsc(e)
    }
}

impl From<InputError> for RunError {
    fn from(e: InputError) -> Self {
        RunError::Input(e)
    }
}
