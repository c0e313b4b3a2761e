//! 3D Tiles terrain as one file: a 3D Tiles Archive (`.3tz`), the ZIP
//! profile that Cesium ion, ArcGIS, `3d-tiles-tools` and loaders.gl read.
//!
//! Written from the 3D Tiles Archive Format specification (v1.3, Maxar's
//! `3tz-specification`):
//!
//! * a ZIP file whose local headers carry the CRC-32 and both sizes (the
//!   `zip` crate writes them so for stored entries); `tileset.json` at the
//!   root, every other path relative, as the directory pyramid has them;
//! * entries **stored**, not compressed: the specification's fastest to
//!   read, and the GLBs are already meshopt-coded or small;
//! * last, the index `@3dtilesIndex1@` (stored, no comment, the last entry
//!   of the central directory): one 24-byte record per file, the MD5 of its
//!   path (forward slashes, no leading slash) and the offset of its local
//!   header (u64, little-endian), sorted by the hash read as two
//!   little-endian u64s, high half first.
//!
//! The pyramid is first written as a directory beside the archive
//! ([`staging_path`], with the directory's guarantees: atomic per tile,
//! resumed by a later run), then packed into `OUT.partial` and renamed to
//! `OUT` ([`write_3tz`]): an interrupted run never leaves a file that looks
//! complete, and the staging directory goes once the archive is in place.
//! Files whose names start with a dot (the run's manifest and journals)
//! stay out of the archive.

use std::io::Write;
use std::path::{Path, PathBuf};

use md5::{Digest, Md5};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipArchive, ZipWriter};

use super::pyramid::{PyramidError, PyramidOptions, PyramidReport};
use super::pyramid3d::write_tiles3d;
use cota_core::tiles::Prepared;

/// The index entry's name.
pub const INDEX_NAME: &str = "@3dtilesIndex1@";

/// True for a 3D Tiles archive name: `.3tz` or `.3dtiles.zip`.
pub fn is_3tz(out: &Path) -> bool {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    name.ends_with(".3tz") || name.ends_with(".3dtiles.zip")
}

/// The directory the pyramid is written to before it is packed: `OUT.parts`.
pub fn staging_path(out: &Path) -> PathBuf {
    let mut name = out.file_name().unwrap_or_default().to_os_string();
    name.push(".parts");
    out.with_file_name(name)
}

/// The archive under construction: `OUT.partial`.
fn partial_path(out: &Path) -> PathBuf {
    let mut name = out.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    out.with_file_name(name)
}

/// Writes the 3D Tiles pyramid of `prep` as the archive `out`: the
/// directory pyramid in [`staging_path`] (resumed if a run left one), packed
/// by [`pack_3tz`], then the staging directory removed.
///
/// # Errors
/// As [`write_tiles3d`]; [`PyramidError::Io`] naming the file that could
/// not be read or written.
pub fn write_3tz(
    prep: &Prepared<'_>,
    out: &Path,
    opts: &PyramidOptions,
    source: Option<&super::drawn::Against<'_>>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<PyramidReport, PyramidError> {
    let staging = staging_path(out);
    let report = write_tiles3d(prep, &staging, opts, source, progress)?;
    pack_3tz(&staging, out)?;
    std::fs::remove_dir_all(&staging).map_err(io_err(&staging))?;
    Ok(report)
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> PyramidError + '_ {
    move |source| PyramidError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn zip_err(path: &Path) -> impl FnOnce(zip::result::ZipError) -> PyramidError + '_ {
    move |e| PyramidError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    }
}

/// Packs the 3D Tiles directory `dir` (its `tileset.json` at the root) into
/// the archive `out`, through `OUT.partial` and a rename; returns the files
/// packed (the index left out).
///
/// # Errors
/// [`PyramidError::Io`] naming `dir` when it holds no `tileset.json`, or the
/// file that could not be read or written.
pub fn pack_3tz(dir: &Path, out: &Path) -> Result<usize, PyramidError> {
    let tileset = dir.join("tileset.json");
    if !tileset.is_file() {
        return Err(io_err(dir)(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "expected a 3D Tiles directory with tileset.json at its root, found none",
        )));
    }
    let mut files = Vec::new();
    list_files(dir, "", &mut files)?;
    // tileset.json first: readers without the index find the root at once.
    files.sort_by(|a, b| (a != "tileset.json", a).cmp(&(b != "tileset.json", b)));
    let partial = partial_path(out);
    let packed = pack_files(dir, &files, &partial).and_then(|()| {
        std::fs::File::open(&partial)
            .and_then(|f| f.sync_all())
            .map_err(io_err(&partial))?;
        std::fs::rename(&partial, out).map_err(io_err(out))
    });
    if packed.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    packed.map(|()| files.len())
}

/// The files under `dir/rel`, as archive paths (forward slashes), leaving
/// out names that start with a dot.
fn list_files(dir: &Path, rel: &str, files: &mut Vec<String>) -> Result<(), PyramidError> {
    let here = dir.join(rel);
    for entry in std::fs::read_dir(&here).map_err(io_err(&here))? {
        let entry = entry.map_err(io_err(&here))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') {
            continue;
        }
        let path = if rel.is_empty() {
            name
        } else {
            format!("{rel}/{name}")
        };
        let kind = entry.file_type().map_err(io_err(&entry.path()))?;
        if kind.is_dir() {
            list_files(dir, &path, files)?;
        } else if kind.is_file() {
            files.push(path);
        }
    }
    Ok(())
}

/// Writes `files` of `dir`, stored, into `partial`, then reads back where
/// each local header lies and appends the index.
fn pack_files(dir: &Path, files: &[String], partial: &Path) -> Result<(), PyramidError> {
    let stored = SimpleFileOptions::default()
        .compression_method(CompressionMethod::Stored)
        .large_file(false);
    let file = std::fs::File::create(partial).map_err(io_err(partial))?;
    let mut zip = ZipWriter::new(std::io::BufWriter::new(file));
    for rel in files {
        let path = dir.join(rel);
        let bytes = std::fs::read(&path).map_err(io_err(&path))?;
        zip.start_file(rel.as_str(), stored)
            .map_err(zip_err(partial))?;
        zip.write_all(&bytes).map_err(io_err(partial))?;
    }
    let mut inner = zip.finish().map_err(zip_err(partial))?;
    inner.flush().map_err(io_err(partial))?;
    drop(inner);
    let f = std::fs::File::open(partial).map_err(io_err(partial))?;
    let mut archive = ZipArchive::new(std::io::BufReader::new(f)).map_err(zip_err(partial))?;
    let mut index = Vec::with_capacity(files.len());
    for i in 0..archive.len() {
        let e = archive.by_index_raw(i).map_err(zip_err(partial))?;
        let name = e.name().map_err(zip_err(partial))?;
        index.push((path_hash(&name), e.header_start()));
    }
    drop(archive);
    let f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(partial)
        .map_err(io_err(partial))?;
    let mut zip = ZipWriter::new_append(f).map_err(zip_err(partial))?;
    zip.start_file(INDEX_NAME, stored)
        .map_err(zip_err(partial))?;
    zip.write_all(&index_bytes(index))
        .map_err(io_err(partial))?;
    zip.finish().map_err(zip_err(partial))?;
    check_offsets(partial, files)
}

/// Reads `partial` back and checks that every entry's local header lies
/// where the index says and that the index is the last entry.
fn check_offsets(partial: &Path, files: &[String]) -> Result<(), PyramidError> {
    let f = std::fs::File::open(partial).map_err(io_err(partial))?;
    let mut zip = ZipArchive::new(std::io::BufReader::new(f)).map_err(zip_err(partial))?;
    let bad = |what: String| io_err(partial)(std::io::Error::other(what));
    if zip.len() != files.len() + 1 {
        return Err(bad(format!(
            "expected {} entries, found {}",
            files.len() + 1,
            zip.len()
        )));
    }
    let index = {
        let mut e = zip.by_index(files.len()).map_err(zip_err(partial))?;
        let name = e.name().map_err(zip_err(partial))?.into_owned();
        if name != INDEX_NAME {
            return Err(bad(format!("expected {INDEX_NAME} last, found {name}")));
        }
        let mut v = Vec::new();
        std::io::Read::read_to_end(&mut e, &mut v).map_err(io_err(partial))?;
        v
    };
    let offsets: std::collections::HashMap<[u8; 16], u64> =
        parse_index(&index).into_iter().collect();
    for i in 0..files.len() {
        let e = zip.by_index_raw(i).map_err(zip_err(partial))?;
        let name = e.name().map_err(zip_err(partial))?;
        if offsets.get(&path_hash(&name)) != Some(&e.header_start()) {
            return Err(bad(format!(
                "{name}: its index offset is not its local header's ({})",
                e.header_start()
            )));
        }
    }
    Ok(())
}

/// The MD5 of an archive path, normalised (forward slashes, no leading
/// slash).
pub fn path_hash(path: &str) -> [u8; 16] {
    let p = path.replace('\\', "/");
    Md5::digest(p.trim_start_matches('/').as_bytes()).into()
}

/// The index's bytes: its records sorted by hash, read as two little-endian
/// u64s (the first eight bytes the higher).
fn index_bytes(mut index: Vec<([u8; 16], u64)>) -> Vec<u8> {
    index.sort_by_key(|(h, o)| (key(h), *o));
    index
        .iter()
        .flat_map(|(h, o)| h.iter().copied().chain(o.to_le_bytes()))
        .collect()
}

/// A 3D Tiles Archive opened for reading through its index, as the
/// specification asks readers to: a path's MD5 looked up in
/// `@3dtilesIndex1@`, its local header read at the offset found, its name
/// compared, its stored bytes returned.
pub struct Tz3Reader {
    file: std::sync::Mutex<std::fs::File>,
    index: Vec<([u8; 16], u64)>,
}

impl Tz3Reader {
    /// Opens `path` and reads its index (the central directory's last entry).
    ///
    /// # Errors
    /// [`PyramidError::Io`] naming `path` when it is not a ZIP file or its
    /// last entry is not the index.
    pub fn open(path: &Path) -> Result<Tz3Reader, PyramidError> {
        let file = std::fs::File::open(path).map_err(io_err(path))?;
        let mut zip = ZipArchive::new(&file).map_err(zip_err(path))?;
        let last = zip.len().checked_sub(1).ok_or_else(|| {
            io_err(path)(std::io::Error::other(
                "expected a 3D Tiles Archive, found an empty ZIP file",
            ))
        })?;
        let mut e = zip.by_index(last).map_err(zip_err(path))?;
        let name = e.name().map_err(zip_err(path))?.into_owned();
        if name != INDEX_NAME {
            return Err(io_err(path)(std::io::Error::other(format!(
                "expected {INDEX_NAME} as the last entry of a 3D Tiles Archive, found {name}"
            ))));
        }
        let mut raw = Vec::new();
        std::io::Read::read_to_end(&mut e, &mut raw).map_err(io_err(path))?;
        drop(e);
        let index = parse_index(&raw);
        Ok(Tz3Reader {
            file: std::sync::Mutex::new(file),
            index,
        })
    }

    /// The files the index names.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// True when the index names no file.
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// The bytes of the stored file at `path`, or `None` when the index
    /// does not name it.
    ///
    /// # Errors
    /// An I/O error on a local header that is not one, or an entry that is
    /// compressed.
    pub fn get(&self, path: &str) -> std::io::Result<Option<Vec<u8>>> {
        let mut file = self
            .file
            .lock()
            .map_err(|_| std::io::Error::other("a reader of the archive panicked"))?;
        let mut read_at = |buf: &mut [u8], at: u64| {
            use std::io::{Read, Seek, SeekFrom};
            file.seek(SeekFrom::Start(at))?;
            file.read_exact(buf)
        };
        let name = path.replace('\\', "/");
        let name = name.trim_start_matches('/');
        let h = path_hash(name);
        let first = self.index.partition_point(|(k, _)| key(k) < key(&h));
        for (_, offset) in self.index[first..].iter().take_while(|(k, _)| *k == h) {
            let mut head = [0u8; 30];
            read_at(&mut head, *offset)?;
            let u16_at = |k: usize| usize::from(u16::from_le_bytes([head[k], head[k + 1]]));
            let u32_at =
                |k: usize| u32::from_le_bytes([head[k], head[k + 1], head[k + 2], head[k + 3]]);
            if u32_at(0) != 0x0403_4b50 {
                return Err(std::io::Error::other(format!(
                    "no local header at {offset}"
                )));
            }
            let mut got = vec![0u8; u16_at(26)];
            read_at(&mut got, offset + 30)?;
            if got != name.as_bytes() {
                continue;
            }
            if u16_at(8) != 0 {
                return Err(std::io::Error::other(format!(
                    "{name}: compressed, expected stored"
                )));
            }
            let mut data = vec![0u8; u32_at(18) as usize];
            let start = offset + 30 + (u16_at(26) + u16_at(28)) as u64;
            read_at(&mut data, start)?;
            return Ok(Some(data));
        }
        Ok(None)
    }
}

/// The index's records: the MD5 of each path and its local header's offset.
fn parse_index(raw: &[u8]) -> Vec<([u8; 16], u64)> {
    raw.chunks_exact(24)
        .map(|r| {
            let mut h = [0u8; 16];
            h.copy_from_slice(&r[..16]);
            (h, u64::from_le_bytes(r[16..].try_into().unwrap_or([0; 8])))
        })
        .collect()
}

/// The index's order: the hash as two little-endian u64s, high half first.
fn key(h: &[u8; 16]) -> (u64, u64) {
    let half = |k: usize| u64::from_le_bytes(h[k..k + 8].try_into().unwrap_or([0; 8]));
    (half(0), half(8))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_index_is_sorted_by_the_hash_as_two_little_endian_halves() {
        let mut a = [0u8; 16];
        let mut b = [0u8; 16];
        // a's first half is larger read little-endian (its last byte), b's
        // read big-endian (its first byte): little-endian must decide.
        a[7] = 1;
        b[0] = 2;
        let bytes = index_bytes(vec![(a, 10), (b, 20)]);
        assert_eq!(bytes.len(), 48);
        assert_eq!(&bytes[..16], &b);
        assert_eq!(
            u64::from_le_bytes(bytes[16..24].try_into().unwrap_or([0; 8])),
            20
        );
        assert_eq!(&bytes[24..40], &a);
    }

    #[test]
    fn paths_are_hashed_normalised() {
        // MD5("tileset.json"), as `md5sum` gives it.
        let h = path_hash("tileset.json");
        let hex: String = h.iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(hex, "c09bdea7e745894f499a7517db9a7709");
        assert_eq!(path_hash("/tileset.json"), h);
        assert_eq!(path_hash("0\\0\\0.glb"), path_hash("0/0/0.glb"));
    }

    #[test]
    fn names() {
        assert!(is_3tz(Path::new("a/b.3tz")) && is_3tz(Path::new("B.3DTILES.ZIP")));
        assert!(!is_3tz(Path::new("b.zip")) && !is_3tz(Path::new("b.mbtiles")));
        assert_eq!(
            staging_path(Path::new("d/t.3tz")),
            Path::new("d/t.3tz.parts")
        );
    }
}
