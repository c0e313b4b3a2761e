//! [`Imagery`]: shaded-relief PNG tiles made from the DEM
//! ([`cota_core::relief`], encoded by [`cota_io::relief::relief_png`]) for
//! `/imagery/{z}/{x}/{y}.png`, in the geographic tiling of the terrain
//! tiles (TMS rows), and their description at `/imagery.json`. A page
//! drapes them over the terrain so that relief reads without any imagery
//! from the network.

use std::sync::Arc;

use axum::body::Bytes;
use cota_core::relief::{Relief, ReliefOptions};
use cota_core::HeightGrid;

use crate::error::{Result, ServeError};
use crate::tiles::{check_in_world, etag_of, Tile, TileId};

/// Shaded-relief tiles of one DEM.
#[derive(Debug)]
pub struct Imagery {
    relief: Relief,
    json: Bytes,
}

impl Imagery {
    /// Prepares the relief of `grid` (shared, not copied; its box-filtered
    /// levels take a third of its memory).
    ///
    /// # Errors
    /// [`ServeError::Relief`] for a grid that is not geographic.
    pub fn new(grid: Arc<HeightGrid>) -> Result<Self> {
        let relief = Relief::new(grid, &ReliefOptions::DEFAULT)?;
        let v = cota_io::relief::imagery_json(&relief, "imagery/{z}/{x}/{y}.png");
        Ok(Imagery {
            json: Bytes::from(format!("{v:#}\n")),
            relief,
        })
    }

    /// The relief the tiles are drawn from.
    pub fn relief(&self) -> &Relief {
        &self.relief
    }

    /// `/imagery.json`.
    pub(crate) fn json(&self) -> &Bytes {
        &self.json
    }

    /// Checks that tile `id` holds some of the data.
    ///
    /// # Errors
    /// [`ServeError::BadRequest`] outside the world, [`ServeError::NotFound`]
    /// beyond the finest zoom or away from the data.
    pub(crate) fn check(&self, id: TileId) -> Result<()> {
        check_in_world(id, true)?;
        let found = u8::try_from(id.z)
            .ok()
            .filter(|&z| z <= self.relief.max_zoom() && self.relief.overlaps(z, id.x, id.y));
        found.map(|_| ()).ok_or_else(|| {
            ServeError::NotFound(format!(
                "imagery tile {}/{}/{} holds none of the data (zooms 0..={})",
                id.z,
                id.x,
                id.y,
                self.relief.max_zoom()
            ))
        })
    }

    /// Draws tile `id` (checked with [`Imagery::check`]).
    ///
    /// # Errors
    /// [`ServeError::NotFound`] for a tile without data.
    pub(crate) fn tile(&self, id: TileId) -> Result<Tile> {
        self.check(id)?;
        let z = u8::try_from(id.z).unwrap_or(u8::MAX);
        let png = cota_io::relief::relief_png(&self.relief, z, id.x, id.y).ok_or_else(|| {
            ServeError::NotFound(format!("imagery tile {}/{}/{}", id.z, id.x, id.y))
        })?;
        Ok(Tile {
            etag: etag_of(&png),
            gzip: false,
            bytes: Bytes::from(png),
        })
    }
}
