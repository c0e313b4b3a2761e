//! `cota tiles` says what a run will cost before it starts
//! ([`mod@cota_core::tiles::estimate`]: tiles, lattice, memory, time) and refuses,
//! unless `--yes`, a run past [`MAX_TILES`] tiles or one whose estimated
//! memory is more than the machine has available.

use cota_core::tiles::{estimate, Estimate, LatticeFrame};

use crate::args::TilesArgs;
use crate::progress;

/// The most tiles a run makes without `--yes`.
pub const MAX_TILES: u64 = 1_000_000;

/// Prints the estimate of the pyramid of `frame` over `source_samples`
/// samples (stderr, not with `--quiet`) and refuses it past the limits
/// without `--yes`. Only whole runs are checked: the plan step and the
/// shards (`--plan`, `--shard`) are how a run past them is split.
pub fn check(a: &TilesArgs, frame: &LatticeFrame, source_samples: u64) -> anyhow::Result<()> {
    if a.plan || a.shard.is_some() {
        return Ok(());
    }
    let e = estimate(frame, a.min_zoom, source_samples);
    let available = available_memory_bytes();
    if !progress::quiet() {
        eprintln!("cota: estimate: {}", describe(&e, available));
    }
    let over = past_limits(&e, available);
    if over.is_empty() {
        return Ok(());
    }
    if a.yes {
        eprintln!(
            "cota: warning: going on past {} (--yes)",
            over.join(" and ")
        );
        return Ok(());
    }
    anyhow::bail!(
        "the estimate is past {}: expected --yes to make this pyramid (or a lower --max-zoom, a smaller --tile-cells, a --bbox or --crop window, or a sharded run: --plan --shards N)",
        over.join(" and ")
    )
}

/// What the estimate is past: the tile limit, the memory available.
fn past_limits(e: &Estimate, available: Option<u64>) -> Vec<String> {
    let mut over = Vec::new();
    if e.tiles > MAX_TILES {
        over.push(format!(
            "{} tiles (more than {})",
            count(e.tiles as f64),
            count(MAX_TILES as f64)
        ));
    }
    if let Some(av) = available.filter(|&av| e.memory_bytes > av) {
        over.push(format!(
            "{} of memory (more than the {} available)",
            bytes(e.memory_bytes as f64),
            bytes(av as f64)
        ));
    }
    over
}

/// The estimate in words.
fn describe(e: &Estimate, available: Option<u64>) -> String {
    let [w, h] = e.lattice_size;
    let avail = available.map_or_else(String::new, |av| {
        format!(" of {} available", bytes(av as f64))
    });
    format!(
        "{} tiles at zooms {} to {}; a lattice of {w} x {h} ({} samples); about {} of memory{avail}; roughly {} of CPU time",
        count(e.tiles as f64),
        e.zooms[0],
        e.zooms[1],
        count(e.lattice_samples() as f64),
        bytes(e.memory_bytes as f64),
        duration(e.cpu_seconds),
    )
}

/// An estimate's figure: whole from 10 up, one decimal below.
fn short(v: f64) -> String {
    if v >= 10.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.1}")
    }
}

/// A count: plain below ten thousand, else in thousands (k), millions (M)
/// or billions (G).
fn count(n: f64) -> String {
    match n {
        n if n < 1e4 => format!("{n:.0}"),
        n if n < 1e6 => format!("{} k", short(n / 1e3)),
        n if n < 1e9 => format!("{} M", short(n / 1e6)),
        n => format!("{} G", short(n / 1e9)),
    }
}

/// Bytes in MB or GB (10^6, 10^9).
fn bytes(b: f64) -> String {
    if b < 1e9 {
        format!("{} MB", short(b / 1e6))
    } else {
        format!("{} GB", short(b / 1e9))
    }
}

/// Seconds, minutes or hours.
fn duration(s: f64) -> String {
    match s {
        s if s < 90.0 => format!("{} s", short(s.max(0.1))),
        s if s < 5400.0 => format!("{} min", short(s / 60.0)),
        s => format!("{} h", short(s / 3600.0)),
    }
}

/// The memory available to this process: `MemAvailable` of
/// `/proc/meminfo`, or less where a cgroup's limit leaves less
/// (`memory.max` − `memory.current`); `None` where neither can be read.
pub fn available_memory_bytes() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| meminfo_field(&t, "MemAvailable:"));
    let read = |p: &str| std::fs::read_to_string(p).ok()?.trim().parse::<u64>().ok();
    let cgroup = read("/sys/fs/cgroup/memory.max")
        .map(|max| max.saturating_sub(read("/sys/fs/cgroup/memory.current").unwrap_or(0)));
    match (meminfo, cgroup) {
        (Some(m), Some(c)) => Some(m.min(c)),
        (m, c) => m.or(c),
    }
}

/// A `/proc/meminfo` field (`MemAvailable:`), in bytes.
fn meminfo_field(text: &str, field: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(field))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn meminfo_available_in_bytes() {
        let t = "MemTotal:       24684084 kB\nMemFree:        19427340 kB\nMemAvailable:   22000000 kB\n";
        assert_eq!(meminfo_field(t, "MemAvailable:"), Some(22_000_000 * 1024));
        assert_eq!(meminfo_field("MemFree: 1 kB", "MemAvailable:"), None);
    }

    #[test]
    fn figures_in_words() {
        assert_eq!(count(789.0), "789");
        assert_eq!(count(2_796_203.0), "2.8 M");
        assert_eq!(count(44_858.0), "45 k");
        assert_eq!(bytes(85.7e6), "86 MB");
        assert_eq!(bytes(3.5e9), "3.5 GB");
        assert_eq!(duration(63.0), "63 s");
        assert_eq!(duration(600.0), "10 min");
    }
}
