//! Joining DEMs already read into one grid: [`Region`], [`RegionOptions`] and
//! [`join`], the second half of [`read_region`](super::read_region) (which
//! reads the files, in parallel, and hands them here).
//!
//! The steps, each a `cota_core` call: [`mosaic`] (tiles placed by their
//! georeference, overlaps compared and combined, samples no tile covers left
//! as voids), then, when [`RegionOptions::fill`] asks for it, [`fill_voids`].

use cota_core::grid::mosaic::{layout, TileShape};
use cota_core::{
    fill_voids, grid::voids::FillReport, mosaic, FillOptions, GeoRef, HeightGrid, MosaicOptions,
    PixelIs, SeamReport,
};

use crate::dem::{Dem, DemSummary, ReadOptions};
use crate::error::RegionError;

/// Options of [`read_region`](super::read_region): how each file is read,
/// how the files are joined and what happens to the voids.
///
/// ```
/// use cota_core::{FillOptions, MosaicOptions, SeamPolicy};
/// use cota_io::RegionOptions;
/// let opts = RegionOptions::DEFAULT
///     .with_mosaic(MosaicOptions::DEFAULT.with_seam_policy(SeamPolicy::First))
///     .with_fill(None);
/// assert_eq!(opts.fill, None);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct RegionOptions {
    /// How each file is decoded. Default: [`ReadOptions::DEFAULT`].
    pub read: ReadOptions,
    /// How the files are joined (seam policy, hole and seam limits). Default:
    /// [`MosaicOptions::DEFAULT`] (overlapping samples averaged).
    pub mosaic: MosaicOptions,
    /// What is done with the voids of the joined grid (the files' own voids
    /// and the samples no file covers): `Some` applies [`fill_voids`] with
    /// these options (fill, or refuse with an error), `None` leaves them NaN.
    /// Default: `Some(FillOptions::DEFAULT)` (harmonic fill).
    pub fill: Option<FillOptions>,
}

impl RegionOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: RegionOptions = RegionOptions {
        read: ReadOptions::DEFAULT,
        mosaic: MosaicOptions::DEFAULT,
        fill: Some(FillOptions::DEFAULT),
    };

    /// Sets [`RegionOptions::read`].
    pub const fn with_read(mut self, read: ReadOptions) -> Self {
        self.read = read;
        self
    }

    /// Sets [`RegionOptions::mosaic`].
    pub const fn with_mosaic(mut self, mosaic: MosaicOptions) -> Self {
        self.mosaic = mosaic;
        self
    }

    /// Sets [`RegionOptions::fill`].
    pub const fn with_fill(mut self, fill: Option<FillOptions>) -> Self {
        self.fill = fill;
        self
    }
}

impl Default for RegionOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The grid of one or more files, joined (and filled when asked).
#[derive(Debug, Clone)]
pub struct Region {
    /// The joined grid. Voids are NaN unless [`RegionOptions::fill`] filled them.
    pub grid: HeightGrid,
    /// Each file as read, in input order.
    pub files: Vec<DemSummary>,
    /// The overlaps between the files; `None` for a single file.
    pub seams: Option<SeamReport>,
    /// Samples of the joined grid covered by no file.
    pub hole_samples: usize,
    /// Void samples of the joined grid before any fill (the files' voids plus
    /// the holes).
    pub voids: usize,
    /// What the fill did; `None` when [`RegionOptions::fill`] is `None`.
    pub fill: Option<FillReport>,
}

/// Joins DEMs already read into one [`Region`] per group of DEMs on the same
/// kind of grid (the same CRS, pixel size and pixel convention), each as
/// [`join`] joins them; a group whose DEMs do not mosaic (not aligned, say)
/// gives one region per DEM. Groups are in the order of their first DEM.
/// What `cota tiles` takes when its inputs differ in CRS or resolution: each
/// region is then one source of the tiling's lattice.
///
/// # Errors
/// As [`join`], for a DEM alone that cannot be taken.
pub fn join_groups(dems: Vec<Dem>, opts: &RegionOptions) -> Result<Vec<Region>, RegionError> {
    let mut groups: Vec<(String, Vec<Dem>)> = Vec::new();
    for d in dems {
        let g = d.grid.georef();
        let key = format!(
            "{} {:x} {:x} {:?} {}",
            g.crs,
            g.pixel_x.to_bits(),
            g.pixel_y.to_bits(),
            g.pixel_is,
            g.known
        );
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, v)) => v.push(d),
            None => groups.push((key, vec![d])),
        }
    }
    let mut out = Vec::new();
    for (_, group) in groups {
        if group.len() == 1 {
            out.push(join(group, opts)?);
            continue;
        }
        let shapes: Vec<TileShape> = group
            .iter()
            .map(|d| TileShape {
                width: d.grid.width(),
                height: d.grid.height(),
                georef: d.grid.georef().clone(),
            })
            .collect();
        if layout(&shapes, &opts.mosaic).is_ok() {
            out.push(join(group, opts)?);
        } else {
            for d in group {
                out.push(join(vec![d], opts)?);
            }
        }
    }
    Ok(out)
}

/// How far one input, resampled onto another's finer grid by
/// [`resample_join`], lies from its own samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Resampled {
    /// The input's files, joined with ", ".
    pub files: String,
    /// Its pixel size before, CRS units (the larger side).
    pub pixel: f64,
    /// The largest |resampled surface − sample| over its own samples,
    /// metres (0 where the finer grid holds each of them).
    pub max_deviation_m: f64,
}

/// One region from `regions` (from [`join_groups`]) in one CRS and of
/// several resolutions: each coarser region resampled once, bilinearly,
/// onto the finest region's grid (the same pixel size, samples aligned with
/// its own), then all mosaicked as [`join`] does (the finest first) and the
/// voids filled as `opts` says; with each resampled region's deviation at
/// its own samples. What `cota mesh` and `cota serve` make of inputs of
/// several resolutions (paper 001's DEMs of different sizes and
/// resolutions joined into one region without cracks).
///
/// # Errors
/// [`RegionError::Crs`] for regions in different CRSs, and as [`join`].
pub fn resample_join(
    mut regions: Vec<Region>,
    opts: &RegionOptions,
) -> Result<(Region, Vec<Resampled>), RegionError> {
    let pixel = |r: &Region| {
        r.grid
            .georef()
            .pixel_x
            .abs()
            .max(r.grid.georef().pixel_y.abs())
    };
    regions.sort_by(|a, b| pixel(a).total_cmp(&pixel(b)));
    let Some(finest) = regions.first() else {
        return Err(RegionError::NoFiles);
    };
    let reference = finest.grid.georef().clone();
    let lonlat = |c: &cota_core::Crs| crate::crs::transform_for(c).is_ok_and(|t| t.is_identity());
    for r in &regions[1..] {
        let crs = &r.grid.georef().crs;
        if *crs != reference.crs && !(lonlat(crs) && lonlat(&reference.crs)) {
            return Err(RegionError::Crs {
                first: names(&finest.files),
                first_crs: reference.crs.to_string(),
                other: names(&r.files),
                other_crs: r.grid.georef().crs.to_string(),
            });
        }
    }
    let mut report = Vec::new();
    let mut files = Vec::new();
    let mut grids = Vec::new();
    for (k, r) in regions.into_iter().enumerate() {
        files.extend(r.files.iter().cloned());
        if k == 0 {
            grids.push(r.grid);
            continue;
        }
        let onto = onto_grid(&r.grid, &reference);
        report.push(Resampled {
            files: names(&r.files),
            pixel: pixel(&r),
            max_deviation_m: deviation_at_samples(&r.grid, &onto),
        });
        grids.push(onto);
    }
    let m = mosaic(grids, &opts.mosaic).map_err(|source| RegionError::Mosaic {
        files: names(&files),
        source,
    })?;
    let mut grid = m.grid;
    let voids = grid.void_count();
    let fill = match &opts.fill {
        Some(f) => Some(fill_voids(&mut grid, f).map_err(RegionError::Fill)?),
        None => None,
    };
    let region = Region {
        grid,
        files,
        seams: Some(m.seams),
        hole_samples: m.hole_samples,
        voids,
        fill,
    };
    Ok((region, report))
}

/// `g` bilinearly resampled onto the grid of `reference`'s pixel sizes and
/// sample positions, over `g`'s own sample-centre extent (NaN next to a
/// void of `g`).
fn onto_grid(g: &HeightGrid, reference: &GeoRef) -> HeightGrid {
    let src = g.georef();
    let (rx0, ry0) = reference.sample_xy(0.0, 0.0);
    let (ax, ay) = src.sample_xy(0.0, 0.0);
    let (bx, by) = src.sample_xy(g.width() as f64 - 1.0, g.height() as f64 - 1.0);
    let (px, py) = (reference.pixel_x, reference.pixel_y);
    let idx = |v: f64, o: f64, p: f64| (v - o) / p;
    let (c0, c1) = (idx(ax, rx0, px), idx(bx, rx0, px));
    let (r0, r1) = (idx(ay, ry0, py), idx(by, ry0, py));
    let eps = 1e-9;
    let (cl, ch) = ((c0.min(c1) - eps).ceil(), (c0.max(c1) + eps).floor());
    let (rl, rh) = ((r0.min(r1) - eps).ceil(), (r0.max(r1) + eps).floor());
    let (w, h) = ((ch - cl) as usize + 1, (rh - rl) as usize + 1);
    let mut heights = vec![f32::NAN; w * h];
    for (j, row) in heights.chunks_mut(w).enumerate() {
        for (i, v) in row.iter_mut().enumerate() {
            let x = rx0 + (cl + i as f64) * px;
            let y = ry0 + (rl + j as f64) * py;
            let (sx, sy) = ((x - ax) / src.pixel_x, (y - ay) / src.pixel_y);
            *v = bilinear(g, sx, sy) as f32;
        }
    }
    let mut georef = reference.clone();
    let (ox, oy) = reference.sample_xy(cl, rl);
    let half = if matches!(reference.pixel_is, PixelIs::Area) {
        0.5
    } else {
        0.0
    };
    georef.origin_x = ox - half * px;
    georef.origin_y = oy - half * py;
    HeightGrid::new(w, h, heights, georef).unwrap_or_else(|_| g.clone())
}

/// The bilinear surface of `g` at fractional sample position `(c, r)`,
/// clamped into its samples; NaN next to a void.
fn bilinear(g: &HeightGrid, c: f64, r: f64) -> f64 {
    let (w, h) = (g.width() as f64 - 1.0, g.height() as f64 - 1.0);
    let (c, r) = (c.clamp(0.0, w.max(0.0)), r.clamp(0.0, h.max(0.0)));
    let i = (c as usize).min(g.width().saturating_sub(2));
    let j = (r as usize).min(g.height().saturating_sub(2));
    let (i1, j1) = ((i + 1).min(g.width() - 1), (j + 1).min(g.height() - 1));
    let (fx, fy) = (c - i as f64, r - j as f64);
    let z = |a: usize, b: usize| f64::from(g.get(a, b));
    let top = z(i, j) + (z(i1, j) - z(i, j)) * fx;
    let bottom = z(i, j1) + (z(i1, j1) - z(i, j1)) * fx;
    top + (bottom - top) * fy
}

/// The largest |bilinear surface of `onto` − sample| over the samples of
/// `g` (voids skipped).
fn deviation_at_samples(g: &HeightGrid, onto: &HeightGrid) -> f64 {
    let (o, s) = (onto.georef(), g.georef());
    let (ox, oy) = o.sample_xy(0.0, 0.0);
    let mut max = 0f64;
    for r in 0..g.height() {
        for c in 0..g.width() {
            let z = g.get(c, r);
            let (x, y) = s.sample_xy(c as f64, r as f64);
            let v = bilinear(onto, (x - ox) / o.pixel_x, (y - oy) / o.pixel_y);
            if !z.is_nan() && !v.is_nan() {
                max = max.max((v - f64::from(z)).abs());
            }
        }
    }
    max
}

/// Joins DEMs already read (in the order given) into a [`Region`], as
/// [`read_region`](super::read_region) does after reading its files.
///
/// # Errors
/// [`RegionError::NoFiles`] for an empty list, [`RegionError::Mosaic`] when
/// the tiles cannot be joined, [`RegionError::Fill`] when the void policy
/// fails or refuses.
pub fn join(dems: Vec<Dem>, opts: &RegionOptions) -> Result<Region, RegionError> {
    if dems.is_empty() {
        return Err(RegionError::NoFiles);
    }
    let files: Vec<DemSummary> = dems.iter().map(Dem::summary).collect();
    let several = files.len() > 1;
    let grids: Vec<HeightGrid> = dems.into_iter().map(|d| d.grid).collect();
    let m = mosaic(grids, &opts.mosaic).map_err(|source| RegionError::Mosaic {
        files: names(&files),
        source,
    })?;
    let mut grid = m.grid;
    let voids = grid.void_count();
    let fill = match &opts.fill {
        Some(f) => Some(fill_voids(&mut grid, f).map_err(RegionError::Fill)?),
        None => None,
    };
    Ok(Region {
        grid,
        files,
        seams: several.then_some(m.seams),
        hole_samples: m.hole_samples,
        voids,
        fill,
    })
}

/// The files' paths joined with ", ".
fn names(files: &[DemSummary]) -> String {
    let names: Vec<String> = files.iter().map(|f| f.path.display().to_string()).collect();
    names.join(", ")
}
