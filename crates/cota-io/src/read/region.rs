//! Joining DEMs already read into one grid: [`Region`], [`RegionOptions`] and
//! [`join`], the second half of [`read_region`](super::read_region) (which
//! reads the files, in parallel, and hands them here).
//!
//! The steps, each a `cota_core` call: [`mosaic`] (tiles placed by their
//! georeference, overlaps compared and combined, samples no tile covers left
//! as voids), then, when [`RegionOptions::fill`] asks for it, [`fill_voids`].

use cota_core::grid::mosaic::{layout, TileShape};
use cota_core::{
    fill_voids, grid::voids::FillReport, mosaic, FillOptions, HeightGrid, MosaicOptions, SeamReport,
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
