//! The plan step in parts, for a cluster: the plan step's work is each
//! shard's part read and resampled for the lattice's statistics and the
//! band corners ([`super::plan_frame`]); these parts are independent, so
//! they can run as separate processes, and a last cheap step merges them.
//!
//! Files under `OUT`, written atomically, removed by [`finish_plan`] once the
//! frame is written:
//!
//! * `.cota-layout-N.json` ([`super::frame::plan_layout_path`]): the frame
//!   before the statistics ([`super::plan_layout`]), written once, from the
//!   files' shapes;
//! * `.cota-plan-I-of-N.bin` ([`plan_part_path`]): part `I`'s statistics
//!   (exact bits) and band corners, with the settings' key. Little-endian
//!   binary with a magic; a truncated, foreign or inconsistent file is
//!   refused naming it, and its counts are checked against its length
//!   before anything is allocated.
//!
//! A part whose file is there is not computed again, so the parts are
//! idempotent and resumable; [`finish_plan`] computes (in turn) the parts
//! whose files are missing, so the plan step run alone is still the whole
//! plan step. Merging is order-free (minima, maxima, disjoint corners), so
//! the frame and the corners are the same bits however the parts ran.

use std::path::{Path, PathBuf};

use cota_core::tiles::{BandCorners, LevelStats, PartStats, TilerOptions};
use cota_core::HeightGrid;

use super::coarse::{bad, Reader};
use super::frame::{plan_layout_path, read_plan_layout, write_plan_layout, ShardFrame};
use super::plan_frame::{merge_plan, plan_part, PlanPart};
use super::pyramid::{write_file_atomically, PyramidError};
use super::shard::write_plan;

const PLAN_PART_MAGIC: &[u8; 8] = b"COTAPLN1";

/// The path of plan part `index` of `shards` under `out`.
pub fn plan_part_path(out: &Path, index: u32, shards: u32) -> PathBuf {
    out.join(format!(".cota-plan-{index}-of-{shards}.bin"))
}

/// The layout of `shards` shards under `out` when it is there (made with
/// the settings `key`), else the one `make` gives, written there; `None`
/// when `make` gives none (an input whose shards read every file: the plan
/// step then reads the whole input and has no parts).
///
/// # Errors
/// [`PyramidError::Shard`] for a layout of other settings or a damaged one,
/// [`PyramidError::Io`], and what `make` returns.
pub fn plan_layout_or<E: From<PyramidError>>(
    out: &Path,
    key: &str,
    shards: u32,
    make: impl FnOnce() -> Result<Option<ShardFrame>, E>,
) -> Result<Option<ShardFrame>, E> {
    if let Some(layout) = read_plan_layout(out, shards)? {
        if layout.key != key {
            let message = format!("expected the layout of a plan step with these settings and inputs ({key}), found one of other settings ({}); remove it or write elsewhere", layout.key);
            return Err(bad(&plan_layout_path(out, shards), message).into());
        }
        return Ok(Some(layout));
    }
    let Some(layout) = make()? else {
        return Ok(None);
    };
    std::fs::create_dir_all(out).map_err(|e| PyramidError::Io {
        path: out.to_path_buf(),
        source: e,
    })?;
    write_plan_layout(out, &layout)?;
    Ok(Some(layout))
}

/// What [`run_plan_part`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlanPartReport {
    /// True when the part's file was already there.
    pub skipped: bool,
    /// The input files read (none when skipped or when the part is empty).
    pub files_read: Vec<String>,
}

/// Plan part `index` of `layout`: computed ([`plan_part`], `read` as its
/// reader) and written to [`plan_part_path`] unless that file is there.
///
/// # Errors
/// What [`plan_part`] returns, [`PyramidError::Shard`] for a damaged part
/// file or one of other settings, [`PyramidError::Io`].
pub fn run_plan_part<E: From<PyramidError>>(
    out: &Path,
    layout: &ShardFrame,
    opts: &TilerOptions,
    index: u32,
    read: impl FnOnce(Option<Vec<PathBuf>>) -> Result<(HeightGrid, Vec<String>), E>,
) -> Result<PlanPartReport, E> {
    if read_plan_part(out, layout, index)?.is_some() {
        return Ok(PlanPartReport {
            skipped: true,
            files_read: Vec::new(),
        });
    }
    let part = plan_part(out, layout, opts, index, read)?;
    write_plan_part(out, layout, index, part.as_ref())?;
    Ok(PlanPartReport {
        skipped: false,
        files_read: part.map(|p| p.files_read).unwrap_or_default(),
    })
}

/// The plan step from `layout`: each part from its file under `out`, or
/// computed now, in turn (`read`, as [`plan_part`]'s); merged
/// ([`merge_plan`]) and written ([`write_plan`]: the band corners, then the
/// frame); then the layout and the part files are removed. Returns the frame,
/// the corners and how many parts came from their files.
///
/// # Errors
/// What [`plan_part`] and [`merge_plan`] return, [`PyramidError::Shard`]
/// for a damaged part file, [`PyramidError::Io`].
pub fn finish_plan<E: From<PyramidError>>(
    out: &Path,
    layout: ShardFrame,
    opts: &TilerOptions,
    mut read: impl FnMut(Option<Vec<PathBuf>>) -> Result<(HeightGrid, Vec<String>), E>,
) -> Result<(ShardFrame, BandCorners, u32), E> {
    let mut parts = Vec::new();
    let mut from_files = 0;
    for i in 0..layout.shards {
        let part = match read_plan_part(out, &layout, i)? {
            Some(p) => {
                from_files += 1;
                p
            }
            None => plan_part(out, &layout, opts, i, &mut read)?,
        };
        parts.extend(part);
    }
    let shards = layout.shards;
    let (frame, corners) = merge_plan(layout, parts, opts, out)?;
    write_plan(out, &frame, &corners)?;
    for i in 0..shards {
        remove(&plan_part_path(out, i, shards))?;
    }
    remove(&plan_layout_path(out, shards))?;
    Ok((frame, corners, from_files))
}

fn remove(path: &Path) -> Result<(), PyramidError> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(PyramidError::Io {
            path: path.to_path_buf(),
            source: e,
        }),
        _ => Ok(()),
    }
}

/// Writes part `index`'s file (`part`: `None` when the shard has no tile at
/// the band zoom or finer).
fn write_plan_part(
    out: &Path,
    layout: &ShardFrame,
    index: u32,
    part: Option<&PlanPart>,
) -> Result<(), PyramidError> {
    let mut b = PLAN_PART_MAGIC.to_vec();
    put_bytes(&mut b, layout.key.as_bytes());
    b.extend(index.to_le_bytes());
    b.extend(layout.shards.to_le_bytes());
    b.push(u8::from(part.is_some()));
    if let Some(p) = part {
        let (lo, hi) = p.stats.range_m.unwrap_or((f32::NAN, f32::NAN));
        b.push(u8::from(p.stats.range_m.is_some()));
        b.extend(lo.to_le_bytes());
        b.extend(hi.to_le_bytes());
        b.extend(p.stats.step_m[0].to_le_bytes());
        b.extend(p.stats.step_m[1].to_le_bytes());
        b.extend(p.stats.residual_m.to_le_bytes());
        let levels = &p.stats.levels;
        b.extend((levels.slope.len() as u64).to_le_bytes());
        for (a, s) in levels.slope.iter().zip(&levels.span_m) {
            b.extend(a.to_le_bytes());
            b.extend(s.to_le_bytes());
        }
        b.extend(p.corners.cells.to_le_bytes());
        for v in p.corners.window {
            b.extend(v.to_le_bytes());
        }
        b.extend((p.corners.heights_m.len() as u64).to_le_bytes());
        for h in &p.corners.heights_m {
            b.extend(h.to_le_bytes());
        }
        b.extend((p.files_read.len() as u64).to_le_bytes());
        for f in &p.files_read {
            put_bytes(&mut b, f.as_bytes());
        }
    }
    write_file_atomically(&plan_part_path(out, index, layout.shards), &b, false)
}

fn put_bytes(b: &mut Vec<u8>, s: &[u8]) {
    b.extend((s.len() as u64).to_le_bytes());
    b.extend(s);
}

/// Part `index`'s file under `out`: `None` when there is none, `Some(None)`
/// for a part without tiles.
fn read_plan_part(
    out: &Path,
    layout: &ShardFrame,
    index: u32,
) -> Result<Option<Option<PlanPart>>, PyramidError> {
    let path = plan_part_path(out, index, layout.shards);
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => {
            let message = format!("expected a plan part's file, could not read it: {e}");
            return Err(bad(&path, message));
        }
    };
    let mut r = Reader::new(&bytes, &path);
    r.magic(PLAN_PART_MAGIC)?;
    let key = text(&mut r)?;
    let (i, n) = (r.u32()?, r.u32()?);
    if key != layout.key || i != index || n != layout.shards {
        let message = format!(
            "expected part {index} of {} of the plan step with the settings {}, found part {i} of {n} with {key}; remove it or write elsewhere",
            layout.shards, layout.key
        );
        return Err(bad(&path, message));
    }
    if r.u8()? == 0 {
        return Ok(Some(None));
    }
    let part = part_body(&mut r)?;
    if r.left() != 0 {
        return Err(bad(
            &path,
            format!("expected the file to end, found {} more bytes", r.left()),
        ));
    }
    Ok(Some(Some(part)))
}

/// A part's statistics, corners and files.
fn part_body(r: &mut Reader<'_>) -> Result<PlanPart, PyramidError> {
    let has_range = r.u8()? != 0;
    let (lo, hi) = (r.f32()?, r.f32()?);
    let step_m = [r.f64()?, r.f64()?];
    let residual_m = r.f64()?;
    let n = r.count(16)?;
    let mut levels = LevelStats::default();
    for _ in 0..n {
        levels.slope.push(r.f64()?);
        levels.span_m.push(r.f64()?);
    }
    let cells = r.u64()?;
    let window = [r.u64()?, r.u64()?, r.u64()?, r.u64()?];
    let n = r.count(4)?;
    let mut heights_m = Vec::with_capacity(n);
    for _ in 0..n {
        heights_m.push(r.f32()?);
    }
    let files = r.count(8)?;
    let files_read = (0..files).map(|_| text(r)).collect::<Result<_, _>>()?;
    Ok(PlanPart {
        stats: PartStats {
            range_m: has_range.then_some((lo, hi)),
            step_m,
            levels,
            residual_m,
        },
        corners: BandCorners {
            cells,
            window,
            heights_m,
        },
        files_read,
    })
}

/// A length-prefixed UTF-8 string.
fn text(r: &mut Reader<'_>) -> Result<String, PyramidError> {
    let n = r.count(1)?;
    let b = r.take(n)?;
    Ok(String::from_utf8_lossy(b).into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{
        mosaic_frame, plan_layout, read_band_corners, read_part_files, read_shard_frame,
        stream_frame, summarize_files,
    };
    use cota_core::grid::mosaic::MosaicOptions;
    use cota_core::tiles::LatticeOptions;
    use cota_io::{ReadOptions, RegionOptions};

    /// The two-tile mosaic: the plan step run in parts, in any order and
    /// with a part run twice, writes the frame and corners of the plan step
    /// run in turn, byte for byte; the layout and part files are then gone;
    /// a part file of other settings or a damaged one is refused naming it.
    #[test]
    fn plan_in_parts_is_the_plan_in_turn() {
        let (Some(w), Some(e)) = (
            cota_fixtures::shared("srtm/N00E010.hgt"),
            cota_fixtures::shared("srtm/N00E011.hgt.zip"),
        ) else {
            return;
        };
        let inputs = vec![w, e];
        let lo = LatticeOptions::DEFAULT.with_max_zoom(Some(11));
        let opts = TilerOptions::DEFAULT;
        let sums = summarize_files(&inputs, &ReadOptions::DEFAULT).unwrap();
        let m = mosaic_frame(&sums, &lo, &MosaicOptions::DEFAULT)
            .unwrap()
            .unwrap();
        let read = |f| read_part_files(&inputs, f, &RegionOptions::DEFAULT);
        let n = 4;
        let whole = tempfile::tempdir().unwrap();
        let (f0, c0) = stream_frame(whole.path(), "k".into(), n, &m, &opts, read).unwrap();
        write_plan(whole.path(), &f0, &c0).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path();
        let make = || Ok::<_, PyramidError>(Some(plan_layout("k".into(), n, &m, &opts)?));
        let layout = plan_layout_or(out, "k", n, make).unwrap().unwrap();
        assert!(plan_layout_path(out, n).is_file());
        for i in [3, 1, 0, 1] {
            let r = run_plan_part(out, &layout, &opts, i, read).unwrap();
            assert_eq!(r.skipped, i == 1 && plan_part_path(out, 0, n).is_file());
        }
        // Part 2 is left for the plan step to compute.
        let again = plan_layout_or(out, "k", n, || -> Result<_, PyramidError> {
            panic!("made again")
        })
        .unwrap();
        let (f1, _, from_files) = finish_plan(out, again.unwrap(), &opts, read).unwrap();
        assert_eq!(from_files, 3);
        assert_eq!(f1, f0);
        let file = |d: &Path, p: PathBuf| std::fs::read(d.join(p.file_name().unwrap())).unwrap();
        for p in [
            crate::shard_frame_path(whole.path(), n),
            crate::corners_path(whole.path(), n),
        ] {
            assert_eq!(file(out, p.clone()), file(whole.path(), p));
        }
        assert!(read_band_corners(out, &read_shard_frame(out, n).unwrap().unwrap()).is_ok());
        assert!(!plan_layout_path(out, n).exists());
        assert!((0..n).all(|i| !plan_part_path(out, i, n).exists()));

        // Refusals name the file.
        let other = tempfile::tempdir().unwrap();
        plan_layout_or(other.path(), "k", n, make).unwrap();
        let msg = plan_layout_or(other.path(), "k2", n, make)
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains(".cota-layout-4.json") && msg.contains("other settings"),
            "{msg}"
        );
        run_plan_part(other.path(), &layout, &opts, 1, read).unwrap();
        let p = plan_part_path(other.path(), 1, n);
        let bytes = std::fs::read(&p).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() - 3]).unwrap();
        let msg = run_plan_part(other.path(), &layout, &opts, 1, read)
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains(".cota-plan-1-of-4.bin") && msg.contains("expected"),
            "{msg}"
        );
        let mut foreign = layout.clone();
        foreign.key = "k3".into();
        std::fs::write(&p, &bytes).unwrap();
        let msg = run_plan_part(other.path(), &foreign, &opts, 1, read)
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains(".cota-plan-1-of-4.bin") && msg.contains("k3"),
            "{msg}"
        );
    }
}
