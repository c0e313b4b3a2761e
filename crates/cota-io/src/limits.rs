//! The memory budget of the readers: how many samples one file may declare
//! ([`default_max_samples`], [`ReadOptions::max_samples`]) and allocation that
//! fails with a "too large" error instead of aborting.
//!
//! Every reader checks the dimensions its header declares against the limit
//! before it allocates, and compressed inputs stop decompressing once their
//! output exceeds what the inner format can hold within the limit. The default
//! limit comes from the machine's memory: a whole `cota mesh` run peaks at
//! about 7 bytes per sample plus its output mesh and the decoder's scratch, so
//! the default allows one sample per [`BYTES_PER_SAMPLE`] bytes of memory
//! (the smaller of `MemTotal` in `/proc/meminfo` and the cgroup's
//! `memory.max`), at most [`DEFAULT_CAP_SAMPLES`]. Where the memory cannot be
//! read, it is [`FALLBACK_MAX_SAMPLES`].

use std::sync::OnceLock;

use cota_core::grid::MAX_SAMPLES;

use crate::dem::ReadOptions;
use crate::error::ReadErrorKind;

/// Bytes of memory the default limit reserves per sample.
pub const BYTES_PER_SAMPLE: u64 = 16;

/// The largest default limit, whatever the memory: 2^30 samples (32768²,
/// 80 one-arc-second SRTM tiles). Larger inputs need an explicit
/// [`ReadOptions::max_samples`] (`--max-samples`), up to [`MAX_SAMPLES`].
pub const DEFAULT_CAP_SAMPLES: u64 = 1 << 30;

/// The default limit where the machine's memory cannot be read: 2^28 samples.
pub const FALLBACK_MAX_SAMPLES: u64 = 1 << 28;

/// The largest `.hgt` a compressed input may expand to unless the limit is
/// set explicitly: a 3601² one-arc-second tile, 2·3601² bytes.
pub const HGT_MAX_BYTES: u64 = 2 * 3601 * 3601;

/// The default sample limit of this machine (computed once): memory /
/// [`BYTES_PER_SAMPLE`], at most [`DEFAULT_CAP_SAMPLES`], or
/// [`FALLBACK_MAX_SAMPLES`] where the memory is unknown.
pub fn default_max_samples() -> u64 {
    static LIMIT: OnceLock<u64> = OnceLock::new();
    *LIMIT.get_or_init(|| match machine_memory_bytes() {
        Some(bytes) => (bytes / BYTES_PER_SAMPLE).clamp(1, DEFAULT_CAP_SAMPLES),
        None => FALLBACK_MAX_SAMPLES,
    })
}

/// The smaller of the total memory and the cgroup v2 limit, in bytes.
fn machine_memory_bytes() -> Option<u64> {
    let total = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| meminfo_total_bytes(&s));
    let cgroup = std::fs::read_to_string("/sys/fs/cgroup/memory.max")
        .ok()
        .and_then(|s| s.trim().parse::<u64>().ok());
    match (total, cgroup) {
        (Some(t), Some(c)) => Some(t.min(c)),
        (t, c) => t.or(c),
    }
}

/// `MemTotal` of a `/proc/meminfo` text, in bytes.
fn meminfo_total_bytes(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

/// The limit `opts` sets: its own, else the machine's default; never above
/// [`MAX_SAMPLES`].
pub fn max_samples(opts: &ReadOptions) -> u64 {
    opts.max_samples
        .unwrap_or_else(default_max_samples)
        .min(MAX_SAMPLES)
}

/// Refuses a `width`×`height` header (zero sides, or over the limit).
pub(crate) fn check(width: u64, height: u64, opts: &ReadOptions) -> Result<(), ReadErrorKind> {
    cota_core::grid::check_dimensions(width, height).map_err(crate::error::too_large)?;
    let max = max_samples(opts);
    if width.saturating_mul(height) > max {
        return Err(ReadErrorKind::TooLarge { width, height, max });
    }
    Ok(())
}

/// The most bytes a gzipped input may expand to: a `.hgt` (by its name, or
/// content with no magic, which only a `.hgt` can be) at most
/// [`HGT_MAX_BYTES`] unless the limit is set explicitly (then 2 bytes per
/// sample of it); anything else 8 bytes per sample of the limit (f64
/// samples) plus 64 KiB of headers.
pub(crate) fn gzip_cap(hgt: bool, opts: &ReadOptions) -> u64 {
    match (hgt, opts.max_samples) {
        (true, None) => HGT_MAX_BYTES,
        (true, Some(_)) => max_samples(opts).saturating_mul(2),
        (false, _) => max_samples(opts).saturating_mul(8).saturating_add(1 << 16),
    }
}

/// The most bytes one sample may take in any format read whole (ESRI and
/// USGS ASCII text written with long decimals, e.g. `%.18e`, take up to 25;
/// binary formats at most 8).
pub const MAX_FILE_BYTES_PER_SAMPLE: u64 = 32;

/// Room for headers, metadata and container overhead on top of the samples.
pub const FILE_HEADER_BYTES: u64 = 1 << 20;

/// The largest file a reader loads into memory under `opts`:
/// [`MAX_FILE_BYTES_PER_SAMPLE`] bytes per sample of the limit plus
/// [`FILE_HEADER_BYTES`]. A larger file cannot hold a grid within the limit,
/// so it is refused before it is read.
pub fn max_file_bytes(opts: &ReadOptions) -> u64 {
    max_samples(opts)
        .saturating_mul(MAX_FILE_BYTES_PER_SAMPLE)
        .saturating_add(FILE_HEADER_BYTES)
}

/// Refuses a file of `bytes` bytes over [`max_file_bytes`].
pub(crate) fn check_file_bytes(bytes: u64, opts: &ReadOptions) -> Result<(), ReadErrorKind> {
    if bytes > max_file_bytes(opts) {
        return Err(file_too_large(bytes, opts));
    }
    Ok(())
}

/// The error for a file of `bytes` bytes over [`max_file_bytes`].
pub(crate) fn file_too_large(bytes: u64, opts: &ReadOptions) -> ReadErrorKind {
    ReadErrorKind::FileTooLarge {
        bytes,
        limit: max_file_bytes(opts),
        max_samples: max_samples(opts),
        per_sample: MAX_FILE_BYTES_PER_SAMPLE,
    }
}

/// Appends at most `limit` bytes of `reader` to `buf`, stopping while it
/// reads: `Ok(true)` when the input ended within the limit, `Ok(false)` when
/// more followed (then `buf` holds one byte past the limit). Whatever a
/// file's size says, a device, a pipe or a file that grows is never read
/// past `limit + 1` bytes.
///
/// # Errors
/// The reader's I/O error.
pub fn read_capped(
    reader: &mut impl std::io::Read,
    limit: u64,
    buf: &mut Vec<u8>,
) -> std::io::Result<bool> {
    use std::io::Read;
    let before = buf.len() as u64;
    reader.take(limit.saturating_add(1)).read_to_end(buf)?;
    Ok(buf.len() as u64 - before <= limit)
}

/// Reads the file at `path` whole, at most `limit` bytes of it (see
/// [`read_capped`]).
///
/// # Errors
/// The I/O error, or one of kind [`std::io::ErrorKind::FileTooLarge`]
/// saying "more than `limit` bytes" when the file holds more.
pub fn read_file_capped(path: &std::path::Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let mut file = std::fs::File::open(path)?;
    let mut buf = Vec::new();
    if read_capped(&mut file, limit, &mut buf)? {
        Ok(buf)
    } else {
        Err(std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!("more than {limit} bytes, the most read"),
        ))
    }
}

/// An empty vector with room for `n` items, or a "too large" error naming
/// `what` and the bytes asked for, instead of an abort.
pub(crate) fn try_vec<T>(n: usize, what: &str) -> Result<Vec<T>, ReadErrorKind> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| ReadErrorKind::OutOfMemory {
            what: what.to_string(),
            bytes: (n as u64).saturating_mul(std::mem::size_of::<T>() as u64),
        })?;
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meminfo_parses_kilobytes() {
        let text = "MemTotal:       24684084 kB\nMemFree:        19427340 kB\n";
        assert_eq!(meminfo_total_bytes(text), Some(24_684_084 * 1024));
        assert_eq!(meminfo_total_bytes("MemFree: 1 kB"), None);
    }

    #[test]
    fn default_is_bounded() {
        let d = default_max_samples();
        assert!((1..=DEFAULT_CAP_SAMPLES).contains(&d), "{d}");
    }

    #[test]
    fn explicit_limit_wins_and_is_capped() {
        let o = ReadOptions::DEFAULT.with_max_samples(Some(100));
        assert_eq!(max_samples(&o), 100);
        assert!(check(10, 10, &o).is_ok());
        let e = check(11, 10, &o).unwrap_err();
        assert!(matches!(e, ReadErrorKind::TooLarge { max: 100, .. }), "{e}");
        let o = ReadOptions::DEFAULT.with_max_samples(Some(u64::MAX));
        assert_eq!(max_samples(&o), MAX_SAMPLES);
    }

    #[test]
    fn hgt_cap_is_one_tile_unless_raised() {
        assert_eq!(gzip_cap(true, &ReadOptions::DEFAULT), 2 * 3601 * 3601);
        let o = ReadOptions::DEFAULT.with_max_samples(Some(10_000 * 10_000));
        assert_eq!(gzip_cap(true, &o), 2 * 10_000 * 10_000);
    }

    #[test]
    fn file_bytes_follow_the_sample_limit() {
        let o = ReadOptions::DEFAULT.with_max_samples(Some(1000));
        assert_eq!(max_file_bytes(&o), 32_000 + (1 << 20));
        assert!(check_file_bytes(32_000 + (1 << 20), &o).is_ok());
        let e = check_file_bytes(32_001 + (1 << 20), &o).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("too large") && msg.contains("1000 samples"),
            "{msg}"
        );
    }

    #[test]
    fn failed_allocation_is_an_error() {
        let e = try_vec::<f32>(usize::MAX / 2, "heights").unwrap_err();
        assert!(e.to_string().contains("too large"), "{e}");
    }
}
