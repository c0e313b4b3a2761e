//! Joining DEMs already read into one grid: [`Region`], [`RegionOptions`] and
//! [`join`], the second half of [`read_region`](super::read_region) (which
//! reads the files, in parallel, and hands them here).
//!
//! The steps, each a `cota_core` call: [`mosaic`] (tiles placed by their
//! georeference, overlaps compared and combined, samples no tile covers left
//! as voids), then, when [`RegionOptions::fill`] asks for it, [`fill_voids`].

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
