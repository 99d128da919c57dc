//! Writing output files all-or-nothing: the data goes to a temporary file in the destination's
//! folder, which is renamed over the destination only when complete. A failed or interrupted
//! write never leaves a partial file behind.
//!
//! Permissions are those any program's new files get: read/write for all less the user's umask
//! (0644 under the usual 022), so that a printer host running as another user can read the
//! G-code. A file that is replaced keeps the permissions it had.
//!
//! A symbolic link is followed: the file it points to is replaced and the link stays. A
//! destination that exists and is not a file (a terminal, a pipe, `/dev/stdout`, a device) is
//! never renamed over: the data waits in a temporary file of the system's temporary folder and
//! is written into the destination when complete.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

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
    let (pending, filled) = prepare(path, |w| fill(w))?;
    drop(pending.commit()?);
    Ok(filled)
}

/// A complete temporary file waiting to go to its destination: [`Pending::commit`] puts it in
/// place, dropping it deletes it. So that a file can be checked as it is written (`clayloft
/// gcode` verifies its program on the way to the disk) and appear only if it passes.
#[must_use = "dropped, the file is deleted: call commit() to put it in place"]
pub struct Pending {
    tmp: tempfile::NamedTempFile,
    /// The file the destination's path names (a link followed) and whether it is renamed over.
    target: PathBuf,
    rename: bool,
    /// The path as given, for messages.
    path: PathBuf,
}

/// The file a commit replaced, kept open: the system frees a replaced file's data when its
/// last name and descriptor are gone (2–3 ms for the benchmark vase's 8 MB of G-code here,
/// mostly waiting for the disk), so this frees it when dropped, where it costs the caller
/// nothing (`clayloft gcode` drops it on a thread of its own while both cores judge the print).
#[must_use = "dropped at once, the old file's data is freed here"]
pub struct Replaced(#[allow(dead_code)] Option<std::fs::File>);

/// A thread that drops what it is given ([`Replaced`] files, whose freeing waits for the disk),
/// started ahead of the moment it is needed. A thread started at that moment waited for a core
/// while both were busy (`clayloft gcode` judging the print): the old file's freeing began only
/// once the judging was done, and the command ended 1.5–2 ms later than with a thread already
/// started and waiting, which the system runs as soon as it is woken (measured on the benchmark
/// vase).
pub struct FreeingThread<T: Send + 'static> {
    to_free: Option<std::sync::mpsc::Sender<T>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl<T: Send + 'static> FreeingThread<T> {
    /// Starts the thread (where none can be started, [`FreeingThread::free`] drops here).
    pub fn start() -> Self {
        let (to_free, given) = std::sync::mpsc::channel::<T>();
        let thread = std::thread::Builder::new()
            .name("clayloft freeing".into())
            .spawn(move || given.into_iter().for_each(drop))
            .ok();
        Self {
            to_free: thread.is_some().then_some(to_free),
            thread,
        }
    }

    /// Drops `value` on the thread (here, where it could not be started).
    pub fn free(&self, value: T) {
        match &self.to_free {
            Some(to_free) => {
                if let Err(unsent) = to_free.send(value) {
                    drop(unsent.0);
                }
            }
            None => drop(value),
        }
    }

    /// Waits until everything given is dropped (as dropping the `FreeingThread` does).
    pub fn finish(self) {}
}

impl<T: Send + 'static> Drop for FreeingThread<T> {
    fn drop(&mut self) {
        // The thread ends once the channel is closed and it has dropped all it was given.
        drop(self.to_free.take());
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl Pending {
    /// Renames the temporary file over the destination, or, for a destination that is not a
    /// file, writes the data into it. Gives the file replaced, if any (see [`Replaced`]).
    pub fn commit(self) -> Result<Replaced, WriteError> {
        let err = |reason: String| WriteError {
            file: self.path.display().to_string(),
            reason,
        };
        if self.rename {
            // Open (if it can be read) before the rename unlinks it.
            let old = std::fs::File::open(&self.target).ok();
            return self
                .tmp
                .persist(&self.target)
                .map(|_| Replaced(old))
                .map_err(|e| err(e.error.to_string()));
        }
        let mut data = self.tmp.reopen().map_err(|e| err(e.to_string()))?;
        let mut out = std::fs::OpenOptions::new()
            .write(true)
            .open(&self.target)
            .map_err(|e| err(e.to_string()))?;
        std::io::copy(&mut data, &mut out)
            .and_then(|_| out.flush())
            .map(|_| Replaced(None))
            .map_err(|e| err(e.to_string()))
    }
}

/// Where the data for `path` goes: the file to rename the finished data over (a symbolic link
/// followed to the file it names, so the link stays), or, for anything that exists and is not
/// a file (a terminal, a pipe, a device, `/dev/stdout`, which names the process's own output
/// through a link of the system's), `path` itself, written into and never renamed over.
fn destination(path: &Path) -> (PathBuf, bool) {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => (std::fs::canonicalize(path).unwrap_or(path.into()), true),
        Ok(_) => (path.into(), false),
        // Nothing there yet; a link to a file not made yet makes that file.
        Err(_) => match std::fs::read_link(path) {
            Ok(to) => (path.parent().unwrap_or(Path::new("")).join(to), true),
            Err(_) => (path.into(), true),
        },
    }
}

/// The writer [`prepare`] fills a temporary file with: buffered, and with the file at hand for
/// [`start_writeback`] of what is written already.
pub struct Output<'a> {
    writer: BufWriter<&'a std::fs::File>,
}

impl<'a> Output<'a> {
    /// The file written, for [`start_writeback`] and [`write_at`] (from other threads, say,
    /// while this writer waits; [`Write::flush`] it first, so that the file holds what was
    /// written before).
    pub fn file(&self) -> &'a std::fs::File {
        self.writer.get_ref()
    }

    /// Goes on writing at byte `offset` of the file (after text put in place up to there with
    /// [`write_at`]).
    pub fn continue_at(&mut self, offset: u64) -> std::io::Result<()> {
        use std::io::Seek;
        self.writer
            .seek(std::io::SeekFrom::Start(offset))
            .map(|_| ())
    }
}

/// Writes `bytes` at byte `offset` of `file`, whatever the file's own position: threads may
/// each write their parts of a file at once.
#[cfg(unix)]
pub fn write_at(file: &std::fs::File, bytes: &[u8], offset: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::write_all_at(file, bytes, offset)
}

/// Writes `bytes` at byte `offset` of `file` (Windows also moves the file's position).
#[cfg(windows)]
pub fn write_at(file: &std::fs::File, mut bytes: &[u8], mut offset: u64) -> std::io::Result<()> {
    while !bytes.is_empty() {
        match std::os::windows::fs::FileExt::seek_write(file, bytes, offset) {
            Ok(0) => return Err(std::io::ErrorKind::WriteZero.into()),
            Ok(n) => {
                bytes = &bytes[n..];
                offset += n as u64;
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

impl Write for Output<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.writer.write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.writer.write_all(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.writer.flush()
    }
}

/// The first half of [`write_atomically`]: the temporary file, filled by `fill` but not yet
/// in place.
pub fn prepare<T>(
    path: &Path,
    fill: impl FnOnce(&mut Output<'_>) -> std::io::Result<T>,
) -> Result<(Pending, T), WriteError> {
    let err = |reason: String| WriteError {
        file: path.display().to_string(),
        reason,
    };
    let (target, rename) = destination(path);
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(err(format!("the folder {} does not exist", dir.display())));
    }
    let existing = std::fs::metadata(&target).ok();
    if existing.as_ref().is_some_and(|m| m.is_dir()) {
        return Err(err("it is a folder".into()));
    }
    let mut builder = tempfile::Builder::new();
    builder.prefix(".clayloft-").suffix(".part");
    #[cfg(unix)]
    {
        // What `open(2)` makes of mode 0666: the umask applies (the library would otherwise
        // create its files readable by their owner only).
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = if rename {
        builder.tempfile_in(dir)
    } else {
        builder.tempfile()
    }
    .map_err(|e| err(e.to_string()))?;
    if let Some(m) = existing.filter(|_| rename) {
        tmp.as_file()
            .set_permissions(m.permissions())
            .map_err(|e| err(e.to_string()))?;
    }
    let filled = {
        // Small writes (a header's lines, an STL's triangles) are gathered; a write of at least
        // the buffer's size (a G-code body's chunk of 150 kB) goes to the file as it is, not
        // copied into the buffer first (8 MB copied for the benchmark vase with a 1 MB buffer).
        let mut w = Output {
            writer: BufWriter::with_capacity(WRITE_BUFFER, tmp.as_file()),
        };
        let filled = fill(&mut w).map_err(|e| err(e.to_string()))?;
        w.flush().map_err(|e| err(e.to_string()))?;
        filled
    };
    // What `fill` did not start already (to the end of the file).
    start_writeback(tmp.as_file(), 0..u64::MAX);
    Ok((
        Pending {
            tmp,
            target,
            rename,
            path: path.to_path_buf(),
        },
        filled,
    ))
}

/// The buffer of an atomic write, bytes.
const WRITE_BUFFER: usize = 64 << 10;

/// Starts the data of `file` in `bytes` (to the end of the file, for an end past it) for the
/// disk without waiting for it. A rename that replaces a file on ext4 writes the new file's
/// data out first (`auto_da_alloc`, which keeps a crash from leaving it empty): 4–5 ms for the
/// benchmark vase's 8 MB inside `Pending::commit`; started once the file is written, the rename
/// takes about 2 ms (the old file's pages freed), and the start itself 0.6–1.5 ms on one core.
/// Started part by part as they are written, on a core with time to spare (`clayloft gcode`
/// starts each round of its body while the next is written), it leaves little to start at the
/// end. A hint only: data not written yet, or already started, is passed over, and if the call
/// fails the rename does the writing as before.
#[cfg(target_os = "linux")]
pub fn start_writeback(file: &std::fs::File, bytes: std::ops::Range<u64>) {
    use std::os::fd::AsRawFd;
    let Ok(from) = i64::try_from(bytes.start) else {
        return;
    };
    // A count of 0 means "to the end of the file" to the call.
    let count = match i64::try_from(bytes.end - bytes.start.min(bytes.end)) {
        Ok(0) => return,
        Ok(count) => count,
        Err(_) => 0,
    };
    // SAFETY: the descriptor is open (borrowed from `file`) and the call only queues writes.
    unsafe {
        libc::sync_file_range(file.as_raw_fd(), from, count, libc::SYNC_FILE_RANGE_WRITE);
    }
}

/// Elsewhere nothing is started early.
#[cfg(not(target_os = "linux"))]
pub fn start_writeback(_: &std::fs::File, _: std::ops::Range<u64>) {}

#[cfg(test)]
mod tests {
    use super::*;

    /// What a freeing thread is given is dropped on that thread (not the caller's), in order,
    /// all of it by the time `finish` returns.
    #[test]
    fn a_freeing_thread_drops_what_it_is_given_before_finish_returns() {
        use std::sync::{Arc, Mutex};
        struct Noted(usize, Arc<Mutex<Vec<(usize, std::thread::ThreadId)>>>);
        impl Drop for Noted {
            fn drop(&mut self) {
                self.1
                    .lock()
                    .unwrap()
                    .push((self.0, std::thread::current().id()));
            }
        }
        let dropped = Arc::new(Mutex::new(Vec::new()));
        let freeing = FreeingThread::start();
        for k in 0..3 {
            freeing.free(Noted(k, Arc::clone(&dropped)));
        }
        freeing.finish();
        let dropped = std::mem::take(&mut *dropped.lock().unwrap());
        assert_eq!(dropped.iter().map(|d| d.0).collect::<Vec<_>>(), [0, 1, 2]);
        let here = std::thread::current().id();
        assert!(dropped.iter().all(|d| d.1 == dropped[0].1 && d.1 != here));
    }

    /// A file replaced and given to a freeing thread is closed by the time `finish` returns.
    #[cfg(unix)]
    #[test]
    fn a_replaced_file_given_to_a_freeing_thread_is_closed_when_it_finishes() {
        use std::os::fd::AsRawFd;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("old.gcode");
        std::fs::write(&path, "G1 X1\n").unwrap();
        let old = std::fs::File::open(&path).unwrap();
        let fd = old.as_raw_fd();
        std::fs::remove_file(&path).unwrap();
        let freeing = FreeingThread::start();
        freeing.free(Replaced(Some(old)));
        freeing.finish();
        // The descriptor is no longer this file's: closed (or, if another test's file took the
        // number meanwhile, another file).
        let link = std::fs::read_link(format!("/proc/self/fd/{fd}"));
        assert!(link.is_err() || !link.unwrap().to_string_lossy().contains("old.gcode"));
    }

    /// Starting a file's data for the disk, whatever the range (empty, reversed, past the end,
    /// to the end), leaves the data as written.
    #[test]
    fn starting_the_writeback_leaves_the_data() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.txt");
        let data: Vec<u8> = (0..200_000u32).map(|i| (i % 251) as u8).collect();
        let (pending, ()) = prepare(&out, |w| {
            w.write_all(&data[..100_000])?;
            let file = w.file();
            w.flush()?;
            let reversed = std::ops::Range { start: 10, end: 3 };
            for range in [
                0..0,
                5..5,
                reversed,
                0..4096,
                90_000..u64::MAX,
                u64::MAX..u64::MAX,
            ] {
                start_writeback(file, range);
            }
            w.write_all(&data[100_000..])
        })
        .unwrap();
        drop(pending.commit().unwrap());
        assert!(std::fs::read(&out).unwrap() == data);
    }

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
        let Replaced(old) = pending.commit().unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"new");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temporary left"
        );
        // The file replaced comes back open, its data whole until it is dropped.
        let mut kept = String::new();
        std::io::Read::read_to_string(&mut old.expect("the old file"), &mut kept).unwrap();
        assert_eq!(kept, "old");
        // Nothing was replaced: nothing comes back.
        let fresh = dir.path().join("b.gcode");
        let (pending, ()) = prepare(&fresh, |w| w.write_all(b"new")).unwrap();
        assert!(pending.commit().unwrap().0.is_none());
    }

    #[cfg(unix)]
    #[test]
    fn a_link_is_followed_and_kept() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.gcode");
        std::fs::write(&real, b"old").unwrap();
        let link = dir.path().join("current.gcode");
        std::os::unix::fs::symlink("real.gcode", &link).unwrap();
        write_atomically(&link, |w| w.write_all(b"new")).unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        // A link to a file not made yet makes it.
        let dangling = dir.path().join("next.gcode");
        std::os::unix::fs::symlink("made.gcode", &dangling).unwrap();
        write_atomically(&dangling, |w| w.write_all(b"made")).unwrap();
        assert_eq!(
            std::fs::read(dir.path().join("made.gcode")).unwrap(),
            b"made"
        );
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            4,
            "no temporary left"
        );
    }

    /// A pipe gets the data and stays a pipe, never renamed over; likewise through a link (the
    /// shape of `/dev/stdout`, a link to the process's output). Before, as root, `-o /dev/full`
    /// replaced the device with a file.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_pipe_is_written_into_not_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(made.success());
        let link = dir.path().join("out");
        std::os::unix::fs::symlink(&fifo, &link).unwrap();
        for (path, data) in [(&fifo, b"G1 X1\n"), (&link, b"G1 X2\n")] {
            let reader = {
                let fifo = fifo.clone();
                std::thread::spawn(move || std::fs::read(fifo).unwrap())
            };
            let (pending, ()) = prepare(path, |w| w.write_all(data)).unwrap();
            assert_eq!(
                std::fs::read_dir(dir.path()).unwrap().count(),
                2,
                "the temporary is elsewhere"
            );
            drop(pending.commit().unwrap());
            assert_eq!(reader.join().unwrap(), data);
            assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
            assert!(
                std::fs::symlink_metadata(&link)
                    .unwrap()
                    .file_type()
                    .is_symlink()
            );
        }
    }

    #[test]
    fn missing_folder_is_reported() {
        let e = write_atomically(Path::new("/no/such/folder/x.gcode"), |_| Ok(())).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
    }
}
