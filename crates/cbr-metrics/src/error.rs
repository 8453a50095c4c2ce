use std::path::PathBuf;

/// Why a comparison could not be made (the CLI maps these to exit status 2).
#[derive(Debug, thiserror::Error)]
pub enum MetricsError {
    #[error("{}: {msg}", path.display())]
    Input { path: PathBuf, msg: String },
    #[error("{0}")]
    Mismatch(String),
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
}
