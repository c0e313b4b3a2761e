//! Tile files written in place, with a journal instead of a rename per tile
//! (issue 29 item 3).
//!
//! Writing each tile to a temporary name and renaming it costs two directory
//! changes per tile; on the ext4 disk of the benchmark machine that atomic
//! write took 2.5 times the time of a plain write of the same bytes
//! (`tiles-codec`, `bench/README.md`). A pyramid directory is a set of
//! small files, so that tax is most of the time spent writing.
//!
//! Instead each run appends to its own journal,
//! `OUT/.cota-journal/PID-NANOS.log`, one line `b Z X Y` when it starts
//! writing a tile (written to the file before the tile's first byte) and
//! one line `e Z X Y` once the tile is written and closed. A tile file is
//! complete unless some journal holds its `b` line without its `e` line.
//! So an interrupted run (a crash, a kill, a full disk) leaves at most one
//! unfinished tile per thread, each named in its journal; the next run over
//! the same tiles (the resume) removes them first and makes them again, and
//! `layer.json` is written only once every tile is (a client never loads an
//! unfinished pyramid). A run that ends removes its journal, and the
//! journals of earlier runs whose every unfinished tile it has made again.
//!
//! Runs over disjoint tile sets in one directory (shards) each keep their
//! own journal and only ever remove unfinished tiles of their own set.
//! What is not promised: a reader that opens a tile while a run writes it
//! may read a partial file (as with any tiler writing files in place); the
//! journal is not `fsync`ed, like the tiles (a power cut may lose recent
//! tiles' lines; then those tiles are made again).

use std::collections::{BTreeSet, HashSet};
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{SystemTime, UNIX_EPOCH};

use cota_core::tiles::TileId;

/// A file-system failure and the path it concerns (turned into
/// `PyramidError::Io` by the pyramid writer).
#[derive(Debug)]
pub(crate) struct PathIo(pub PathBuf, pub std::io::Error);

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> PathIo + '_ {
    move |e| PathIo(path.to_path_buf(), e)
}

/// The journal folder under a pyramid directory.
pub const JOURNAL_DIR: &str = ".cota-journal";

/// A run's journal: begun and ended tiles.
pub(crate) struct Journal {
    file: Mutex<File>,
    path: PathBuf,
    /// Earlier runs' journals whose unfinished tiles this run makes again.
    redone: Vec<PathBuf>,
}

/// The tiles an earlier journal began and did not end.
fn unfinished(text: &str) -> HashSet<TileId> {
    let mut open = HashSet::new();
    for line in text.lines() {
        let mut f = line.split(' ');
        let (Some(kind), Some(z), Some(x), Some(y), None) =
            (f.next(), f.next(), f.next(), f.next(), f.next())
        else {
            continue; // a line cut by the interruption: its tile never began
        };
        let (Ok(z), Ok(x), Ok(y)) = (z.parse(), x.parse(), y.parse()) else {
            continue;
        };
        let t = TileId { z, x, y };
        match kind {
            "b" => open.insert(t),
            "e" => open.remove(&t),
            _ => false,
        };
    }
    open
}

impl Journal {
    /// Removes the files of `tiles` that earlier runs left unfinished, then
    /// opens this run's journal under `out`.
    ///
    /// # Errors
    /// The journal or tile that could not be read, removed or created.
    pub(crate) fn open(
        out: &Path,
        tiles: &[TileId],
        path_of: impl Fn(TileId) -> PathBuf,
    ) -> Result<Journal, PathIo> {
        let dir = out.join(JOURNAL_DIR);
        std::fs::create_dir_all(&dir).map_err(io_err(&dir))?;
        let mine: HashSet<TileId> = tiles.iter().copied().collect();
        let mut redone = Vec::new();
        for entry in std::fs::read_dir(&dir).map_err(io_err(&dir))? {
            let p = entry.map_err(io_err(&dir))?.path();
            let text = std::fs::read_to_string(&p).map_err(io_err(&p))?;
            let open = unfinished(&text);
            for &t in open.iter().filter(|t| mine.contains(t)) {
                let tile = path_of(t);
                match std::fs::remove_file(&tile) {
                    Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                        return Err(io_err(&tile)(e))
                    }
                    _ => {}
                }
            }
            if !open.is_empty() && open.iter().all(|t| mine.contains(t)) {
                redone.push(p);
            }
        }
        let nanos = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        let path = dir.join(format!("{}-{nanos}.log", std::process::id()));
        let file = OpenOptions::new()
            .create_new(true)
            .append(true)
            .open(&path)
            .map_err(io_err(&path))?;
        Ok(Journal {
            file: Mutex::new(file),
            path,
            redone,
        })
    }

    fn line(&self, kind: char, t: TileId) -> Result<(), PathIo> {
        let text = format!("{kind} {} {} {}\n", t.z, t.x, t.y);
        let mut f = self.file.lock().unwrap_or_else(|e| e.into_inner());
        f.write_all(text.as_bytes()).map_err(io_err(&self.path))
    }

    /// Writes `bytes` as tile `t` at `path`: `b`, the file, then `e`.
    ///
    /// # Errors
    /// The tile or the journal that could not be written.
    pub(crate) fn write_tile(&self, t: TileId, path: &Path, bytes: &[u8]) -> Result<(), PathIo> {
        self.line('b', t)?;
        let written = std::fs::write(path, bytes).or_else(|e| {
            // A read-only tile in the way (only ever replaced under --force):
            // the rename this replaces would have replaced it.
            if e.kind() != std::io::ErrorKind::PermissionDenied || !path.is_file() {
                return Err(e);
            }
            std::fs::remove_file(path).and_then(|()| std::fs::write(path, bytes))
        });
        written.map_err(io_err(path))?;
        self.line('e', t)
    }

    /// The run ended: its journal and the earlier ones it made good go.
    ///
    /// # Errors
    /// A journal that could not be removed.
    pub(crate) fn finish(self) -> Result<(), PathIo> {
        drop(self.file);
        for p in self.redone.iter().chain([&self.path]) {
            std::fs::remove_file(p).map_err(io_err(p))?;
        }
        let dir = self.path.parent().unwrap_or(Path::new("."));
        let _ = std::fs::remove_dir(dir); // only when empty: other runs may be writing
        Ok(())
    }
}

/// Makes every directory the tiles of `tiles` go into, once each.
///
/// # Errors
/// The directory that could not be made.
pub(crate) fn make_dirs(
    tiles: &[TileId],
    path_of: impl Fn(TileId) -> PathBuf,
) -> Result<(), PathIo> {
    let dirs: BTreeSet<PathBuf> = tiles
        .iter()
        .filter_map(|&t| path_of(t).parent().map(Path::to_path_buf))
        .collect();
    for d in dirs {
        std::fs::create_dir_all(&d).map_err(io_err(&d))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unfinished_tiles_are_begun_and_not_ended_and_cut_lines_are_ignored() {
        let t = |z, x, y| TileId { z, x, y };
        let text = "b 3 1 2\nb 3 1 3\ne 3 1 2\nb 4 9 9\ne 4 9\nb 5 1";
        let open = unfinished(text);
        assert_eq!(open, [t(3, 1, 3), t(4, 9, 9)].into_iter().collect());
        assert!(unfinished("").is_empty());
    }
}
