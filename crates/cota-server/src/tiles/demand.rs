//! [`DemandTileSource`]: quantized-mesh tiles made on demand from one
//! prepared hierarchy in memory.
//!
//! The pyramid is the one `cota tiles` writes (issue 17's design,
//! `ARCHITECTURE.md`): the source resampled onto the tiling's lattice, one
//! bitree over it ([`Prepared`], built once at start), and each requested
//! tile cut from it and encoded by [`make_tile`] (quantized-mesh-1.0,
//! CesiumGS/quantized-mesh), so a tile made here is byte for byte the file
//! `cota tiles` writes with the same options, and same-zoom neighbours share
//! their borders whichever order they are asked in.
//!
//! The source makes a tile each time it is asked: the server asks on its
//! bounded worker pool, once per tile at a time (concurrent requests for one
//! tile share one making), and keeps what it made in its byte-bounded LRU
//! cache.

use axum::body::Bytes;
use cota_core::tiles::{Lattice, LatticeOptions, Prepared, Source, TilerOptions};
use cota_core::{GeoTransform, HeightGrid};
use cota_tiles::{layer_json, make_tile, make_tiles3d, PyramidOptions, TileExtensions, TileFormat};

use super::{check_in_world, etag_of, Tile, TileId, TileSource};
use crate::error::{Result, ServeError};

self_cell::self_cell!(
    /// The lattice and the hierarchy prepared over it (which borrows it).
    struct Pyramid {
        owner: Lattice,
        #[covariant]
        dependent: Prepared,
    }
    impl {Debug}
);

/// Tiles made on demand from a prepared hierarchy (see the module docs).
#[derive(Debug)]
pub struct DemandTileSource {
    pyramid: Pyramid,
    options: PyramidOptions,
    layer: Bytes,
}

impl DemandTileSource {
    /// Resamples `grid` onto the tiling's lattice and prepares its hierarchy
    /// (`cota tiles`' first steps); tiles are then encoded with `options`.
    ///
    /// # Errors
    /// [`ServeError::Tiling`]: a source that is not geographic, has voids or
    /// lies outside the world, options out of range, a lattice too large.
    ///
    /// # Runtime
    /// The lattice's resampling and its bitree: `O(n log n)` for `n` lattice
    /// samples (about a second for two SRTM 3" tiles on two cores).
    pub fn new(
        grid: &HeightGrid,
        lattice: &LatticeOptions,
        tiler: &TilerOptions,
        options: PyramidOptions,
    ) -> Result<Self> {
        let lattice = Lattice::resample(grid, lattice)?;
        let pyramid = Pyramid::try_new(lattice, |l| Prepared::new(l, grid, tiler))?;
        Ok(Self::of(pyramid, options))
    }

    /// [`DemandTileSource::new`] for a grid in any CRS that `transform` takes
    /// to WGS 84 longitude/latitude (a projected DEM): resampled once onto
    /// the lattice through it ([`cota_core::tiles::sources`]).
    ///
    /// # Errors
    /// As [`DemandTileSource::new`].
    pub fn projected(
        grid: &HeightGrid,
        transform: &dyn GeoTransform,
        lattice: &LatticeOptions,
        tiler: &TilerOptions,
        options: PyramidOptions,
    ) -> Result<Self> {
        let source = Source { grid, transform };
        let r = Lattice::resample_sources(&[source], lattice)?;
        let samples = r.samples;
        let pyramid = Pyramid::try_new(r.lattice, |l| Prepared::new_sampled(l, &samples, tiler))?;
        Ok(Self::of(pyramid, options))
    }

    /// The source over a prepared pyramid.
    fn of(pyramid: Pyramid, options: PyramidOptions) -> Self {
        let layer = layer_json(pyramid.borrow_dependent(), &options.extensions);
        DemandTileSource {
            layer: Bytes::from(format!("{layer:#}\n")),
            pyramid,
            options,
        }
    }

    /// The prepared hierarchy the tiles are cut from.
    pub fn prepared(&self) -> &Prepared<'_> {
        self.pyramid.borrow_dependent()
    }

    /// The core's name of tile `id`, when the pyramid has it.
    fn find(&self, id: TileId) -> Result<cota_core::tiles::TileId> {
        check_in_world(id, true)?;
        let prep = self.prepared();
        let t = u8::try_from(id.z)
            .ok()
            .filter(|&z| {
                prep.in_range(cota_core::tiles::TileId {
                    z,
                    x: id.x,
                    y: id.y,
                })
            })
            .map(|z| cota_core::tiles::TileId {
                z,
                x: id.x,
                y: id.y,
            });
        t.ok_or_else(|| {
            ServeError::NotFound(format!(
                "tile {}/{}/{} is not in the layer",
                id.z, id.x, id.y
            ))
        })
    }

    /// Makes tile `t` (cut, encoded, gzipped as the options say).
    fn make(&self, t: cota_core::tiles::TileId) -> std::result::Result<Tile, String> {
        let m = make_tile(self.prepared(), t, &self.options, None).map_err(|e| e.to_string())?;
        Ok(Tile {
            gzip: self.options.gzip,
            etag: etag_of(&m.bytes),
            bytes: Bytes::from(m.bytes),
        })
    }
}

impl TileSource for DemandTileSource {
    fn layer_json(&self) -> &Bytes {
        &self.layer
    }

    /// `cota tiles --format 3dtiles --meshopt` of the same hierarchy (with
    /// `--normals` when the quantized-mesh tiles carry normals), byte for
    /// byte.
    fn tiles3d(&self) -> Option<std::result::Result<super::Files, String>> {
        let normals = self.options.extensions.normals;
        let opts = PyramidOptions::DEFAULT
            .with_extensions(TileExtensions::with(normals, false, false))
            .with_meshopt(true)
            .with_format(TileFormat::Tiles3d);
        Some(make_tiles3d(self.prepared(), &opts).map_err(|e| e.to_string()))
    }

    fn makes_tiles3d(&self) -> bool {
        true
    }

    fn has(&self, id: TileId) -> Result<()> {
        self.find(id).map(|_| ())
    }

    fn tile(&self, id: TileId) -> Result<Tile> {
        let t = self.find(id)?;
        self.make(t)
            .map_err(|e| ServeError::Internal(format!("tile {t}: {e}")))
    }
}
