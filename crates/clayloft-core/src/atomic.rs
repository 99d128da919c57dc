//! Writing output files all-or-nothing: the data goes to a temporary file in the destination's
//! folder, which is renamed over the destination only when complete. A failed or interrupted
//! write never leaves a partial file behind.
//!
//! Permissions are those any program's new files get: read/write for all less the user's umask
//! (0644 under the usual 022), so that a printer host running as another user can read the
//! G-code. A file that is replaced keeps the permissions it had.

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
/// into place; returns what `fill` returned (a writer's figures, say).
pub fn write_atomically<T>(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<T>,
) -> Result<T, WriteError> {
    let (pending, filled) = prepare(path, fill)?;
    pending.commit()?;
    Ok(filled)
}

/// A complete temporary file waiting to be renamed over its destination: [`Pending::commit`]
/// puts it in place, dropping it deletes it. So that a file can be checked as it is written
/// (`clayloft gcode` verifies its program on the way to the disk) and appear only if it passes.
#[must_use = "dropped, the file is deleted: call commit() to put it in place"]
pub struct Pending {
    tmp: tempfile::NamedTempFile,
    path: std::path::PathBuf,
}

impl Pending {
    /// Renames the temporary file over the destination.
    pub fn commit(self) -> Result<(), WriteError> {
        let file = self.path.display().to_string();
        self.tmp.persist(&self.path).map_err(|e| WriteError {
            file,
            reason: e.error.to_string(),
        })?;
        Ok(())
    }
}

/// The first half of [`write_atomically`]: the temporary file beside `path`, filled by `fill`
/// but not yet in place.
pub fn prepare<T>(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<T>,
) -> Result<(Pending, T), WriteError> {
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
    let existing = std::fs::metadata(path).ok().map(|m| m.permissions());
    let mut builder = tempfile::Builder::new();
    builder.prefix(".clayloft-").suffix(".part");
    #[cfg(unix)]
    {
        // What `open(2)` makes of mode 0666: the umask applies (the library would otherwise
        // create its files readable by their owner only).
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder.tempfile_in(dir).map_err(|e| err(e.to_string()))?;
    if let Some(p) = existing {
        tmp.as_file()
            .set_permissions(p)
            .map_err(|e| err(e.to_string()))?;
    }
    let filled = {
        let mut w = BufWriter::with_capacity(1 << 20, tmp.as_file());
        let filled = fill(&mut w).map_err(|e| err(e.to_string()))?;
        w.flush().map_err(|e| err(e.to_string()))?;
        filled
    };
    Ok((
        Pending {
            tmp,
            path: path.to_path_buf(),
        },
        filled,
    ))
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
        let r: Result<(), _> = write_atomically(&failed, |w| {
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

    /// The umask of this process, from /proc (Linux).
    #[cfg(target_os = "linux")]
    fn umask() -> u32 {
        let status = std::fs::read_to_string("/proc/self/status").unwrap();
        let line = status.lines().find(|l| l.starts_with("Umask:")).unwrap();
        u32::from_str_radix(line["Umask:".len()..].trim(), 8).unwrap()
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn new_files_get_the_umasks_permissions_replaced_files_keep_theirs() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.gcode");
        write_atomically(&out, |w| w.write_all(b"G1 X1")).unwrap();
        let mode = std::fs::metadata(&out).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o666 & !umask(), "{mode:o}");
        std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomically(&out, |w| w.write_all(b"G1 X2")).unwrap();
        let mode = std::fs::metadata(&out).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o640);
        assert_eq!(std::fs::read(&out).unwrap(), b"G1 X2");
    }

    #[test]
    fn a_pending_file_appears_only_when_committed() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.gcode");
        std::fs::write(&out, b"old").unwrap();
        let (pending, ()) = prepare(&out, |w| w.write_all(b"new")).unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"old", "not yet in place");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
        drop(pending);
        assert_eq!(
            std::fs::read(&out).unwrap(),
            b"old",
            "dropped: the old file stays"
        );
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temporary left"
        );
        let (pending, ()) = prepare(&out, |w| w.write_all(b"new")).unwrap();
        pending.commit().unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"new");
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
