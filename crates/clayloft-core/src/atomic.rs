//! Writing output files all-or-nothing: the data goes to a temporary file in the destination's
//! folder, which is renamed over the destination only when complete. A failed or interrupted
//! write never leaves a partial file behind.

use std::io::{BufWriter, Write};
use std::path::Path;

/// Why an output file could not be written, as one sentence.
#[derive(Debug, thiserror::Error)]
#[error("{file}: cannot write: {reason}")]
pub struct WriteError {
    pub file: String,
    pub reason: String,
}

/// Writes `path` by calling `fill` with a buffered writer on a temporary file, then renames it
/// into place.
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), WriteError> {
    let err = |reason: String| WriteError {
        file: path.display().to_string(),
        reason,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(err(format!("the folder {} does not exist", dir.display())));
    }
    if path.is_dir() {
        return Err(err("it is a folder".into()));
    }
    let tmp = tempfile::Builder::new()
        .prefix(".clayloft-")
        .suffix(".part")
        .tempfile_in(dir)
        .map_err(|e| err(e.to_string()))?;
    {
        let mut w = BufWriter::with_capacity(1 << 20, tmp.as_file());
        fill(&mut w).map_err(|e| err(e.to_string()))?;
        w.flush().map_err(|e| err(e.to_string()))?;
    }
    tmp.persist(path).map_err(|e| err(e.error.to_string()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn complete_file_or_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.txt");
        write_atomically(&out, |w| w.write_all(b"hello")).unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"hello");
        let failed = dir.path().join("b.txt");
        let r = write_atomically(&failed, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        });
        assert!(r.is_err());
        assert!(!failed.exists());
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temporary left"
        );
    }

    #[test]
    fn missing_folder_is_reported() {
        let e = write_atomically(Path::new("/no/such/folder/x.gcode"), |_| Ok(())).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
    }
}
