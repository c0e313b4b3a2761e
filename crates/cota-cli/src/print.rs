//! STL print scale for `cota mesh`: `--scale 1:N` or `--size-mm W` turn the
//! local metres of the STL into millimetres of the printed model, heights
//! (already times `--z-scale`) at the same scale, all about the south-west
//! sample at 0 m.

use cota_core::HeightGrid;
use cota_io::export::MeshFormat;
use serde_json::json;

use crate::args::{CoordsArg, MeshArgs};
use crate::input::num;

/// The flag that sets the print scale, if any.
fn flag(a: &MeshArgs) -> Option<&'static str> {
    match (a.scale, a.size_mm) {
        (Some(_), _) => Some("--scale"),
        (None, Some(_)) => Some("--size-mm"),
        (None, None) => None,
    }
}

/// Refuses a print scale that makes no sense: a size that is not a
/// positive number, no output or one other than STL, grid coordinates.
pub fn validate(a: &MeshArgs, format: Option<MeshFormat>) -> anyhow::Result<()> {
    if let Some(mm) = a.base_mm {
        if !(mm.is_finite() && mm > 0.0) {
            anyhow::bail!(
                "--base-mm: expected a positive number of millimetres, found {}",
                num(mm)
            );
        }
        if flag(a).is_none() {
            anyhow::bail!(
                "--base-mm: expected --scale 1:N or --size-mm MM (millimetres of the model need a print scale); --base-m M sets the base in metres"
            );
        }
    }
    let Some(flag) = flag(a) else {
        return Ok(());
    };
    if let Some(mm) = a.size_mm {
        if !(mm.is_finite() && mm > 0.0) {
            anyhow::bail!(
                "--size-mm: expected a positive number of millimetres, found {}",
                num(mm)
            );
        }
    }
    match format {
        None => anyhow::bail!(
            "{flag}: expected -o OUT.stl (a print scale applies to STL output), found no output"
        ),
        Some(f) if f != MeshFormat::Stl => anyhow::bail!(
            "{flag}: expected an .stl output (a print scale applies to STL, written in millimetres), found .{f}"
        ),
        Some(_) => {}
    }
    if matches!(a.coords, CoordsArg::Grid) {
        anyhow::bail!(
            "{flag}: expected --coords local (a print scale applies to metres), found --coords grid"
        );
    }
    Ok(())
}

/// The grid's horizontal extent in metres, east-west and north-south.
fn extent_m(grid: &HeightGrid) -> [f64; 2] {
    let [dx, dy] = grid.cell_size_m();
    [
        (grid.width() - 1) as f64 * dx,
        (grid.height() - 1) as f64 * dy,
    ]
}

/// Millimetres of the model per metre of terrain, when a print scale is set.
pub fn mm_per_m(a: &MeshArgs, grid: &HeightGrid) -> anyhow::Result<Option<f64>> {
    match (a.scale, a.size_mm) {
        (Some(ratio), _) => Ok(Some(1000.0 * ratio)),
        (None, Some(mm)) => {
            let side = extent_m(grid)[0].max(extent_m(grid)[1]);
            let k = mm / side;
            if !(side > 0.0 && k.is_finite() && k > 0.0) {
                anyhow::bail!(
                    "--size-mm: expected a grid with a horizontal extent, found {} m",
                    num(side)
                );
            }
            Ok(Some(k))
        }
        (None, None) => Ok(None),
    }
}

/// The height of the solid's base in true metres (before `--z-scale`):
/// `--base-m`, or `--base-mm` below the lowest sample at the print scale.
/// A `--base-m` not below the lowest sample is refused here, before any
/// meshing, with the flag that fits any terrain.
pub fn base_m(a: &MeshArgs, grid: &HeightGrid) -> anyhow::Result<Option<f64>> {
    let lo = grid.valid_range().map_or(0.0, |(lo, _)| f64::from(lo));
    if let Some(b) = a.base_m.filter(|b| b.is_nan() || *b >= lo) {
        anyhow::bail!(
            "--base-m: expected a base below the lowest sample ({} m), found {} m; give a lower --base-m, or --base-mm MM for a base MM millimetres below the lowest point",
            num(lo),
            num(b)
        );
    }
    let (Some(mm), Some(k)) = (a.base_mm, mm_per_m(a, grid)?) else {
        return Ok(a.base_m);
    };
    Ok(Some(lo - mm / (k * a.z_scale)))
}

/// Adds the print fields to the report: the scale as 1:N, millimetres per
/// metre and the model's size in millimetres (x, y, and z from the base or
/// the lowest sample to the highest); `null` without a print scale.
pub fn add_fields(
    r: &mut serde_json::Value,
    a: &MeshArgs,
    grid: &HeightGrid,
) -> anyhow::Result<()> {
    let k = mm_per_m(a, grid)?;
    let [ex, ey] = extent_m(grid);
    let (lo, hi) = grid.valid_range().unwrap_or((0.0, 0.0));
    let bottom = base_m(a, grid)?.map_or(f64::from(lo), |b| b.min(f64::from(lo)));
    let relief_m = (f64::from(hi) - bottom) * a.z_scale;
    let fields = json!({
        "print_scale": k.map(|k| format!("1:{}", scale_n(1000.0 / k))),
        "print_mm_per_m": k,
        "print_size_mm": k.map(|k| [ex * k, ey * k, relief_m * k]),
    });
    if let (Some(r), serde_json::Value::Object(f)) = (r.as_object_mut(), fields) {
        r.extend(f);
    }
    Ok(())
}

/// N of a print scale 1:N as people write it: whole from 100 up (a
/// `--size-mm` gives 1:742218, not 1:742218.0622702213), else to four
/// significant figures.
fn scale_n(n: f64) -> String {
    if n.abs() >= 100.0 {
        format!("{n:.0}")
    } else {
        sig4(n)
    }
}

/// `v` to four significant figures, plainly.
fn sig4(v: f64) -> String {
    num(format!("{v:.3e}").parse().unwrap_or(v))
}

/// The print line of the text report, when a print scale is set.
pub fn text_line(s: &mut String, r: &serde_json::Value) {
    let (Some(scale), Some(size)) = (r["print_scale"].as_str(), r["print_size_mm"].as_array())
    else {
        return;
    };
    let mm: Vec<f64> = size.iter().filter_map(|v| v.as_f64()).collect();
    if let [x, y, z] = mm[..] {
        say!(
            s,
            "print       {scale} ({} mm per m): {x:.1} x {y:.1} mm, {z:.1} mm high; STL in millimetres",
            sig4(r["print_mm_per_m"].as_f64().unwrap_or(0.0))
        );
    }
}
