//! `memory`: peak heap of cota on the large grids, phase by phase, measured by
//! a counting global allocator, against the memory target of ≤ 8 bytes per
//! sample (1.5 × the grid's `f32` size + 2 bytes per sample for the
//! hierarchy).
//!
//! For each large grid (`srtm3601`, `mosaic8`; see [`cota_bench::big`] for what
//! they are and where they come from), it reports:
//!
//! * `read`: `cota_io::read_dem` of every file, `cota_core::mosaic` and the
//!   harmonic void fill (what `cota mesh FILES…` does first);
//! * `build`: `Bitree::build` with the grid alive;
//! * `extract E`: `Bitree::extract(max_error_m(E))` with grid and tree alive;
//!   the output mesh is reported on its own (it is the caller's, and its size
//!   depends on E, not on the hierarchy);
//! * `strip` and `measure` of that mesh (`cota_core::strip::stripify_bitree`,
//!   `cota_core::measure`), which `cota mesh` also runs for its report.
//!
//! Columns: *peak* is the largest heap in use during the phase (everything
//! alive, from the process's start); *live after* is the heap in use when the
//! phase ends (after its temporaries are freed); *VmHWM* is the kernel's peak
//! resident set over the phase (`/proc/self/status`, reset through
//! `/proc/self/clear_refs` before each phase; blank where unavailable). Bytes
//! per sample divide by the grid's W·H; *÷ target* divides the peak by
//! 8 bytes × W·H.
//!
//! Counting: every `alloc`, `alloc_zeroed`, `dealloc` and `realloc` adds or
//! removes its size; a `realloc` that moves counts as the larger of the two
//! sizes, not their sum (the allocator may move pages without a copy).
//!
//! Run: `cargo run --release -p cota-bench --bin memory [-- --only srtm3601|mosaic8] [-- --e 1,5,20]`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::Context;
use cota_bench::big::{big_files, load_big, seam_line, BigGrid};
use cota_core::strip::stripify_bitree;
use cota_core::{Bitree, ExtractOptions, MeshVertex};

/// Heap bytes in use.
static CURRENT: AtomicUsize = AtomicUsize::new(0);
/// Largest [`CURRENT`] since the last [`reset_peak`].
static PEAK: AtomicUsize = AtomicUsize::new(0);

/// [`System`], counting the bytes it hands out.
struct Counting;

fn grow(n: usize) {
    let now = CURRENT.fetch_add(n, Ordering::Relaxed) + n;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

fn shrink(n: usize) {
    CURRENT.fetch_sub(n, Ordering::Relaxed);
}

// SAFETY: every method forwards to `System` with the caller's arguments
// unchanged and returns its result; the counters are plain atomics.
#[allow(
    unsafe_code,
    reason = "a counting GlobalAlloc must implement an unsafe trait"
)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded as is; the caller upholds `alloc`'s contract.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grow(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded as is.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grow(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded as is; `ptr` came from this allocator, i.e. `System`.
        unsafe { System.dealloc(ptr, layout) };
        shrink(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded as is.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                grow(new_size - layout.size());
            } else {
                shrink(layout.size() - new_size);
            }
        }
        p
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

/// Starts a phase: the peak becomes the current use, and the kernel's
/// resident-set peak is reset (best effort).
fn reset_peak() {
    PEAK.store(CURRENT.load(Ordering::Relaxed), Ordering::Relaxed);
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// The kernel's peak resident set since the last reset, bytes.
fn vm_hwm() -> Option<usize> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: usize = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// One measured phase.
struct Phase {
    name: String,
    peak: usize,
    live_after: usize,
    hwm: Option<usize>,
    ms: f64,
    extra: String,
}

fn measure<T>(name: &str, f: impl FnOnce() -> anyhow::Result<T>) -> anyhow::Result<(T, Phase)> {
    reset_peak();
    let t0 = Instant::now();
    let out = f()?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let phase = Phase {
        name: name.to_string(),
        peak: PEAK.load(Ordering::Relaxed),
        live_after: CURRENT.load(Ordering::Relaxed),
        hwm: vm_hwm(),
        ms,
        extra: String::new(),
    };
    Ok((out, phase))
}

const MB: f64 = 1024.0 * 1024.0;
/// The target, bytes per sample.
const TARGET_B_PER_SAMPLE: f64 = 8.0;

fn run(big: BigGrid, read: Phase, es: &[f64]) -> anyhow::Result<()> {
    let grid = &big.grid;
    let n = grid.len() as f64;
    println!(
        "### {} ({}×{}, {:.2} M samples)\n",
        big.name,
        grid.width(),
        grid.height(),
        n / 1e6
    );
    println!("{}.", big.description);
    if let Some(s) = &big.seams {
        println!("{}.", seam_line(s));
    }
    println!(
        "Grid as f32: {:.1} MB (4 B/sample); target: peak ≤ {:.1} MB (8 B/sample).\n",
        4.0 * n / MB,
        TARGET_B_PER_SAMPLE * n / MB
    );
    let before_build = CURRENT.load(Ordering::Relaxed);
    let (tree, mut build) = measure("build", || Ok(Bitree::build(grid)?))?;
    let hierarchy = build.live_after.saturating_sub(before_build);
    build.extra = format!(
        "hierarchy (live after − before): {:.1} MB = {:.2} B/sample",
        hierarchy as f64 / MB,
        hierarchy as f64 / n
    );
    let mut phases = vec![read, build];
    for &e in es {
        let before = CURRENT.load(Ordering::Relaxed);
        let (x, mut p) = measure(&format!("extract {e} m"), || {
            Ok(tree.extract(&ExtractOptions::max_error_m(e))?)
        })?;
        let (vs, ts) = (
            std::mem::size_of::<MeshVertex>(),
            std::mem::size_of::<[u32; 3]>(),
        );
        let mesh_bytes = x.mesh.vertices.capacity() * vs + x.mesh.triangles.capacity() * ts;
        let mesh_used = x.mesh.vertices.len() * vs + x.mesh.triangles.len() * ts;
        let transient = p.peak.saturating_sub(before).saturating_sub(mesh_bytes);
        p.extra = format!(
            "mesh {} tris, {} verts: {:.1} MB used ({:.2} B/sample), {:.1} MB allocated (Vec capacity); transient beyond grid + tree + mesh {:.1} MB; peak less the mesh {:.2} B/sample",
            x.mesh.triangles.len(),
            x.mesh.vertices.len(),
            mesh_used as f64 / MB,
            mesh_used as f64 / n,
            mesh_bytes as f64 / MB,
            transient as f64 / MB,
            p.peak.saturating_sub(mesh_bytes) as f64 / n
        );
        phases.push(p);
        // What `cota mesh` also does with the mesh: the strip statistics and
        // the exact error measure (peaks with grid, tree and mesh alive).
        let (strip, mut ps) = measure(&format!("  strip of the {e} m mesh"), || {
            Ok(stripify_bitree(&x.mesh)?)
        })?;
        ps.extra = format!("{} strip indices", strip.strip.indices.len());
        drop(strip);
        phases.push(ps);
        let (_, pm) = measure(&format!("  measure of the {e} m mesh"), || {
            Ok(cota_core::measure(grid, &x.mesh))
        })?;
        phases.push(pm);
        drop(x);
    }
    println!("| phase | ms | peak MB | peak B/sample | peak ÷ target | live after MB | VmHWM MB | notes |");
    println!("|---|---:|---:|---:|---:|---:|---:|---|");
    for p in &phases {
        println!(
            "| {} | {:.0} | {:.1} | {:.2} | {:.2} | {:.1} | {} | {} |",
            p.name,
            p.ms,
            p.peak as f64 / MB,
            p.peak as f64 / n,
            p.peak as f64 / (TARGET_B_PER_SAMPLE * n),
            p.live_after as f64 / MB,
            p.hwm
                .map_or(String::new(), |h| format!("{:.1}", h as f64 / MB)),
            p.extra
        );
    }
    println!();
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut only: Option<String> = None;
    let mut es = vec![1.0, 5.0, 20.0];
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--only" => {
                only = args.get(i + 1).cloned();
                i += 1;
            }
            "--e" => {
                let v = args
                    .get(i + 1)
                    .context("--e: expected a list such as 1,5,20")?;
                es = v
                    .split(',')
                    .map(|s| {
                        s.parse::<f64>()
                            .with_context(|| format!("--e: bad number {s:?}"))
                    })
                    .collect::<anyhow::Result<_>>()?;
                i += 1;
            }
            other => anyhow::bail!("unknown argument {other:?}; expected --only NAME or --e LIST"),
        }
        i += 1;
    }
    let scratch = tempfile::tempdir().context("a scratch directory")?;
    let files =
        big_files(scratch.path(), |m| eprintln!("memory: {m}")).map_err(anyhow::Error::msg)?;
    println!(
        "Peak heap per phase (counting global allocator; {} rayon threads).\n",
        rayon::current_num_threads()
    );
    let cases = [
        (
            "srtm3601",
            files.tile3601.clone(),
            files.tile3601_note.clone(),
        ),
        ("mosaic8", files.mosaic8.clone(), files.mosaic8_note.clone()),
    ];
    for (name, paths, note) in cases {
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        let (big, read) = measure("read + mosaic + fill", || {
            load_big(name, &paths, &note).map_err(anyhow::Error::msg)
        })?;
        run(big, read, &es)?;
    }
    Ok(())
}
