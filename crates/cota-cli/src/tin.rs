//! `cota mesh --mesh tin`: an irregular triangulation with the same
//! guaranteed error as the bitree's mesh and fewer triangles
//! (`cota_core::tin`). Kept apart from the bitree path; it returns what the
//! shared report, check and write path of `cota mesh` needs.

use std::time::Instant;

use anyhow::bail;
use cota_core::tin::{self, TinOptions};
use cota_core::{Bitree, CheckOptions, HeightGrid, Mesh};

use crate::args::{HierarchyArg, MeshArgs};
use crate::progress;

/// A TIN and what the report needs.
pub struct TinRun {
    pub mesh: Mesh,
    pub threshold_m: f64,
    pub build_ms: f64,
    pub extract_ms: f64,
    pub check: CheckOptions,
}

/// Rejects the flags the TIN path does not take, before any long work.
pub fn validate(a: &MeshArgs) -> anyhow::Result<()> {
    if a.hierarchy != HierarchyArg::Bitree {
        bail!(
            "--mesh tin: expected --hierarchy bitree (the TIN is decimated from the bitree's mesh)"
        );
    }
    if !crate::refine::is_fast(&a.refine) {
        bail!(
            "--mesh tin: expected --mode conforming and --criterion max-error (a vertical bound)"
        );
    }
    if a.strip || a.strip_method.is_some() {
        bail!(
            "--mesh tin: triangle strips follow the bitree; expected no --strip or --strip-method"
        );
    }
    Ok(())
}

/// Builds the bitree (with a progress bar on a terminal), then the TIN.
pub fn run(grid: &HeightGrid, a: &MeshArgs) -> anyhow::Result<TinRun> {
    let opts = match a.max_triangles {
        Some(n) => TinOptions::max_triangles(n),
        None => TinOptions::max_error_m(a.max_error.unwrap_or(1.0)),
    }
    .with_lock_border(a.lock_border);
    let t = Instant::now();
    let pb = progress::bar(0, "building");
    let tree = Bitree::build_with_progress(grid, &|done, total| {
        pb.set_length(total as u64);
        pb.set_position(done as u64);
    })?;
    pb.finish_and_clear();
    let build_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let x = tin::build_from(&tree, &opts)?;
    Ok(TinRun {
        mesh: x.mesh,
        threshold_m: x.threshold_m,
        build_ms,
        extract_ms: t.elapsed().as_secs_f64() * 1e3,
        check: CheckOptions::tin(x.threshold_m),
    })
}
