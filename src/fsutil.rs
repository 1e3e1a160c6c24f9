//! Writing output files safely: one atomic-write helper for every file the crate writes, an
//! output directory that appears whole or not at all, and the cleanup of both when the process
//! is interrupted.
//!
//! * [`write_atomic`] writes a file through a temporary file in the target's directory, synced
//!   and then renamed over the target: a reader never sees half a file, and a failed write
//!   leaves the old file as it was. The new file's mode is `0666` less the umask, like a file
//!   created normally (not the `0600` of a private temporary file).
//! * [`OutputDir`] collects a command's output set (a report, a calibration) in a temporary
//!   directory beside the target and moves it into place only when all of it is written.
//!   Creating it is also the check that the target's folder is writable, before any long
//!   computation starts.
//! * While either exists, its temporary path is registered; [`remove_pending`] deletes every
//!   registered path. The CLI calls it when it receives SIGINT or SIGTERM, so an interrupted
//!   run leaves no hidden temporary file behind.

use std::ffi::{OsStr, OsString};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// Temporary paths that exist right now (files and directories), removed by
/// [`remove_pending`].
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending() -> MutexGuard<'static, Vec<PathBuf>> {
    // A panic while the lock was held leaves a valid list: keep using it.
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

/// A temporary path registered for [`remove_pending`] while this guard lives.
struct Registered(PathBuf);

impl Registered {
    /// Creates a temporary file or directory with `create` and registers its path, both
    /// while the list is locked. So a signal handler's [`remove_pending`] either runs first
    /// (and then nothing is created: the list stays locked until the process exits) or sees
    /// the new path; and no temporary file appears inside a registered directory while
    /// [`remove_pending`] is deleting it (which would leave that directory behind).
    fn create<T>(
        create: impl FnOnce() -> io::Result<T>,
        path: impl Fn(&T) -> &Path,
    ) -> io::Result<(T, Self)> {
        let mut list = pending();
        let made = create()?;
        let p = path(&made).to_path_buf();
        list.push(p.clone());
        Ok((made, Self(p)))
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        let mut list = pending();
        if let Some(i) = list.iter().rposition(|p| *p == self.0) {
            list.swap_remove(i);
        }
    }
}

/// Deletes every temporary file and directory that [`write_atomic`] or an [`OutputDir`] has
/// open right now, and returns how many it removed. Meant for a signal handler's thread just
/// before the process exits: the list stays locked afterwards, so no new temporary path is
/// registered and no rename into place happens in between.
pub fn remove_pending() -> usize {
    let list = pending();
    let mut removed = 0;
    for p in list.iter() {
        let ok = if p.is_dir() {
            std::fs::remove_dir_all(p).is_ok()
        } else {
            std::fs::remove_file(p).is_ok()
        };
        removed += usize::from(ok);
    }
    // Keep the lock until the process exits.
    std::mem::forget(list);
    removed
}

/// The directory a path's file goes into (`.` for a bare file name).
fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// `.name.` — the prefix of a temporary path beside `path`.
fn hidden_prefix(path: &Path) -> OsString {
    let mut s = OsString::from(".");
    s.push(path.file_name().unwrap_or_else(|| "out".as_ref()));
    s.push(".");
    s
}

/// A builder of the temporary path `{prefix}XXXXXX.tmp` ([`hidden_prefix`]), created with the
/// Unix mode `mode` less the umask.
fn temp_beside(prefix: &OsStr, mode: u32) -> tempfile::Builder<'_, 'static> {
    let mut builder = tempfile::Builder::new();
    builder.prefix(prefix).suffix(".tmp");
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(mode));
    #[cfg(not(unix))]
    let _ = mode;
    builder
}

/// Writes a file atomically: `write` fills a temporary file in the target's directory, which
/// is then flushed, synced and renamed over `path`. On any error, `write`'s included, `path` is
/// left as it was and the temporary file is removed. The file's mode is `0666` less the umask.
///
/// `E` is any error an [`io::Error`] converts into (`io::Error` itself when `write` only does
/// I/O); `write` sees a buffered writer.
pub fn write_atomic<E: From<io::Error>>(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> Result<(), E>,
) -> Result<(), E> {
    let prefix = hidden_prefix(path);
    let (tmp, registered) = Registered::create(
        || temp_beside(&prefix, 0o666).tempfile_in(parent_of(path)),
        |t| t.path(),
    )?;
    let mut w = io::BufWriter::with_capacity(1 << 16, tmp);
    write(&mut w)?;
    let tmp = w.into_inner().map_err(io::IntoInnerError::into_error)?;
    tmp.as_file().sync_all()?;
    // Hold the list while renaming, so a signal handler never deletes a file that has just
    // been renamed into place (nor misses the temporary one).
    let list = pending();
    let persisted = tmp.persist(path);
    drop(list);
    drop(registered);
    persisted.map_err(|e| e.error)?;
    Ok(())
}

/// [`write_atomic`] of a byte string.
pub fn write_atomic_bytes(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic(path, |w| w.write_all(bytes))
}

/// A command's output directory, written whole or not at all.
///
/// [`OutputDir::create`] makes a temporary directory beside the target (`.name.XXXXXX.tmp`);
/// the command writes its files into [`OutputDir::path`]; [`OutputDir::commit`] moves them
/// into the target. Dropped without a commit (an error, a panic), the temporary directory is
/// removed with everything in it and the target is left as it was.
#[derive(Debug)]
pub struct OutputDir {
    target: PathBuf,
    tmp: Option<tempfile::TempDir>,
    registered: Option<RegisteredDir>,
}

/// [`Registered`] with a `Debug` for [`OutputDir`].
struct RegisteredDir(#[allow(dead_code)] Registered);

impl std::fmt::Debug for RegisteredDir {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Registered")
    }
}

impl OutputDir {
    /// Creates the temporary directory beside `target` (and `target`'s parent folders if they
    /// do not exist). Fails when `target` exists and is not a directory, or when its folder is
    /// not writable: call it before a long computation so that such a problem shows at once.
    pub fn create(target: &Path) -> io::Result<Self> {
        if target.exists() && !target.is_dir() {
            return Err(io::Error::new(
                io::ErrorKind::AlreadyExists,
                "exists and is not a directory",
            ));
        }
        let parent = parent_of(target);
        std::fs::create_dir_all(parent)?;
        let prefix = hidden_prefix(target);
        let (tmp, registered) = Registered::create(
            || temp_beside(&prefix, 0o777).tempdir_in(parent),
            |t| t.path(),
        )?;
        Ok(Self {
            target: target.to_path_buf(),
            tmp: Some(tmp),
            registered: Some(RegisteredDir(registered)),
        })
    }

    /// The temporary directory to write into.
    pub fn path(&self) -> &Path {
        self.tmp
            .as_ref()
            .map_or(self.target.as_path(), |t| t.path())
    }

    /// The final directory.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Moves the written set into the target: a rename of the whole directory when the target
    /// does not exist yet, else a rename of each file into it (files of the same name are
    /// replaced, other files in the target are kept).
    pub fn commit(mut self) -> io::Result<()> {
        let Some(tmp) = self.tmp.take() else {
            return Ok(());
        };
        let list = pending();
        let whole = !self.target.exists();
        let result = if whole {
            std::fs::rename(tmp.path(), &self.target)
        } else {
            // Everything that could stop a rename half-way is checked before the first one.
            check_entries(tmp.path(), &self.target)
                .and_then(|()| move_entries(tmp.path(), &self.target))
        };
        drop(list);
        if whole && result.is_ok() {
            // Renamed as a whole: nothing is left to clean up.
            let _ = tmp.keep();
        }
        // Otherwise `tmp` (now empty, or partly moved on an error) is removed on drop.
        self.registered = None;
        result
    }
}

/// Checks that every entry of `from` can be renamed into `to`: no file lands on a directory
/// and no directory on a file.
fn check_entries(from: &Path, to: &Path) -> io::Result<()> {
    if !to.is_dir() {
        return Err(io::Error::new(
            io::ErrorKind::AlreadyExists,
            format!("{} exists and is not a directory", to.display()),
        ));
    }
    for entry in std::fs::read_dir(from)? {
        let entry = entry?;
        let dest = to.join(entry.file_name());
        if entry.file_type()?.is_dir() {
            if dest.exists() {
                check_entries(&entry.path(), &dest)?;
            }
        } else if dest.is_dir() {
            return Err(io::Error::new(
                io::ErrorKind::IsADirectory,
                format!("{} is a directory; nothing was moved", dest.display()),
            ));
        }
    }
    Ok(())
}

/// Renames every entry of `from` into `to`, replacing entries of the same name.
fn move_entries(from: &Path, to: &Path) -> io::Result<()> {
    for entry in std::fs::read_dir(from)? {
        let entry = entry?;
        let dest = to.join(entry.file_name());
        if entry.file_type()?.is_dir() {
            if !dest.is_dir() {
                std::fs::create_dir_all(&dest)?;
            }
            move_entries(&entry.path(), &dest)?;
        } else {
            std::fs::rename(entry.path(), dest)?;
        }
    }
    Ok(())
}

/// Opens an input file for reading without ever blocking: a named pipe (FIFO) or a socket is
/// refused by its type before it is opened (opening a FIFO with no writer blocks forever), and
/// on Unix the file is opened non-blocking, so a device with nothing to read fails at once
/// instead of hanging. Directories are left to the caller, whose message names what it wanted.
pub fn open_input(path: &Path) -> io::Result<std::fs::File> {
    let meta = std::fs::metadata(path)?;
    if let Some(kind) = special_kind(&meta) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("is {kind}, not a regular file: give a file"),
        ));
    }
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // O_NONBLOCK: ignored by regular files, makes a device's empty read fail at once.
        options.custom_flags(libc::O_NONBLOCK);
    }
    options.open(path)
}

/// "a named pipe (FIFO)" or "a socket" for the file types that block a reader; `None` else.
fn special_kind(meta: &std::fs::Metadata) -> Option<&'static str> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return Some("a named pipe (FIFO)");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    #[cfg(not(unix))]
    let _ = meta;
    None
}

/// Whether `output` names the same file as `input` (the same path after resolving links, or
/// the same inode through a hard link). `false` when `output` does not exist yet.
pub fn same_file(input: &Path, output: &Path) -> bool {
    let (Ok(a), Ok(b)) = (std::fs::metadata(input), std::fs::metadata(output)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if a.dev() == b.dev() && a.ino() == b.ino() {
            return true;
        }
    }
    let _ = (a, b);
    match (std::fs::canonicalize(input), std::fs::canonicalize(output)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// 1-based line and column of byte offset `at` in a file's bytes, for messages that point into
/// a file. The column counts characters (a byte that is not valid UTF-8 counts as one); an
/// offset inside a character points at that character; one past the end is allowed.
pub fn line_column(bytes: &[u8], at: usize) -> (usize, usize) {
    let before = &bytes[..at.min(bytes.len())];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    // Count the bytes that start a character (not UTF-8 continuation bytes 10xxxxxx).
    let starts = before[start..]
        .iter()
        .filter(|&&b| b & 0xC0 != 0x80)
        .count();
    let inside = bytes.get(at).is_some_and(|&b| b & 0xC0 == 0x80) && starts > 0;
    (line, starts + 1 - usize::from(inside))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_column_counts_characters() {
        let text = "a = 1\nβé = x".as_bytes();
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 4), (1, 5));
        assert_eq!(line_column(text, 6), (2, 1));
        // β and é are two bytes each: `=` is the 4th character of line 2, at byte 11.
        assert_eq!(line_column(text, 11), (2, 4));
        // Inside é (its second byte) points at é.
        assert_eq!(line_column(text, 9), (2, 2));
        assert_eq!(line_column(text, text.len()), (2, 7));
        assert_eq!(line_column(b"ok\n\xff", 3), (2, 1));
    }

    #[test]
    fn atomic_write_replaces_or_leaves_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic_bytes(&p, b"one").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"one");
        let e = write_atomic(&p, |w| {
            w.write_all(b"two")?;
            Err(io::Error::other("refused"))
        })
        .unwrap_err();
        assert_eq!(e.to_string(), "refused");
        assert_eq!(std::fs::read(&p).unwrap(), b"one");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "no temporary file left");
        assert!(!pending().iter().any(|q| q.starts_with(dir.path())));
    }

    #[test]
    fn output_dir_commits_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("sub").join("out");
        let out = OutputDir::create(&target).unwrap();
        std::fs::write(out.path().join("a"), "a").unwrap();
        assert!(!target.exists());
        drop(out);
        assert!(!target.exists());
        assert_eq!(
            std::fs::read_dir(dir.path().join("sub")).unwrap().count(),
            0
        );

        let out = OutputDir::create(&target).unwrap();
        std::fs::write(out.path().join("a"), "a").unwrap();
        out.commit().unwrap();
        assert_eq!(std::fs::read_to_string(target.join("a")).unwrap(), "a");

        // Into an existing directory: replaces `a`, keeps `keep`.
        std::fs::write(target.join("keep"), "k").unwrap();
        let out = OutputDir::create(&target).unwrap();
        std::fs::write(out.path().join("a"), "A").unwrap();
        out.commit().unwrap();
        assert_eq!(std::fs::read_to_string(target.join("a")).unwrap(), "A");
        assert_eq!(std::fs::read_to_string(target.join("keep")).unwrap(), "k");
        assert_eq!(
            std::fs::read_dir(dir.path().join("sub")).unwrap().count(),
            1
        );
    }
}
