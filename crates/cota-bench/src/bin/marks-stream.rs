//! Bytes of cota's marks streams (refinement under the vertical-error
//! criterion, conforming or with fictitious points, paper
//! `000_ebf7e3a88dffd361.txt` §2.2 and §3): one step against the progressive
//! stream, per mode and tolerance, with bytes per triangle at every step.
//!
//! Usage: `cargo run --release -p cota-bench --bin marks-stream -- [--json]
//! [--errors 20,5,1] FILE...` (default file: the bundled
//! `fixtures/S29W072.hgt.zip`). Voids are filled and heights rounded to whole
//! metres (SRTM's lattice), quantum 1 m, so every stream is exact.
//!
//! For each DEM, mode and `E`:
//! 1. one step: `refine_marks(E)` + `encode_marks` (the former
//!    `cota stream encode --mode M` layout: one block, framing included);
//! 2. progressive: `encode_marks_progressive` down to `E` (what
//!    `cota stream encode --mode M --max-error E` writes), every step with its
//!    cumulative bytes, its mesh and its stated error.

use std::error::Error;
use std::path::{Path, PathBuf};

use cota_core::grid::voids::{fill_voids, FillOptions};
use cota_core::refine::{refine_marks, Mode, RefineOptions};
use cota_core::stream::{encode_marks, encode_marks_progressive, StreamOptions};
use cota_core::{HeightGrid, MaxVerticalError};
use cota_io::stream_file::{step_end_offsets, stream_bytes};
use cota_io::{read_dem, ReadOptions};
use serde_json::json;

fn load(path: &Path) -> Result<HeightGrid, Box<dyn Error>> {
    let mut g = read_dem(path, &ReadOptions::DEFAULT)?.grid;
    fill_voids(&mut g, &FillOptions::DEFAULT)?;
    for h in g.heights_mut() {
        *h = h.round();
    }
    Ok(g)
}

fn main() -> Result<(), Box<dyn Error>> {
    let mut json_out = false;
    let mut errors = vec![20.0, 5.0, 1.0];
    let mut files = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--json" => json_out = true,
            "--errors" => {
                let v = args.next().ok_or("--errors needs a list such as 20,5,1")?;
                errors = v
                    .split(',')
                    .map(|s| s.trim().parse::<f64>())
                    .collect::<Result<_, _>>()?;
            }
            _ => files.push(PathBuf::from(a)),
        }
    }
    if files.is_empty() {
        files.push(cota_fixtures::fixture(cota_fixtures::BUNDLED_TILE));
    }
    let modes = [
        Mode::Conforming,
        Mode::Fictitious { watertight: true },
        Mode::Fictitious { watertight: false },
    ];
    let mut rows = Vec::new();
    for f in &files {
        let grid = load(f)?;
        let name = f
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        for mode in modes {
            for &e in &errors {
                let so = StreamOptions::default().with_max_error_m(e);
                let crit = MaxVerticalError { max_error_m: e };
                let (_, marks) =
                    refine_marks(&grid, &crit, &RefineOptions::DEFAULT.with_mode(mode))?;
                let one = encode_marks(&grid, &marks, mode, &so)?;
                let one_bytes = stream_bytes(&one, grid.georef()).len();
                let one_tris = one.steps[0].triangles;
                let p = encode_marks_progressive(&grid, mode, &so)?;
                let ends = step_end_offsets(&p, grid.georef());
                let steps: Vec<_> = p
                    .steps
                    .iter()
                    .zip(&ends)
                    .enumerate()
                    .map(|(k, (s, &end))| {
                        json!({
                            "step": k,
                            "threshold_m": if k == 0 { None } else { Some(s.threshold_m) },
                            "max_error_m": s.max_error_m,
                            "new_points": s.new_points,
                            "total_bytes": end,
                            "triangles": s.triangles,
                            "vertices": s.vertices,
                            "bytes_per_triangle": end as f64 / s.triangles as f64,
                            "bytes_per_point": end as f64 / s.vertices as f64,
                        })
                    })
                    .collect();
                let last = p.steps.last().ok_or("no step")?;
                let total = *ends.last().ok_or("no step")?;
                let row = json!({
                    "dem": name,
                    "mode": mode.name(),
                    "max_error_m": e,
                    "one_step_bytes": one_bytes,
                    "one_step_triangles": one_tris,
                    "one_step_stated_m": one.steps[0].max_error_m,
                    "one_step_b_per_tri": one_bytes as f64 / one_tris as f64,
                    "progressive_bytes": total,
                    "progressive_triangles": last.triangles,
                    "progressive_stated_m": last.max_error_m,
                    "progressive_b_per_tri": total as f64 / last.triangles as f64,
                    "steps": steps,
                });
                if !json_out {
                    println!(
                        "\n{name} {} E = {e} m: one step {one_bytes} B, {one_tris} triangles, {:.3} B/tri (stated {:.3} m); progressive {total} B, {} triangles, {:.3} B/tri (stated {:.3} m), {} steps",
                        mode.name(),
                        one_bytes as f64 / one_tris as f64,
                        one.steps[0].max_error_m,
                        last.triangles,
                        total as f64 / last.triangles as f64,
                        last.max_error_m,
                        p.steps.len()
                    );
                    println!("| step | tolerance m | stated max err m | heights sent | bytes | triangles | vertices | B/tri | B/pt |");
                    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
                    for (k, (s, &end)) in p.steps.iter().zip(&ends).enumerate() {
                        let thr = if k == 0 {
                            "coarse".to_string()
                        } else {
                            format!("{}", s.threshold_m)
                        };
                        println!(
                            "| {k} | {thr} | {:.3} | {} | {end} | {} | {} | {:.3} | {:.3} |",
                            s.max_error_m,
                            s.new_points,
                            s.triangles,
                            s.vertices,
                            end as f64 / s.triangles as f64,
                            end as f64 / s.vertices as f64
                        );
                    }
                }
                rows.push(row);
            }
        }
    }
    if json_out {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    }
    Ok(())
}
