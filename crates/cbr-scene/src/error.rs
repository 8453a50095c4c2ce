use std::path::{Path, PathBuf};

/// A scene that cannot be loaded. Every variant names the file, and the line where there is one.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{}:{line}: {msg}", file.display())]
    Syntax {
        file: PathBuf,
        line: usize,
        msg: String,
    },
    #[error("{}: {msg}", file.display())]
    File { file: PathBuf, msg: String },
    #[error("{0}")]
    Invalid(String),
}

impl SceneError {
    pub fn syntax(file: &Path, line: usize, msg: impl Into<String>) -> Self {
        SceneError::Syntax {
            file: file.to_path_buf(),
            line,
            msg: msg.into(),
        }
    }
    pub fn file(file: &Path, msg: impl Into<String>) -> Self {
        SceneError::File {
            file: file.to_path_buf(),
            msg: msg.into(),
        }
    }
}

pub type Result<T, E = SceneError> = std::result::Result<T, E>;
