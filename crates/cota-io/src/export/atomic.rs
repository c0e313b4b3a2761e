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
//! Symbolic links are written through: when the target is a link (or a chain
//! of them, dangling or not), the file it points to is written, atomically, by
//! a temporary file next to *that* file, and the link is kept. An existing
//! read-only target (the file the link points to, for a link) is refused
//! unless the caller asks to replace it ([`write_atomically_forced`]; the
//! CLI's `--force`): the rename itself would replace it silently.
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
    write_atomically_forced(path, false, encode)
}

/// [`write_atomically`], replacing an existing read-only target when
/// `replace_read_only` (else that is an error naming the file).
///
/// # Errors
/// As [`write_atomically`], and [`WriteError::Io`] (permission denied) for a
/// read-only target unless `replace_read_only`.
pub fn write_atomically_forced<F>(
    path: &Path,
    replace_read_only: bool,
    encode: F,
) -> Result<(), WriteError>
where
    F: FnOnce(&mut (dyn Write + Send)) -> Result<(), ExportError>,
{
    let resolved = resolve_links(path).map_err(|e| WriteError::io(path, e))?;
    let target = resolved.as_path();
    if target.is_dir() {
        return Err(WriteError::io(path, is_a_directory()));
    }
    if !replace_read_only && is_read_only(target) {
        return Err(WriteError::io(path, read_only(path, target)));
    }
    let dir = parent_dir(target);
    let mut tmp = create_temp(target, dir)?;
    {
        let mut w = BufWriter::with_capacity(BUFFER_BYTES, tmp.as_file_mut());
        encode(&mut w).map_err(|e| WriteError::export(path, e))?;
        w.flush().map_err(|e| WriteError::io(path, e))?;
    }
    tmp.as_file()
        .sync_all()
        .map_err(|e| WriteError::io(path, e))?;
    tmp.persist(target)
        .map_err(|e| WriteError::io(path, e.error))?;
    sync_dir(dir);
    Ok(())
}

/// Most links followed before giving up (as Linux's `MAXSYMLINKS`).
const MAX_LINKS: usize = 40;

/// The file `path` names once symbolic links are followed (the path itself
/// when it is no link); a dangling link gives the path it points to.
fn resolve_links(path: &Path) -> io::Result<std::path::PathBuf> {
    let mut p = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let to = std::fs::read_link(&p)?;
                p = parent_dir(&p).join(to);
            }
            _ => return Ok(p),
        }
    }
    Err(io::Error::other(format!(
        "more than {MAX_LINKS} symbolic links to follow (a loop?)"
    )))
}

/// True when `path` exists and its permissions forbid writing.
fn is_read_only(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.permissions().readonly())
}

/// The error for a read-only target.
fn read_only(path: &Path, target: &Path) -> io::Error {
    let through = if target == path {
        String::new()
    } else {
        format!(" (the link's target {})", target.display())
    };
    io::Error::new(
        io::ErrorKind::PermissionDenied,
        format!("the existing file{through} is read-only; use --force to replace it"),
    )
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
