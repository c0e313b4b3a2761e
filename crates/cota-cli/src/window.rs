//! `--crop` and `--bbox`: the window of the input a command works on, cut
//! with the core's [`HeightGrid::window`].

use cota_core::{HeightGrid, PixelIs};

use crate::args::Crop;

/// The window `c` of `g`, with its georeference shifted to the window.
pub fn crop(g: &HeightGrid, c: &Crop) -> anyhow::Result<HeightGrid> {
    let bad = || {
        anyhow::anyhow!(
            "--crop {},{},{},{}: expected a window of at least 2x2 samples inside the {}x{} grid",
            c.col,
            c.row,
            c.width,
            c.height,
            g.width(),
            g.height()
        )
    };
    if c.width < 2 || c.height < 2 {
        return Err(bad());
    }
    g.window(c.col, c.row, c.width, c.height).map_err(|_| bad())
}

/// Largest distance, in pixels, by which a sample centre may lie outside the
/// box and still count as inside (rounding of the box's decimal figures).
const EDGE_TOL_PX: f64 = 1e-6;

/// The first and last index (clamped to `0..n`) of the samples whose centre
/// lies between coordinates `a` and `b` on an axis of `origin` + (i + `half`)
/// × `pixel`; `None` when no sample does.
fn span(a: f64, b: f64, origin: f64, pixel: f64, half: f64, n: usize) -> Option<(usize, usize)> {
    let ia = (a - origin) / pixel - half;
    let ib = (b - origin) / pixel - half;
    let lo = (ia.min(ib) - EDGE_TOL_PX).ceil().max(0.0);
    let hi = (ia.max(ib) + EDGE_TOL_PX).floor().min(n as f64 - 1.0);
    (lo <= hi).then_some((lo as usize, hi as usize))
}

/// The samples of `g` whose centres lie in the box `[west, south, east,
/// north]`, in the CRS units of `g` (degrees of longitude and latitude for
/// SRTM and geographic rasters, metres for projected ones).
pub fn bbox(g: &HeightGrid, b: [f64; 4]) -> anyhow::Result<HeightGrid> {
    let geo = g.georef();
    let [w, s, e, n] = b;
    if !geo.known {
        anyhow::bail!("--bbox: the input has no georeference; use --crop COL,ROW,W,H instead");
    }
    if !(w < e && s < n) {
        anyhow::bail!(
            "--bbox: expected W,S,E,N with WEST < EAST and SOUTH < NORTH, found {w},{s},{e},{n}"
        );
    }
    let half = match geo.pixel_is {
        PixelIs::Area => 0.5,
        PixelIs::Point => 0.0,
    };
    let cols = span(w, e, geo.origin_x, geo.pixel_x, half, g.width());
    let rows = span(n, s, geo.origin_y, geo.pixel_y, half, g.height());
    let (x0, y0) = geo.sample_xy(0.0, 0.0);
    let (x1, y1) = geo.sample_xy((g.width() - 1) as f64, (g.height() - 1) as f64);
    let (bad_w, bad_s, bad_e, bad_n) = (x0.min(x1), y0.min(y1), x0.max(x1), y0.max(y1));
    match (cols, rows) {
        (Some((c0, c1)), Some((r0, r1))) if c1 > c0 && r1 > r0 => {
            Ok(g.window(c0, r0, c1 - c0 + 1, r1 - r0 + 1)?)
        }
        _ => anyhow::bail!(
            "--bbox {w},{s},{e},{n}: expected a box holding at least 2x2 samples of the input, \
             whose sample centres span {bad_w},{bad_s},{bad_e},{bad_n} ({})",
            geo.crs
        ),
    }
}
