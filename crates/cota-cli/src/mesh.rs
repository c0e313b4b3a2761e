//! `cota mesh`: read, fill voids, build the exact-error bitree, extract a
//! conforming mesh by error or budget, measure it exactly, optionally check it,
//! and write it atomically.

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use cota_core::refine::Mode;
use cota_core::voids::FillReport;
use cota_core::{check_mesh, measure, Bitree, CheckOptions, ExtractOptions, Mesh, Metrics};
use cota_io::export::{write_mesh, Coords, ExportOptions, MeshFormat};
use serde_json::json;

use crate::args::{CoordsArg, HierarchyArg, MeshArgs, MeshKindArg, QuadVariant, StripMethodArg};
use crate::input::load;
use crate::progress;
use crate::refine;
use cota_core::quadtree::{QuadOptions, QuadTree};

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Fails early, before any long work, on output paths that cannot be written.
fn check_output(out: &Path, base_m: Option<f64>) -> anyhow::Result<MeshFormat> {
    let format = MeshFormat::from_path(out)?;
    if base_m.is_some() && format != MeshFormat::Stl {
        anyhow::bail!(
            "{}: --base-m makes a closed solid for 3D printing and applies to .stl output only, found .{format}",
            out.display()
        );
    }
    let dir = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        anyhow::bail!(
            "cannot write {}: expected an existing directory {}, found none",
            out.display(),
            dir.display()
        );
    }
    if out.is_dir() {
        anyhow::bail!("cannot write {}: it is a directory", out.display());
    }
    Ok(format)
}

pub fn run(a: &MeshArgs) -> anyhow::Result<ExitCode> {
    if let Some(out) = &a.output {
        check_output(out, a.base_m)?;
    }
    if let Some(e) = a.max_error {
        if e.is_nan() || e < 0.0 {
            anyhow::bail!("--max-error: expected 0 m or more, found {e} m");
        }
    }
    if a.max_triangles == Some(0) {
        anyhow::bail!("--max-triangles: expected at least 2 triangles, found 0");
    }
    crate::refine::validate(&a.refine, a.max_triangles)?;
    let tin = a.mesh == MeshKindArg::Tin;
    if tin {
        crate::tin::validate(a)?;
    } else if a.lock_border {
        anyhow::bail!(
            "--lock-border: expected --mesh tin (the bitree's border follows its triangles)"
        );
    }
    if a.strip {
        if a.hierarchy == HierarchyArg::Quadtree {
            anyhow::bail!(
                "--strip: expected --hierarchy bitree (strips follow the bitree traversal)"
            );
        }
        if let Some(out) = &a.output {
            if MeshFormat::from_path(out)? != MeshFormat::Glb {
                anyhow::bail!(
                    "{}: --strip writes a glTF triangle strip, expected a .glb output",
                    out.display()
                );
            }
        }
    }
    let quadtree = a.hierarchy == HierarchyArg::Quadtree;
    if quadtree && (refine::mode(&a.refine) != Mode::Conforming || a.max_triangles.is_some()) {
        anyhow::bail!(
            "--hierarchy quadtree: expected --mode conforming and --max-error or another criterion (no --max-triangles)"
        );
    }
    let opts = match (a.max_error, a.max_triangles) {
        (_, Some(n)) => ExtractOptions::max_triangles(n),
        (Some(e), None) => ExtractOptions::max_error_m(e),
        (None, None) => ExtractOptions::max_error_m(1.0),
    };

    let input = load(&a.input)?;
    let mut grid = input.grid;
    let nodata = grid.void_count();
    let t = Instant::now();
    let fill: FillReport = crate::input::fill(&mut grid, a.voids)?;
    let fill_ms = ms(t);

    let (mesh, threshold_m, build_ms, extract_ms, check_opts, generic) = if tin {
        let t = crate::tin::run(&grid, a)?;
        let bound = Some(t.threshold_m);
        (t.mesh, bound, t.build_ms, t.extract_ms, t.check, None)
    } else if quadtree {
        let t = Instant::now();
        let qt = QuadTree::build(&grid)?;
        let build_ms = ms(t);
        let t = Instant::now();
        let e = a.max_error.unwrap_or(1.0);
        let leaves = QuadOptions::DEFAULT
            .with_centre_when_needed(matches!(a.quadtree_leaves, QuadVariant::CentreWhenNeeded));
        let (x, name) = refine::with_criterion(&a.refine, e, &grid, |c| {
            (qt.refine_with(c, &leaves), c.name())
        })?;
        let extract_ms = ms(t);
        // Only the max-error criterion promises a vertical bound.
        let bound = refine::is_fast(&a.refine).then_some(e);
        let check = CheckOptions::DEFAULT.with_max_error_m(bound);
        let outcome = refine::Outcome {
            mesh: Mesh::default(),
            threshold_m: bound,
            transmitted_points: x.mesh.vertex_count(),
            fictitious_points: 0,
            line_triangles: 0,
            criterion: name,
            rounds: 1,
            check,
        };
        (x.mesh, bound, build_ms, extract_ms, check, Some(outcome))
    } else if refine::is_fast(&a.refine) {
        let t = Instant::now();
        let pb = progress::bar(0, "building");
        let tin = Bitree::build_with_progress(&grid, &|done, total| {
            pb.set_length(total as u64);
            pb.set_position(done as u64);
        })?;
        pb.finish_and_clear();
        let build_ms = ms(t);

        let t = Instant::now();
        let x = tin.extract(&opts)?;
        let extract_ms = ms(t);
        let check = CheckOptions::conforming(x.threshold_m);
        (
            x.mesh,
            Some(x.threshold_m),
            build_ms,
            extract_ms,
            check,
            None,
        )
    } else {
        // Generic criterion-driven refinement: no error map to build.
        let t = Instant::now();
        let mut o = refine::run(&a.refine, a.max_error.unwrap_or(1.0), &grid)?;
        let extract_ms = ms(t);
        let mesh = std::mem::take(&mut o.mesh);
        (mesh, o.threshold_m, 0.0, extract_ms, o.check, Some(o))
    };
    let (transmitted, fictitious, line_triangles) = match &generic {
        Some(o) => (o.transmitted_points, o.fictitious_points, o.line_triangles),
        None => (mesh.vertex_count(), 0, 0),
    };
    let criterion = match &generic {
        Some(o) => o.criterion.clone(),
        None => cota_core::Criterion::name(&cota_core::MaxVerticalError {
            max_error_m: threshold_m.unwrap_or(0.0),
        }),
    };

    let t = Instant::now();
    let metrics: Metrics = if a.check {
        check_mesh(&grid, &mesh, &check_opts)
            .context("the invariant checker rejected the mesh (this is a bug in cota)")?
            .metrics
    } else {
        measure(&grid, &mesh)
    };
    let measure_ms = ms(t);

    let t = Instant::now();
    // Strips cost time and about 60 bytes per triangle of scratch: made only
    // when asked for (--strip, or --strip-method to report the references).
    let strip = if !quadtree && (a.strip || a.strip_method.is_some()) {
        let method = a.strip_method.unwrap_or(StripMethodArg::Cells).method();
        Some(cota_core::strip::stripify_bitree_with(&mesh, method).context("triangle strip")?)
    } else {
        None
    };
    let strip_ms = ms(t);
    if let (Some(s), true) = (&strip, a.check) {
        // The strip's own mesh when it re-triangulated unit cells: exact, so
        // the same checks must pass.
        if s.retriangulated() {
            check_mesh(&grid, &s.mesh, &check_opts).context(
                "the invariant checker rejected the strip's re-triangulated mesh (this is a bug in cota)",
            )?;
        }
    }

    let mut write_ms = 0.0;
    if let Some(out) = &a.output {
        let coords = match a.coords {
            CoordsArg::Local => Coords::LocalMetres,
            CoordsArg::Grid => Coords::Grid,
        };
        let eo = ExportOptions::DEFAULT
            .with_coords(coords)
            .with_base_m(a.base_m);
        let t = Instant::now();
        match (&strip, a.strip) {
            (Some(s), true) => cota_io::export::write_atomically(out, |w| {
                cota_io::export::write_glb_strip(w, &s.mesh, &s.strip.indices, &grid, &eo)
            })?,
            _ => write_mesh(out, &mesh, &grid, &eo)?,
        }
        write_ms = ms(t);
    }

    let name = crate::input::name(&input.files);
    let report = json!({
        "input": name,
        "width": grid.width(),
        "height": grid.height(),
        "voids_filled": fill.filled,
        "nodata_count": nodata,
        "threshold_m": threshold_m,
        "hierarchy": if quadtree { "quadtree" } else { "bitree" },
        "mesh": if tin { "tin" } else { "bitree" },
        "lock_border": a.lock_border,
        "mode": refine::mode(&a.refine).name(),
        "criterion": criterion,
        "refine_rounds": generic.as_ref().map(|o| o.rounds),
        "vertices": mesh.vertex_count(),
        "transmitted_points": transmitted,
        "fictitious_points": fictitious,
        "line_triangles": line_triangles,
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
        "strip_method": strip.as_ref().map(|s| s.method.name()),
        "strip_refs": strip.as_ref().map(|s| s.strip.refs()),
        "strip_refs_per_triangle": strip.as_ref().map(|s| s.strip.refs_per_triangle()),
        "strip_degenerate": strip.as_ref().map(|s| s.strip.degenerate),
        "strip_retriangulated": strip.as_ref().map(|s| s.retriangulated()),
        "strip_flipped_cells": strip.as_ref().map(|s| s.flipped_cells),
        "strip_ms": strip.as_ref().map(|_| strip_ms),
        "output": a.output.as_ref().map(|p| p.display().to_string()),
    });
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_text(&report, &input.seams);
    }
    Ok(ExitCode::SUCCESS)
}

fn print_text(r: &serde_json::Value, seams: &Option<cota_core::mosaic::SeamReport>) {
    let f = |k: &str| r[k].as_f64().unwrap_or(0.0);
    println!(
        "input       {} ({} x {})",
        r["input"].as_str().unwrap_or(""),
        r["width"],
        r["height"]
    );
    if let Some(s) = seams {
        println!(
            "seams       largest difference {} m over {} samples",
            s.max_abs_diff_m, s.compared
        );
    }
    if f("nodata_count") > 0.0 {
        println!("voids       {} filled", r["voids_filled"]);
    }
    println!(
        "mesh        {} vertices, {} triangles ({:.2}% of {})",
        r["vertices"],
        r["triangles"],
        100.0 * f("triangles") / f("full_triangles").max(1.0),
        r["full_triangles"]
    );
    let bound = match r["threshold_m"].as_f64() {
        Some(b) => format!("bound {b} m"),
        None => "no vertical bound".to_string(),
    };
    println!(
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
    println!(
        "refinement  {tin}{}, {}",
        r["mode"].as_str().unwrap_or(""),
        r["criterion"].as_str().unwrap_or("")
    );
    println!(
        "points      {} transmitted, {} fictitious, {} line triangles",
        r["transmitted_points"], r["fictitious_points"], r["line_triangles"]
    );
    println!(
        "volume      {:.4e} m3 between mesh and grid",
        f("volume_m3")
    );
    if let Some(refs) = r["strip_refs"].as_u64() {
        let cells = match r["strip_flipped_cells"].as_u64() {
            Some(n) if n > 0 => format!(", {n} unit cells re-triangulated (same error)"),
            _ => String::new(),
        };
        println!(
            "strip       {refs} references ({:.3} per triangle, {}), {} degenerate{cells}",
            f("strip_refs_per_triangle"),
            r["strip_method"].as_str().unwrap_or(""),
            r["strip_degenerate"]
        );
    }
    if r["checked"].as_bool() == Some(true) {
        let joints = if r["mode"].as_str() == Some("fictitious-faithful") {
            "T-junctions allowed (hanging vertices, paper 000)"
        } else {
            "no T-junction"
        };
        let bound = if r["threshold_m"].is_null() {
            ""
        } else {
            ", bound holds at every sample"
        };
        println!("check       passed: covers the grid exactly, {joints}{bound}");
    }
    println!(
        "time        read {:.1} ms, fill {:.1} ms, build {:.1} ms, extract {:.2} ms, measure {:.1} ms, write {:.1} ms",
        f("read_ms"),
        f("fill_ms"),
        f("build_ms"),
        f("extract_ms"),
        f("measure_ms"),
        f("write_ms")
    );
    if let Some(out) = r["output"].as_str() {
        println!("wrote       {out}");
    }
}
