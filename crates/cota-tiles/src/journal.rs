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
use std::fs::{File, OpenOptions, TryLockError};
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
    /// Gone runs' journals (held locked) whose unfinished tiles, if any,
    /// this run makes again.
    redone: Vec<(PathBuf, File)>,
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

/// What a look at another run's journal found.
enum Owner {
    /// Its run is gone (its lock was free): held locked by this run now.
    Gone(File),
    /// Its run still writes (its lock is held), or the journal is gone.
    Live,
    /// The file system keeps no locks: a journal with no unfinished tile
    /// may be a live run's between two tiles.
    Unknown(File),
}

/// Takes the lock of the journal at `p` if its run is gone.
fn owner(p: &Path) -> Result<Owner, PathIo> {
    let file = match File::open(p) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Owner::Live),
        Err(e) => return Err(io_err(p)(e)),
    };
    match file.try_lock() {
        Ok(()) => Ok(Owner::Gone(file)),
        Err(TryLockError::WouldBlock) => Ok(Owner::Live),
        Err(TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => {
            Ok(Owner::Unknown(file))
        }
        Err(TryLockError::Error(e)) => Err(io_err(p)(e)),
    }
}

/// Locks the journal folder while a run looks at the journals in it, so that
/// two runs starting together never take each other's for a gone run's.
/// `None` where folders cannot be opened or locked (a run then relies on the
/// journals' own locks).
fn lock_folder(dir: &Path) -> Option<File> {
    let f = File::open(dir).ok()?;
    f.lock().ok()?;
    Some(f)
}

/// Makes the journal folder and locks it; made again if a run that ended
/// removed it before the lock was taken.
fn make_and_lock_folder(dir: &Path) -> Result<Option<File>, PathIo> {
    loop {
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        let lock = lock_folder(dir);
        if dir.is_dir() {
            return Ok(lock);
        }
    }
}

/// The unfinished tiles of a journal, read from its open `file`.
fn read_unfinished(p: &Path, mut file: &File) -> Result<HashSet<TileId>, PathIo> {
    let mut text = String::new();
    std::io::Read::read_to_string(&mut file, &mut text).map_err(io_err(p))?;
    Ok(unfinished(&text))
}

/// Removes a file (a tile's, a journal's), if there.
fn remove_if_there(tile: &Path) -> Result<(), PathIo> {
    match std::fs::remove_file(tile) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(io_err(tile)(e)),
        _ => Ok(()),
    }
}

impl Journal {
    /// Removes the files of `tiles` that earlier runs, now gone, left
    /// unfinished, then opens this run's journal under `out`, locked while
    /// the run lasts (a journal whose lock is free is a gone run's).
    ///
    /// # Errors
    /// The journal or tile that could not be read, removed or created.
    pub(crate) fn open(
        out: &Path,
        tiles: &[TileId],
        path_of: impl Fn(TileId) -> PathBuf,
    ) -> Result<Journal, PathIo> {
        let dir = out.join(JOURNAL_DIR);
        let _looking = make_and_lock_folder(&dir)?;
        let mine: HashSet<TileId> = tiles.iter().copied().collect();
        let mut redone = Vec::new();
        for entry in std::fs::read_dir(&dir).map_err(io_err(&dir))? {
            let p = entry.map_err(io_err(&dir))?.path();
            let (file, known_gone) = match owner(&p)? {
                Owner::Gone(f) => (f, true),
                Owner::Unknown(f) => (f, false),
                Owner::Live => continue,
            };
            let open = read_unfinished(&p, &file)?;
            for &t in open.iter().filter(|t| mine.contains(t)) {
                remove_if_there(&path_of(t))?;
            }
            if (known_gone || !open.is_empty()) && open.iter().all(|t| mine.contains(t)) {
                redone.push((p, file));
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
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => {}
            Err(e) => return Err(io_err(&path)(e.into())),
        }
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
        // The folder's lock first: no run starting now may take this journal
        // for a gone run's once its own lock goes with the file.
        let dir = self.path.parent().unwrap_or(Path::new("."));
        let _ending = lock_folder(dir);
        drop(self.file);
        for (p, _locked) in &self.redone {
            remove_if_there(p)?; // absent only where no lock is kept (Owner::Unknown)
        }
        std::fs::remove_file(&self.path).map_err(io_err(&self.path))?;
        let _ = std::fs::remove_dir(dir); // only when empty: other runs may be writing
        Ok(())
    }
}

/// The reduce's clean-up, once every shard has recorded its end: removes
/// the journals of gone runs that left no tile unfinished (a run killed
/// between two tiles), and the folder when empty. Returns the gone runs'
/// journals that name unfinished tiles, left in place.
///
/// # Errors
/// The journal that could not be read or removed.
pub(crate) fn clear_gone_journals(out: &Path) -> Result<Vec<(PathBuf, Vec<TileId>)>, PathIo> {
    let dir = out.join(JOURNAL_DIR);
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let _looking = lock_folder(&dir);
    let mut left = Vec::new();
    for entry in std::fs::read_dir(&dir).map_err(io_err(&dir))? {
        let p = entry.map_err(io_err(&dir))?.path();
        let Owner::Gone(file) = owner(&p)? else {
            continue;
        };
        let mut open: Vec<TileId> = read_unfinished(&p, &file)?.into_iter().collect();
        if open.is_empty() {
            remove_if_there(&p)?;
        } else {
            open.sort_by_key(|t| (t.z, t.x, t.y));
            left.push((p, open));
        }
    }
    let _ = std::fs::remove_dir(&dir);
    Ok(left)
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

    fn tile_at(out: &Path) -> impl Fn(TileId) -> PathBuf + '_ {
        move |t| out.join(format!("{}-{}-{}.terrain", t.z, t.x, t.y))
    }

    #[test]
    fn a_killed_runs_journal_goes_even_with_no_tile_unfinished() {
        let out = tempfile::tempdir().unwrap();
        let dir = out.path().join(JOURNAL_DIR);
        std::fs::create_dir_all(&dir).unwrap();
        // Killed between two tiles (no lock held: the process is gone).
        std::fs::write(dir.join("1-1.log"), "b 3 1 2\ne 3 1 2\n").unwrap();
        let tiles = [TileId { z: 3, x: 1, y: 3 }];
        let j = Journal::open(out.path(), &tiles, tile_at(out.path())).unwrap();
        assert_eq!(j.redone.len(), 1);
        j.finish().unwrap();
        assert!(!dir.exists(), "the gone run's journal was left");
    }

    #[test]
    fn a_live_runs_journal_is_neither_taken_nor_removed() {
        let out = tempfile::tempdir().unwrap();
        let t = |y| TileId { z: 3, x: 1, y };
        let live = Journal::open(out.path(), &[t(1)], tile_at(out.path())).unwrap();
        live.line('b', t(1)).unwrap();
        std::fs::write(tile_at(out.path())(t(1)), b"half").unwrap();
        let other = Journal::open(out.path(), &[t(1), t(2)], tile_at(out.path())).unwrap();
        assert!(other.redone.is_empty());
        assert!(
            tile_at(out.path())(t(1)).is_file(),
            "a live run's tile was removed"
        );
        other.finish().unwrap();
        assert!(live.path.is_file());
        assert!(clear_gone_journals(out.path()).unwrap().is_empty());
        assert!(
            live.path.is_file(),
            "the reduce removed a live run's journal"
        );
        live.finish().unwrap();
        assert!(!out.path().join(JOURNAL_DIR).exists());
    }

    #[test]
    fn the_reduce_keeps_and_names_journals_with_unfinished_tiles() {
        let out = tempfile::tempdir().unwrap();
        let dir = out.path().join(JOURNAL_DIR);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("1-1.log"), "b 3 1 2\ne 3 1 2\n").unwrap();
        std::fs::write(dir.join("2-1.log"), "b 4 0 0\n").unwrap();
        let left = clear_gone_journals(out.path()).unwrap();
        assert_eq!(
            left,
            vec![(dir.join("2-1.log"), vec![TileId { z: 4, x: 0, y: 0 }])]
        );
        assert!(!dir.join("1-1.log").exists());
    }
}
