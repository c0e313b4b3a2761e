//! `cota stream encode|decode`: the progressive stream of paper 000
//! (`cota_core::stream`, framed by `cota_io::stream_file`).
//!
//! Encode: read and mosaic like `cota mesh`, fill voids, encode (error steps,
//! or the progressive marks of `--mode conforming|fictitious|
//! fictitious-faithful`), write the `.cstream` atomically, report each step's
//! bytes per triangle and per point.
//! Decode: read a prefix (all, `--max-bytes`, or `--max-error`, cut at a step),
//! rebuild the mesh and a grid of the decoded surface for the exporters, write
//! the mesh, report bytes per triangle and per point at each step used.

use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use cota_core::stream::{
    encode_marks_progressive_with_progress, encode_with_progress, StreamOptions,
};
use cota_core::HeightGrid;
use cota_io::export::{write_mesh_to, Coords, ExportOptions};
use cota_io::stream_file::{
    read_stream_from, read_stream_with_progress, step_end_offsets, stream_bytes, DecodedStream,
    StreamLimit,
};
use serde_json::json;

use crate::args::{CoordsArg, StreamCommand, StreamDecodeArgs, StreamEncodeArgs, StreamModeArg};
use crate::input::load;

pub fn run(c: &StreamCommand) -> anyhow::Result<ExitCode> {
    match c {
        StreamCommand::Encode(a) => run_encode(a),
        StreamCommand::Decode(a) => run_decode(a),
    }
}

fn ratio(a: u64, b: usize) -> f64 {
    if b == 0 {
        0.0
    } else {
        a as f64 / b as f64
    }
}

/// Encodes `grid` as `mode` asks, with a spinner on a terminal.
fn encode_grid(
    grid: &HeightGrid,
    mode: StreamModeArg,
    opts: &StreamOptions,
) -> anyhow::Result<cota_core::stream::EncodedStream> {
    let pb = crate::progress::bar(0, "encoding");
    Ok(match mode.mode() {
        None => encode_with_progress(grid, opts, &pb.report())?,
        Some(mode) => encode_marks_progressive_with_progress(grid, mode, opts, &pb.report())?,
    })
}

/// The flags of `cota stream encode`, checked before any work.
fn check_encode(a: &StreamEncodeArgs) -> anyhow::Result<()> {
    if a.max_error.is_nan() || a.max_error < 0.0 {
        anyhow::bail!("--max-error: expected 0 m or more, found {} m", a.max_error);
    }
    if !(a.quantum_m.is_finite() && a.quantum_m > 0.0) {
        anyhow::bail!(
            "--quantum-m: expected a positive number of metres, found {}",
            a.quantum_m
        );
    }
    crate::input::refuse_hole(a.voids, "stream")?;
    if crate::input::is_dash(&a.output) {
        anyhow::bail!(
            "-o -: expected a file name (cota stream encode prints its report on stdout)"
        );
    }
    crate::output::check_file_path(&a.output)
}

fn run_encode(a: &StreamEncodeArgs) -> anyhow::Result<ExitCode> {
    check_encode(a)?;
    let input = load(&a.input)?;
    let mut grid = input.grid;
    crate::input::fill(&mut grid, a.voids)?;
    let t = Instant::now();
    let opts = StreamOptions::default()
        .with_quantum_m(a.quantum_m)
        .with_max_error_m(a.max_error)
        .with_thresholds_m(a.thresholds.clone());
    let s = encode_grid(&grid, a.mode, &opts)?;
    let encode_ms = t.elapsed().as_secs_f64() * 1e3;
    let bytes = stream_bytes(&s, grid.georef());
    crate::output::write_with(&a.output, a.force.force, |w| Ok(w.write_all(&bytes)?))?;
    let ends = step_end_offsets(&s, grid.georef());
    let total = ends.last().copied().unwrap_or(0);
    let full = 2 * (grid.width() - 1) * (grid.height() - 1);
    let steps: Vec<_> = s
        .steps
        .iter()
        .zip(&ends)
        .enumerate()
        .map(|(k, (st, &end))| {
            json!({
                "step": k,
                "threshold_m": if k == 0 {
                    None
                } else {
                    Some(st.threshold_m)
                },
                "max_error_m": st.max_error_m,
                "new_points": st.new_points,
                "step_bytes": st.payload.len() + 8,
                "total_bytes": end,
                "triangles": st.triangles,
                "vertices": st.vertices,
                "bytes_per_triangle": ratio(end, st.triangles),
                "bytes_per_point": ratio(end, st.vertices),
            })
        })
        .collect();
    let last = s.steps.last();
    let name = crate::input::name(&input.files);
    let report = json!({
        "input": name,
        "width": grid.width(),
        "height": grid.height(),
        "quantum_m": a.quantum_m,
        "mode": a.mode.name(),
        "lossless": s.lattice_exact && a.max_error == 0.0,
        "lattice_exact": s.lattice_exact,
        "bytes": total,
        "full_triangles": full,
        "bytes_per_full_triangle": ratio(total, full),
        "final_triangles": last.map(|l| l.triangles),
        "bytes_per_final_triangle": ratio(total, last.map_or(0, |l| l.triangles)),
        "encode_ms": encode_ms,
        "steps": steps,
        "output": a.output.display().to_string(),
    });
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(ExitCode::SUCCESS);
    }
    if !crate::progress::quiet() {
        print_encode_text(a, &name, &grid, &s, &ends);
        println!("wrote       {}", a.output.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// The text report of `cota stream encode`: one line per step, the total.
fn print_encode_text(
    a: &StreamEncodeArgs,
    name: &str,
    grid: &HeightGrid,
    s: &cota_core::stream::EncodedStream,
    ends: &[u64],
) {
    let total = ends.last().copied().unwrap_or(0);
    let full = 2 * (grid.width() - 1) * (grid.height() - 1);
    let last = s.steps.last();
    println!(
        "input       {} ({} x {}), quantum {} m{}",
        name,
        grid.width(),
        grid.height(),
        a.quantum_m,
        if s.lattice_exact {
            ", heights on the lattice (exact)"
        } else {
            ", heights rounded to the lattice: add quantum/2 to the errors"
        }
    );
    println!(
        "{:>4} {:>10} {:>10} {:>10} {:>11} {:>11} {:>10} {:>8} {:>8}",
        "step",
        "threshold",
        "max err m",
        "new pts",
        "bytes",
        "triangles",
        "vertices",
        "B/tri",
        "B/pt"
    );
    for (k, (st, &end)) in s.steps.iter().zip(ends).enumerate() {
        let thr = if k == 0 {
            "coarse".to_string()
        } else {
            format!("{}", st.threshold_m)
        };
        println!(
            "{:>4} {:>10} {:>10.3} {:>10} {:>11} {:>11} {:>10} {:>8.3} {:>8.3}",
            k,
            thr,
            st.max_error_m,
            st.new_points,
            end,
            st.triangles,
            st.vertices,
            ratio(end, st.triangles),
            ratio(end, st.vertices)
        );
    }
    println!(
        "total       {} bytes: {:.3} B per triangle of the final mesh, {:.3} B per full-resolution triangle ({})",
        total,
        ratio(total, last.map_or(0, |l| l.triangles)),
        ratio(total, full),
        full
    );
}

/// Writes the decoded mesh to `-o`, if given.
fn write_decoded(
    a: &StreamDecodeArgs,
    mesh: &cota_core::Mesh,
    grid: &HeightGrid,
) -> anyhow::Result<()> {
    if let Some(out) = &a.output {
        let coords = match a.coords {
            CoordsArg::Local => Coords::LocalMetres,
            CoordsArg::Grid => Coords::Grid,
        };
        let format = crate::output::format_of(out, a.format)?;
        let opts = ExportOptions::DEFAULT
            .with_coords(coords)
            .with_replace_read_only(a.force.force);
        let _spinner = crate::progress::spinner("writing");
        crate::output::write_with(out, a.force.force, |w| {
            write_mesh_to(w, format, mesh, grid, &opts)
        })?;
    }
    Ok(())
}

/// Reads the stream of `input` (`-`: standard input) up to `limit`.
fn decode_input(input: &Path, limit: &StreamLimit) -> anyhow::Result<DecodedStream> {
    if !crate::input::is_dash(input) {
        let pb = crate::progress::bytes(0, "decoding");
        return Ok(read_stream_with_progress(input, limit, &|d, t| {
            pb.set(d, t)
        })?);
    }
    let stdin = std::io::stdin();
    if stdin.is_terminal() {
        anyhow::bail!(
            "-: expected a cota stream on standard input, found a terminal (pipe or redirect one: cota stream decode - < IN.cstream)"
        );
    }
    let name = Path::new(crate::input::STDIN_NAME);
    let _spinner = crate::progress::spinner("decoding");
    Ok(read_stream_from(stdin.lock(), name, limit)?)
}

fn run_decode(a: &StreamDecodeArgs) -> anyhow::Result<ExitCode> {
    if let Some(e) = a.max_error {
        if e.is_nan() || e < 0.0 {
            anyhow::bail!("--max-error: expected 0 m or more, found {e} m");
        }
    }
    if let Some(out) = &a.output {
        crate::output::check_output(out, a.format, None)?;
    }
    let limit = StreamLimit::ALL
        .with_max_bytes(a.max_bytes)
        .with_max_error_m(a.max_error)
        .with_max_samples(a.max_samples)
        .with_partial(!a.strict);
    let d = decode_input(&a.input, &limit)?;
    warn_truncated(&a.input, &d);
    let h = d.decoder.header().clone();
    let mesh = d.decoder.mesh();
    let heights = d
        .decoder
        .heights_m()
        .context("the stream has no complete step")?;
    let grid = HeightGrid::new(
        h.width as usize,
        h.height as usize,
        heights,
        d.georef.clone(),
    )
    .with_context(|| format!("{}: decoded surface", a.input.display()))?;
    write_decoded(a, &mesh, &grid)?;
    let used = d.steps.last().map_or(0, |s| s.end_offset);
    let steps: Vec<_> = d
        .steps
        .iter()
        .map(|s| {
            json!({
                "step": s.info.index,
                "max_error_m": s.info.max_error_m,
                "new_points": s.info.new_points,
                "step_bytes": s.info.payload_bytes + 8,
                "total_bytes": s.end_offset,
                "triangles": s.info.triangles,
                "vertices": s.info.vertices,
                "bytes_per_triangle": ratio(s.end_offset, s.info.triangles),
                "bytes_per_point": ratio(s.end_offset, s.info.vertices),
            })
        })
        .collect();
    let report = json!({
        "input": a.input.display().to_string(),
        "width": h.width,
        "height": h.height,
        "quantum_m": h.quantum_m,
        "steps_used": d.steps.len(),
        "bytes_used": used,
        "file_bytes": d.file_bytes,
        "max_error_m": d.decoder.max_error_m(),
        "triangles": mesh.triangle_count(),
        "vertices": mesh.vertex_count(),
        "bytes_per_triangle": ratio(used, mesh.triangle_count()),
        "bytes_per_point": ratio(used, mesh.vertex_count()),
        "steps": steps,
        "truncated": d.truncated.as_ref().map(|t| t.error.to_string()),
        "output": a.output.as_ref().map(|p| p.display().to_string()),
    });
    let text = match a.json {
        true => format!("{}\n", serde_json::to_string_pretty(&report)?),
        false => decode_text(a, &d, &mesh, used),
    };
    crate::output::print_report(a.output.as_deref(), &text, a.json);
    Ok(ExitCode::SUCCESS)
}

/// Says what a cut stream lacks (decoded up to its last complete step).
fn warn_truncated(input: &Path, d: &cota_io::stream_file::DecodedStream) {
    if let Some(t) = &d.truncated {
        let have = d.decoder.steps().len();
        eprintln!(
            "cota: warning: {}: {}; decoded its {have} complete step(s) of the {} the head announces, \
             {} missing (--strict refuses a cut stream)",
            input.display(),
            t.error,
            t.announced_steps,
            (t.announced_steps as usize).saturating_sub(have)
        );
    }
}

/// The text report of `cota stream decode`: the steps used, the mesh.
fn decode_text(
    a: &StreamDecodeArgs,
    d: &cota_io::stream_file::DecodedStream,
    mesh: &cota_core::Mesh,
    used: u64,
) -> String {
    let mut text = String::new();
    let txt = &mut text;
    let h = d.decoder.header();
    say!(
        txt,
        "input       {} ({} x {}), {} of {} bytes, {} steps",
        a.input.display(),
        h.width,
        h.height,
        used,
        d.file_bytes,
        d.steps.len()
    );
    say!(
        txt,
        "{:>4} {:>10} {:>10} {:>11} {:>11} {:>10} {:>8} {:>8}",
        "step",
        "max err m",
        "new pts",
        "bytes",
        "triangles",
        "vertices",
        "B/tri",
        "B/pt"
    );
    for s in &d.steps {
        say!(
            txt,
            "{:>4} {:>10.3} {:>10} {:>11} {:>11} {:>10} {:>8.3} {:>8.3}",
            s.info.index,
            s.info.max_error_m,
            s.info.new_points,
            s.end_offset,
            s.info.triangles,
            s.info.vertices,
            ratio(s.end_offset, s.info.triangles),
            ratio(s.end_offset, s.info.vertices)
        );
    }
    say!(
        txt,
        "mesh        {} vertices, {} triangles, max error {} m",
        mesh.vertex_count(),
        mesh.triangle_count(),
        d.decoder.max_error_m().unwrap_or(0.0)
    );
    say!(
        txt,
        "size        {:.3} B per triangle, {:.3} B per point",
        ratio(used, mesh.triangle_count()),
        ratio(used, mesh.vertex_count())
    );
    if let Some(out) = &a.output {
        say!(txt, "wrote       {}", out.display());
    }
    text
}
