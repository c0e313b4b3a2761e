//! Atomic file writing: all of the new content or none of it.
//!
//! The bytes go to a temporary file created in the target's own directory (so
//! the final rename never crosses a file system), named `.NAME.XXXXXX.tmp`. When
//! the encoder succeeds the file is flushed, `fsync`ed and renamed over the
//! target, which readers then see change from the old content to the complete
//! new one in a single step (POSIX `rename(2)` is atomic). On any failure the
//! temporary file is removed and the target is untouched: no half-written
//! output, no stray temporary file. On Unix the directory is then synced too
//! (best effort: some file systems refuse it), so the rename itself survives a
//! crash.
//!
//! The rename replaces the directory entry: when the target is a symbolic
//! link, the link itself is replaced by the new file (its old destination is
//! left alone).
//!
//! The temporary file is created with mode `0o666` less the process umask, the
//! permissions an ordinary `File::create` would give, rather than the `0o600`
//! that temporary files get by default.

use std::ffi::OsString;
use std::io::{self, BufWriter, Write};
use std::path::Path;

use super::error::{ExportError, WriteError};

/// Size of the write buffer in front of the temporary file.
const BUFFER_BYTES: usize = 1 << 20;

/// Writes a file atomically: `encode` writes the content to a buffered
/// temporary file in the same directory, which then replaces `path`.
///
/// On error nothing is left behind and an existing file at `path` keeps its
/// old content.
///
/// # Errors
/// [`WriteError::Io`] when the directory does not exist, is not writable,
/// `path` is a directory, or writing, syncing or renaming fails; the error of
/// `encode` otherwise (its I/O errors also become [`WriteError::Io`]).
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("hello.txt");
/// cota_io::export::write_atomically(&path, |w| Ok(w.write_all(b"hello\n")?))?;
/// assert_eq!(std::fs::read(&path)?, b"hello\n");
/// # Ok(())
/// # }
/// ```
pub fn write_atomically<F>(path: &Path, encode: F) -> Result<(), WriteError>
where
    F: FnOnce(&mut (dyn Write + Send)) -> Result<(), ExportError>,
{
    if path.is_dir() {
        return Err(WriteError::io(path, is_a_directory()));
    }
    let dir = parent_dir(path);
    let mut tmp = create_temp(path, dir)?;
    {
        let mut w = BufWriter::with_capacity(BUFFER_BYTES, tmp.as_file_mut());
        encode(&mut w).map_err(|e| WriteError::export(path, e))?;
        w.flush().map_err(|e| WriteError::io(path, e))?;
    }
    tmp.as_file()
        .sync_all()
        .map_err(|e| WriteError::io(path, e))?;
    tmp.persist(path)
        .map_err(|e| WriteError::io(path, e.error))?;
    sync_dir(dir);
    Ok(())
}

/// The directory that holds `path` (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Creates the temporary file `.NAME.XXXXXX.tmp` next to `path`.
fn create_temp(path: &Path, dir: &Path) -> Result<tempfile::NamedTempFile, WriteError> {
    let mut prefix = OsString::from(".");
    if let Some(name) = path.file_name() {
        prefix.push(name);
    }
    prefix.push(".");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    set_ordinary_permissions(&mut builder);
    builder.tempfile_in(dir).map_err(|e| {
        let e = if e.kind() == io::ErrorKind::NotFound && !dir.is_dir() {
            io::Error::new(
                io::ErrorKind::NotFound,
                format!("directory {} does not exist", dir.display()),
            )
        } else {
            e
        };
        WriteError::io(path, e)
    })
}

/// Asks for mode 0o666 (less the umask) instead of tempfile's 0o600.
#[cfg(unix)]
fn set_ordinary_permissions(builder: &mut tempfile::Builder<'_, '_>) {
    use std::os::unix::fs::PermissionsExt;
    builder.permissions(std::fs::Permissions::from_mode(0o666));
}

/// Nothing to do where there are no Unix modes.
#[cfg(not(unix))]
fn set_ordinary_permissions(_builder: &mut tempfile::Builder<'_, '_>) {}

/// The error for an output path that is a directory.
fn is_a_directory() -> io::Error {
    io::Error::new(io::ErrorKind::IsADirectory, "the path is a directory")
}

/// Syncs the directory so the rename is durable; best effort (some file
/// systems refuse to fsync a directory, and the data itself is already synced).
#[cfg(unix)]
fn sync_dir(dir: &Path) {
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
}

/// Directories cannot be opened for syncing here.
#[cfg(not(unix))]
fn sync_dir(_dir: &Path) {}
