//! `cota mesh`: read, fill voids, mesh with `cota_core::Mesher` (the
//! exact-error bitree's extraction, the criterion-driven refinement, or the
//! restricted quadtree), measure the mesh exactly, optionally check it and
//! strip it, and write it atomically.

use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use cota_core::criteria::AvoidVoids;
use cota_core::criteria::{Criterion, CriterionError};
use cota_core::mesh::check::check_mesh_with_progress;
use cota_core::mesh::metrics::measure_with_progress;
use cota_core::strip::{stripify_bitree_with, MeshStrip};
use cota_core::{
    check_mesh, CriterionOptions, HeightGrid, HierarchyKind, Mesh, MeshPlan, Meshed, Mesher,
    Metrics, Mode,
};
use cota_io::export::{write_mesh_to, Coords, ExportOptions, GlbQuantization, MeshFormat};
use serde_json::json;

use crate::args::{
    CoordsArg, CriterionArg, HierarchyArg, MeshArgs, MeshKindArg, OddSpansArg, StripMethodArg,
};
use crate::hole::Holes;
use crate::input::{load, num};
use crate::progress;

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// True for the default conforming max-error meshing: the error map's fast
/// path, whose other refinement flags are not looked at.
fn is_fast(a: &MeshArgs) -> bool {
    a.refine.mode.mode() == Mode::Conforming && a.refine.criterion == CriterionArg::MaxError
}

/// The criterion settings the flags give.
fn criterion_options(a: &MeshArgs) -> CriterionOptions {
    let r = &a.refine;
    CriterionOptions::DEFAULT
        .with_max_error_m(a.max_error.unwrap_or(CriterionOptions::DEFAULT.max_error_m))
        .with_tolerance(r.tolerance)
        .with_observer_m(r.observer)
        .with_look_dir(r.look)
        .with_view(r.fov_deg, r.viewport_px, r.max_error_px)
        .with_light(r.light, r.alpha)
        .with_factors(r.size_factor, r.distance_factor, r.curvature_factor)
}

/// A criterion setting out of range, in the words of the flags.
fn flag_error(a: &MeshArgs, e: CriterionError) -> anyhow::Error {
    match e {
        CriterionError::NeedsObserver { .. } => anyhow::anyhow!(
            "--criterion {:?} needs --observer X,Y,Z (metres, local frame)",
            a.refine.criterion
        ),
        CriterionError::OutOfRange {
            setting,
            expected,
            found,
        } => {
            let flag = match setting {
                "max_error_m" => "--max-error",
                "fov_y_deg" => "--fov-deg",
                "viewport_height_px" => "--viewport-px",
                "max_error_px" => "--max-error-px",
                "size_factor" => "--size-factor",
                "distance_factor" => "--distance-factor",
                "curvature_factor" => "--curvature-factor",
                "alpha" => "--alpha",
                "tolerance" => "--tolerance",
                other => other,
            };
            anyhow::anyhow!("{flag}: expected {expected}, found {found}")
        }
        other => other.into(),
    }
}

/// `--quantize` needs a .glb output, a triangle list and real heights
/// (`--z-scale` 1).
fn check_quantize(a: &MeshArgs) -> anyhow::Result<()> {
    if !(a.z_scale.is_finite() && a.z_scale > 0.0) {
        anyhow::bail!(
            "--z-scale: expected a positive finite factor, found {}",
            crate::input::num(a.z_scale)
        );
    }
    if !a.quantize {
        return Ok(());
    }
    if a.z_scale != 1.0 {
        anyhow::bail!("--quantize: expected --z-scale 1 (a quantized GLB keeps true heights)");
    }
    if let Some(out) = &a.output {
        if crate::output::format_of(out, a.format)? != MeshFormat::Glb {
            anyhow::bail!(
                "{}: --quantize writes a quantized glTF, expected a .glb output",
                out.display()
            );
        }
    }
    if a.strip {
        anyhow::bail!(
            "--quantize: expected a triangle list, found --strip (a quantized GLB holds no strip)"
        );
    }
    if a.refine.mode.mode() != Mode::Conforming {
        anyhow::bail!(
            "--quantize: expected --mode conforming (fictitious heights must stay on their diagonals)"
        );
    }
    Ok(())
}

/// Runs `f` on `mesh` with the heights a quantized GLB writes (when `quant`
/// is given), then puts the mesh's own heights back.
fn with_written_heights<R>(
    mesh: &mut Mesh,
    quant: Option<&GlbQuantization>,
    f: impl FnOnce(&Mesh) -> R,
) -> R {
    let Some(q) = quant else { return f(mesh) };
    let mut heights = q.written_heights(mesh);
    let swap = |mesh: &mut Mesh, heights: &mut Vec<f32>| {
        for (v, h) in mesh.vertices.iter_mut().zip(heights.iter_mut()) {
            std::mem::swap(&mut v.z_m, h);
        }
    };
    swap(mesh, &mut heights);
    let r = f(mesh);
    swap(mesh, &mut heights);
    r
}

/// Rejects the flags `--mesh tin` does not take (and `--lock-border`
/// without it), before any long work.
fn validate_tin(a: &MeshArgs) -> anyhow::Result<()> {
    if a.mesh != MeshKindArg::Tin {
        if a.lock_border {
            anyhow::bail!(
                "--lock-border: expected --mesh tin (the bitree's border follows its triangles)"
            );
        }
        return Ok(());
    }
    if a.hierarchy != HierarchyArg::Bitree {
        anyhow::bail!(
            "--mesh tin: expected --hierarchy bitree (the TIN is decimated from the bitree's mesh)"
        );
    }
    if !is_fast(a) {
        anyhow::bail!(
            "--mesh tin: expected --mode conforming and --criterion max-error (a vertical bound)"
        );
    }
    if a.strip || a.strip_method.is_some() {
        anyhow::bail!(
            "--mesh tin: triangle strips follow the bitree; expected no --strip or --strip-method"
        );
    }
    Ok(())
}

/// Validates the flags before any long work.
fn validate(a: &MeshArgs) -> anyhow::Result<()> {
    crate::hole::validate(a)?;
    let format = match &a.output {
        Some(out) => Some(crate::output::check_output(
            out,
            a.format,
            a.base_m.or(a.base_mm),
        )?),
        None => None,
    };
    crate::print::validate(a, format)?;
    check_quantize(a)?;
    crate::pair::check_texture(
        &a.texture,
        a.output.as_deref(),
        a.format,
        a.strip,
        a.quantize,
    )?;
    if let Some(e) = a.max_error {
        if e.is_nan() || e < 0.0 {
            anyhow::bail!(
                "--max-error: expected 0 m or more, found {} m",
                crate::input::num(e)
            );
        }
    }
    if !is_fast(a) {
        if a.max_triangles.is_some() {
            anyhow::bail!(
                "--max-triangles works with the default --mode conforming --criterion max-error only"
            );
        }
        criterion_options(a)
            .validate(a.refine.criterion.kind())
            .map_err(|e| flag_error(a, e))?;
    }
    validate_tin(a)?;
    let quadtree = a.hierarchy == HierarchyArg::Quadtree;
    if a.strip {
        if quadtree {
            anyhow::bail!(
                "--strip: expected --hierarchy bitree (strips follow the bitree traversal)"
            );
        }
        if let Some(out) = &a.output {
            if crate::output::format_of(out, a.format)? != MeshFormat::Glb {
                anyhow::bail!(
                    "{}: --strip writes a glTF triangle strip, expected a .glb output",
                    out.display()
                );
            }
        }
    }
    if quadtree && (a.refine.mode.mode() != Mode::Conforming || a.max_triangles.is_some()) {
        anyhow::bail!(
            "--hierarchy quadtree: expected --mode conforming and --max-error or another criterion (no --max-triangles)"
        );
    }
    Ok(())
}

/// The mesh the flags ask for, and the build and extraction times (ms).
/// With `holes`, the criterion also splits what touches a void.
fn mesh_grid(
    a: &MeshArgs,
    grid: &HeightGrid,
    holes: Option<&Holes>,
) -> anyhow::Result<(Meshed, f64, f64)> {
    let mesher = Mesher::new(grid);
    let t = Instant::now();
    let inner = mesher
        .criterion(a.refine.criterion.kind(), &criterion_options(a))
        .map_err(|e| flag_error(a, e))?;
    let avoid;
    let criterion: &dyn Criterion = match holes {
        Some(h) => {
            avoid = AvoidVoids {
                inner: &*inner,
                voids: &h.mask,
            };
            &avoid
        }
        None => &*inner,
    };
    let hierarchy = match a.hierarchy {
        HierarchyArg::Bitree if a.mesh == MeshKindArg::Tin => HierarchyKind::Tin {
            lock_border: a.lock_border,
        },
        HierarchyArg::Bitree => HierarchyKind::Bitree,
        HierarchyArg::Quadtree => HierarchyKind::Quadtree(a.quadtree_leaves.options()),
    };
    let plan = MeshPlan::new(criterion)
        .with_hierarchy(hierarchy)
        .with_mode(a.refine.mode.mode())
        .with_max_triangles(a.max_triangles)
        // Strips follow the hierarchy's own triangles, not the clipped ones.
        .with_extend_odd_spans(
            a.odd_spans == OddSpansArg::Extend && !(a.strip || a.strip_method.is_some()),
        );
    let criterion_ms = ms(t);
    let t = Instant::now();
    let pb = progress::bar(0, "building");
    mesher.prepare(&plan, &pb.report())?;
    drop(pb);
    let build_ms = ms(t);
    let t = Instant::now();
    let mut meshed = mesher.mesh(&plan).map_err(|e| match e {
        cota_core::MeshError::BudgetTooSmall { .. } => anyhow::anyhow!("--max-triangles: {e}"),
        e => e.into(),
    })?;
    if holes.is_some() {
        // The wrapper hides the user's bound from the mesher; it still holds.
        meshed.bound_m = inner.vertical_bound_m();
        meshed.check = meshed.check.with_max_error_m(meshed.bound_m);
    }
    Ok((meshed, build_ms, criterion_ms + ms(t)))
}

/// The export options the flags give.
fn export_options(a: &MeshArgs, base_m: Option<f64>) -> ExportOptions {
    let coords = match a.coords {
        CoordsArg::Local => Coords::LocalMetres,
        CoordsArg::Grid => Coords::Grid,
    };
    ExportOptions::DEFAULT
        .with_coords(coords)
        .with_base_m(base_m.map(|b| b * a.z_scale))
        .with_quantize(a.quantize)
        .with_replace_read_only(a.force.force)
}

/// With `--quantize`, the plan of the quantized GLB (planning the file
/// counts as writing it: returns its time in ms too).
fn quantization(
    a: &MeshArgs,
    grid: &HeightGrid,
    m: &Meshed,
) -> anyhow::Result<(Option<GlbQuantization>, f64)> {
    let t = Instant::now();
    let quant = match a.quantize {
        true => Some(
            GlbQuantization::new(&m.mesh, grid, &export_options(a, None))
                .context("quantizing the mesh")?,
        ),
        false => None,
    };
    Ok((quant, ms(t)))
}

/// The mesh's exact metrics, through the checker with `--check`; with
/// `--quantize`, of the mesh as written, against the bound plus half the
/// height step.
fn measure_mesh(
    a: &MeshArgs,
    grid: &HeightGrid,
    m: &mut Meshed,
    quant: Option<&GlbQuantization>,
    pb: &progress::Bar,
) -> anyhow::Result<Metrics> {
    let half_step = quant.map(|q| q.z_step_m() / 2.0);
    let check_opts = match half_step {
        Some(h) => m
            .check
            .with_max_error_m(m.check.max_error_m.map(|b| b + h))
            .with_height_tolerance_m(h),
        None => m.check,
    };
    with_written_heights(&mut m.mesh, quant, |mesh| {
        Ok(if a.check {
            check_mesh_with_progress(grid, mesh, &check_opts, &pb.report())
                .context("the invariant checker rejected the mesh (this is a bug in cota)")?
                .metrics
        } else {
            measure_with_progress(grid, mesh, &pb.report())
                .within_rounding_of(check_opts.max_error_m, grid)
        })
    })
}

/// The strip, made only when asked for (`--strip`, or `--strip-method` to
/// report the references): it costs time and about 60 bytes per triangle of
/// scratch. A re-triangulated strip mesh is checked too with `--check`.
fn strip<'m>(
    a: &MeshArgs,
    grid: &HeightGrid,
    m: &'m Meshed,
) -> anyhow::Result<Option<MeshStrip<'m>>> {
    if a.hierarchy == HierarchyArg::Quadtree || !(a.strip || a.strip_method.is_some()) {
        return Ok(None);
    }
    let method = a.strip_method.unwrap_or(StripMethodArg::Cells).method();
    let s = stripify_bitree_with(&m.mesh, method).context("triangle strip")?;
    if a.check && s.retriangulated() {
        // The strip's own mesh when it re-triangulated unit cells: exact, so
        // the same checks must pass.
        check_mesh(grid, &s.mesh, &m.check).context(
            "the invariant checker rejected the strip's re-triangulated mesh (this is a bug in cota)",
        )?;
    }
    Ok(Some(s))
}

/// `mesh` with its heights multiplied by `--z-scale` (borrowed when 1).
fn scaled(mesh: &Mesh, z_scale: f64) -> std::borrow::Cow<'_, Mesh> {
    if z_scale == 1.0 {
        return std::borrow::Cow::Borrowed(mesh);
    }
    let mut m = mesh.clone();
    for v in &mut m.vertices {
        v.z_m = (f64::from(v.z_m) * z_scale) as f32;
    }
    std::borrow::Cow::Owned(m)
}

/// Writes the mesh (or its strip with `--strip`), heights times `--z-scale`;
/// returns the time taken (ms).
fn write(
    a: &MeshArgs,
    grid: &HeightGrid,
    m: &Meshed,
    strip: Option<&MeshStrip<'_>>,
    quant: Option<&GlbQuantization>,
) -> anyhow::Result<f64> {
    let Some(out) = &a.output else {
        return Ok(0.0);
    };
    let units = crate::print::mm_per_m(a, grid)?.unwrap_or(1.0);
    let base = crate::print::base_m(a, grid)?;
    let eo = export_options(a, base).with_stl_units_per_m(units);
    let t = Instant::now();
    let mesh = scaled(&m.mesh, a.z_scale);
    if crate::pair::write_draped(&a.texture, out, a.force.force, grid, &mesh, &eo)? {
        return Ok(ms(t));
    }
    let format = crate::output::format_of(out, a.format)?;
    crate::output::write_with(out, a.force.force, |w| match (strip, a.strip, quant) {
        (Some(s), true, _) => {
            let sm = scaled(&s.mesh, a.z_scale);
            cota_io::export::write_glb_strip(w, &sm, &s.strip.indices, grid, &eo)
        }
        (_, _, Some(q)) => cota_io::export::write_glb_quantized(w, &m.mesh, grid, &eo, q),
        _ => write_mesh_to(w, format, &mesh, grid, &eo),
    })?;
    Ok(ms(t))
}

/// What [`strip_and_write`] made, and how long each step took (ms).
struct Finished<'m> {
    metrics: Metrics,
    strip: Option<MeshStrip<'m>>,
    measure_ms: f64,
    strip_ms: f64,
    write_ms: f64,
}

/// The metrics and their time (ms) when they must be taken before the
/// output is written (see [`strip_and_write`]): with `--check` (the output is
/// written only after the checker passed) and with `--quantize` (the metrics
/// are taken on the written heights, which swaps them into the mesh for the
/// while), and with `--voids hole` (`always`: measured against the grid with
/// its voids). `None` otherwise.
fn measure_first(
    a: &MeshArgs,
    grid: &HeightGrid,
    m: &mut Meshed,
    quant: Option<&GlbQuantization>,
    always: bool,
) -> anyhow::Result<Option<(Metrics, f64)>> {
    if !a.check && quant.is_none() && !always {
        return Ok(None);
    }
    let t = Instant::now();
    let pb = progress::bar(0, if a.check { "checking" } else { "measuring" });
    let metrics = measure_mesh(a, grid, m, quant, &pb)?;
    Ok(Some((metrics, ms(t))))
}

/// Strips the mesh (when asked) and writes it; measures it at the same time
/// unless [`measure_first`] already did.
///
/// The default report's metrics are computed while the output is written:
/// the writer runs on a thread of its own (its encoding shares rayon's pool,
/// and its `fsync` waits on the disk while the pool measures). The figures and
/// the bytes written are the same as in sequence.
fn strip_and_write<'m>(
    a: &MeshArgs,
    grid: &HeightGrid,
    m: &'m Meshed,
    quant: Option<&GlbQuantization>,
    measured: Option<(Metrics, f64)>,
) -> anyhow::Result<Finished<'m>> {
    // The measure by rows while the writer writes; else writing alone.
    let _spinner = measured.is_some().then(|| progress::spinner("writing"));
    let strip_then_write = || -> anyhow::Result<_> {
        let t = Instant::now();
        let strip = strip(a, grid, m)?;
        let strip_ms = ms(t);
        let write_ms = write(a, grid, m, strip.as_ref(), quant)?;
        Ok((strip, strip_ms, write_ms))
    };
    let ((metrics, measure_ms), (strip, strip_ms, write_ms)) = match measured {
        Some(done) => (done, strip_then_write()?),
        None => std::thread::scope(|s| -> anyhow::Result<_> {
            let writer = s.spawn(strip_then_write);
            let t = Instant::now();
            let pb = progress::bar(0, "measuring");
            let metrics = measure_with_progress(grid, &m.mesh, &pb.report())
                .within_rounding_of(m.check.max_error_m, grid);
            let measure_ms = ms(t);
            drop(pb);
            let _spinner = a.output.is_some().then(|| progress::spinner("writing"));
            let written = writer
                .join()
                .map_err(|_| anyhow::anyhow!("the writer thread stopped (a bug in cota)"))??;
            Ok(((metrics, measure_ms), written))
        })?,
    };
    Ok(Finished {
        metrics,
        strip,
        measure_ms,
        strip_ms,
        write_ms,
    })
}

pub fn run(a: &MeshArgs) -> anyhow::Result<ExitCode> {
    let started = Instant::now();
    validate(a)?;
    let input = load(&a.input)?;
    let seams = crate::input::seams_json(&input);
    let mut grid = input.grid;
    let nodata = grid.void_count();
    let holes = Holes::of(a, &grid);
    let t = Instant::now();
    let files = crate::input::name(&input.files);
    let fill = crate::input::fill(&mut grid, a.voids).with_context(|| files.clone())?;
    let fill_ms = ms(t);
    crate::print::base_m(a, &grid)?;
    let (mut m, build_ms, extract_ms) =
        mesh_grid(a, &grid, holes.as_ref()).with_context(|| files.clone())?;
    let cut = holes.as_ref().map(|h| crate::hole::cut(&mut m, h));
    let (quant, quantize_ms) = quantization(a, &grid, &m)?;
    // With holes the truth is the grid with its voids (measured first).
    let truth = holes.as_ref().map_or(&grid, |h| &h.grid);
    let measured = measure_first(a, truth, &mut m, quant.as_ref(), holes.is_some())?;
    let done = strip_and_write(a, &grid, &m, quant.as_ref(), measured)?;
    let (metrics, strip, measure_ms, strip_ms) =
        (done.metrics, done.strip, done.measure_ms, done.strip_ms);
    let write_ms = done.write_ms + quantize_ms;
    let mesh = &m.mesh;
    let mut report = json!({
        "input": crate::input::name(&input.files),
        "assumed_cell_size_m": crate::input::assumed_cell_m(&input.files),
        "width": grid.width(),
        "height": grid.height(),
        "voids_filled": if cut.is_some() { 0 } else { fill.filled },
        "voids": crate::hole::policy_name(a.voids),
        "triangles_left_out": cut.map(|c| c.triangles_left_out),
        "area_left_out_m2": cut.map(|c| c.cells_left_out * cell_area_m2(&grid)),
        "nodata_count": nodata,
        "seams": seams,
        "threshold_m": m.bound_m,
        "hierarchy": if a.hierarchy == HierarchyArg::Quadtree { "quadtree" } else { "bitree" },
        "mesh": if a.mesh == MeshKindArg::Tin { "tin" } else { "bitree" },
        "lock_border": a.lock_border,
        "extended_to": m.extended_to,
        "mode": a.refine.mode.mode().name(),
        "criterion": m.criterion,
        "refine_rounds": m.rounds,
        "vertices": mesh.vertex_count(),
        "transmitted_points": m.transmitted_points,
        "fictitious_points": m.fictitious_points,
        "line_triangles": m.line_triangles,
        "triangles": mesh.triangle_count(),
        "full_triangles": 2 * (grid.width() - 1) * (grid.height() - 1),
        "max_error_m": metrics.max_error_m,
        "rmse_m": metrics.rmse_m,
        "mean_abs_error_m": metrics.mean_abs_error_m,
        "sse_m2": metrics.sse_m2,
        "volume_m3": metrics.volume_m3,
        "checked": a.check,
        "read_ms": input.read_ms,
        "fill_ms": fill_ms,
        "build_ms": build_ms,
        "extract_ms": extract_ms,
        "measure_ms": measure_ms,
        "write_ms": write_ms,
        "total_ms": ms(started),
        "output": a.output.as_ref().map(|p| p.display().to_string()),
        "quantized": a.quantize,
        "z_scale": a.z_scale,
        "z_step_m": quant.as_ref().map(|q| q.z_step_m()),
        "written_bound_m": m.bound_m.zip(quant.as_ref()).map(|(b, q)| b + q.z_step_m() / 2.0),
        "primitives": quant.as_ref().map(|q| q.primitives()),
    });
    add_strip_fields(&mut report, strip.as_ref(), strip_ms);
    crate::print::add_fields(&mut report, a, &grid)?;
    let text = match a.json {
        true => format!("{}\n", serde_json::to_string_pretty(&report)?),
        false => text(&report),
    };
    crate::output::print_report(a.output.as_deref(), &text, a.json);
    Ok(ExitCode::SUCCESS)
}

/// Adds the strip's figures to the report (`null` without a strip).
fn add_strip_fields(r: &mut serde_json::Value, strip: Option<&MeshStrip<'_>>, strip_ms: f64) {
    let fields = json!({
        "strip_method": strip.map(|s| s.method.name()),
        "strip_refs": strip.map(|s| s.strip.refs()),
        "strip_refs_per_triangle": strip.map(|s| s.strip.refs_per_triangle()),
        "strip_degenerate": strip.map(|s| s.strip.degenerate),
        "strip_retriangulated": strip.map(|s| s.retriangulated()),
        "strip_flipped_cells": strip.map(|s| s.flipped_cells),
        "strip_ms": strip.map(|_| strip_ms),
    });
    if let (Some(r), serde_json::Value::Object(f)) = (r.as_object_mut(), fields) {
        r.extend(f);
    }
}

/// The area of one cell at the grid's centre, square metres.
fn cell_area_m2(grid: &HeightGrid) -> f64 {
    let [dx, dy] = grid.cell_size_m();
    dx * dy
}

/// The input lines of the text report: size, assumed cell, seams, voids.
fn print_input(txt: &mut String, r: &serde_json::Value) {
    say!(
        txt,
        "input       {} ({} x {})",
        r["input"].as_str().unwrap_or(""),
        r["width"],
        r["height"]
    );
    if let Some(c) = r["assumed_cell_size_m"].as_f64() {
        say!(
            txt,
            "cell        assumed {} m: the input has no georeference (set it with --cell-size-m)",
            crate::input::num(c)
        );
    }
    if let Some(d) = r["seams"]["max_abs_diff_m"].as_f64() {
        say!(
            txt,
            "seams       largest difference {d} m over {} samples",
            r["seams"]["compared"]
        );
    }
    if let Some(area) = r["area_left_out_m2"].as_f64() {
        say!(
            txt,
            "voids       hole: {} void samples, {} triangles and {area:.4e} m2 left out",
            r["nodata_count"],
            r["triangles_left_out"]
        );
    } else if r["nodata_count"].as_u64().unwrap_or(0) > 0 {
        say!(txt, "voids       {} filled", r["voids_filled"]);
    }
}

/// The text report.
fn text(r: &serde_json::Value) -> String {
    let mut text = String::new();
    let txt = &mut text;
    let f = |k: &str| r[k].as_f64().unwrap_or(0.0);
    print_input(txt, r);
    say!(
        txt,
        "mesh        {} vertices, {} triangles ({:.2}% of {})",
        r["vertices"],
        r["triangles"],
        100.0 * f("triangles") / f("full_triangles").max(1.0),
        r["full_triangles"]
    );
    let bound = match (r["threshold_m"].as_f64(), r["z_step_m"].as_f64()) {
        (Some(b), Some(s)) => format!(
            "bound {} + {} m = {} m as written",
            num(b),
            num(s / 2.0),
            num(f("written_bound_m"))
        ),
        (Some(b), None) => format!("bound {} m", num(b)),
        (None, _) => "no vertical bound".to_string(),
    };
    say!(
        txt,
        "error       max {:.3} m ({bound}), RMSE {:.3} m, mean {:.3} m",
        f("max_error_m"),
        f("rmse_m"),
        f("mean_abs_error_m")
    );
    let tin = match (r["mesh"].as_str(), r["lock_border"].as_bool()) {
        (Some("tin"), Some(true)) => "tin (locked border), ",
        (Some("tin"), _) => "tin, ",
        _ => "",
    };
    say!(
        txt,
        "refinement  {tin}{}, {}",
        r["mode"].as_str().unwrap_or(""),
        r["criterion"].as_str().unwrap_or("")
    );
    if let Some([w, h]) = r["extended_to"].as_array().map(|a| [&a[0], &a[1]]) {
        say!(
            txt,
            "border      odd span: meshed on the grid extended to {w} x {h}, clipped back"
        );
    }
    say!(
        txt,
        "points      {} transmitted, {} fictitious, {} line triangles",
        r["transmitted_points"],
        r["fictitious_points"],
        r["line_triangles"]
    );
    say!(
        txt,
        "volume      {:.4e} m3 between mesh and grid",
        f("volume_m3")
    );
    print_strip_and_check(txt, r);
    say!(txt,
        "time        read {:.1} ms, fill {:.1} ms, build {:.1} ms, extract {:.2} ms, measure {:.1} ms, write {:.1} ms, total {:.1} ms",
        f("read_ms"),
        f("fill_ms"),
        f("build_ms"),
        f("extract_ms"),
        f("measure_ms"),
        f("write_ms"),
        f("total_ms")
    );
    if let Some(out) = r["output"].as_str() {
        let z = r["z_scale"].as_f64().filter(|z| *z != 1.0);
        let z = z.map(|z| format!(" (heights x {z})")).unwrap_or_default();
        say!(txt, "wrote       {out}{z}");
    }
    crate::print::text_line(txt, r);
    text
}

/// The strip and check lines of the text report.
fn print_strip_and_check(txt: &mut String, r: &serde_json::Value) {
    let f = |k: &str| r[k].as_f64().unwrap_or(0.0);
    if let Some(refs) = r["strip_refs"].as_u64() {
        let cells = match r["strip_flipped_cells"].as_u64() {
            Some(n) if n > 0 => format!(", {n} unit cells re-triangulated (same error)"),
            _ => String::new(),
        };
        say!(
            txt,
            "strip       {refs} references ({:.3} per triangle, {}), {} degenerate{cells}",
            f("strip_refs_per_triangle"),
            r["strip_method"].as_str().unwrap_or(""),
            r["strip_degenerate"]
        );
    }
    if let Some(s) = r["z_step_m"].as_f64() {
        say!(txt,
            "quantized   KHR_mesh_quantization, height step {s} m, {} primitives; error and volume as written",
            r["primitives"]
        );
    }
    if r["checked"].as_bool() == Some(true) {
        let joints = if r["mode"].as_str() == Some("fictitious-faithful") {
            "T-junctions allowed (hanging vertices, paper 000)"
        } else {
            "no T-junction"
        };
        let hole = r["voids"].as_str() == Some("hole");
        let bound = match (r["threshold_m"].is_null(), hole) {
            (true, _) => "",
            (false, false) => ", bound holds at every sample",
            (false, true) => ", bound holds at every valid sample",
        };
        let covers = match hole {
            true => "covers every cell with four valid corners, touches no void",
            false => "covers the grid exactly",
        };
        say!(txt, "check       passed: {covers}, {joints}{bound}");
    }
}
