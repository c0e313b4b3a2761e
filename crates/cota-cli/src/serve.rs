//! `cota serve`: read and mosaic DEM files like `cota mesh` (or take a
//! `.cstream`), encode the progressive stream, and serve it with the viewer,
//! the CesiumJS page and quantized-mesh tiles: with `--tiles`, a `cota tiles`
//! directory; without, tiles made on demand from the hierarchy prepared in
//! memory (`cota_server`). Stops on Ctrl-C or SIGTERM.

use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use cota_core::tiles::{LatticeOptions, TilerOptions, TilesError};
use cota_core::HeightGrid;
use cota_io::stream_file::MAGIC;
use cota_io::tiles::{PyramidOptions, TileExtensions};
use cota_server::{
    DemandTileSource, DirTileSource, ServeError, ServerState, StreamAsset, TileSource,
};

use crate::args::ServeArgs;
use crate::input::{fill, load, name};

/// The stream of the inputs (a `.cstream` as it is, DEMs encoded
/// losslessly) and, for DEMs, their grid.
fn stream_of(a: &ServeArgs) -> anyhow::Result<(StreamAsset, Option<HeightGrid>)> {
    if let [one] = a.input.files.as_slice() {
        let mut head = [0u8; 8];
        let is_stream = std::fs::File::open(one)
            .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
            .is_ok()
            && &head == MAGIC;
        if is_stream {
            let bytes = std::fs::read(one).with_context(|| format!("reading {}", one.display()))?;
            let name = one.display().to_string();
            return Ok((StreamAsset::from_stream_bytes(bytes, &name)?, None));
        }
    }
    let input = load(&a.input)?;
    let mut grid = input.grid;
    fill(&mut grid, a.voids)?;
    let _spinner = crate::progress::spinner("encoding");
    let stream = StreamAsset::from_grid(&grid, &name(&input.files))?;
    Ok((stream, Some(grid)))
}

/// The extensions and encoding of tiles made on demand: normals and
/// metadata (child availability), gzipped.
const DEMAND_TILES: PyramidOptions = PyramidOptions::DEFAULT
    .with_extensions(TileExtensions::with(true, false, true))
    .with_gzip(true);

/// The tile source: `--tiles DIR`, or tiles made on demand from `grid`
/// (none for a stream, or a source that is not geographic: said, not fatal).
fn tiles_of(
    a: &ServeArgs,
    grid: Option<&HeightGrid>,
) -> anyhow::Result<Option<Arc<dyn TileSource>>> {
    if let Some(dir) = &a.tiles {
        let src = DirTileSource::open(dir).with_context(|| format!("--tiles {}", dir.display()))?;
        println!("tiles       {}", dir.display());
        return Ok(Some(Arc::new(src)));
    }
    let Some(grid) = grid else {
        println!("tiles       none (a stream holds no grid to tile; use --tiles DIR)");
        return Ok(None);
    };
    if matches!(a.voids, crate::args::Voids::Hole) {
        println!("tiles       none: {}", crate::tiles::HOLES_REFUSED);
        return Ok(None);
    }
    let t = Instant::now();
    let spinner = crate::progress::spinner("preparing tiles");
    let source = demand_source(grid);
    drop(spinner);
    match source {
        Ok(src) => {
            let p = src.prepared();
            println!(
                "tiles       on demand: zooms {}..={}, {} tiles, prepared in {:.0} ms",
                p.zooms().first().map_or(0, |z| z.zoom),
                p.lattice().scheme().max_zoom,
                p.tile_count(),
                t.elapsed().as_secs_f64() * 1e3
            );
            Ok(Some(Arc::new(src)))
        }
        Err(ServeError::Tiling(e @ TilesError::NotGeographic { .. })) => {
            println!("tiles       none: {e}");
            Ok(None)
        }
        Err(e) => Err(e).context("preparing tiles on demand"),
    }
}

/// Tiles on demand from `grid`: along its own axes when it is in WGS 84
/// longitude/latitude, through its projection otherwise (a grid whose CRS
/// cannot be placed on the Earth gets none: said, not fatal).
fn demand_source(grid: &HeightGrid) -> Result<DemandTileSource, ServeError> {
    let (lattice, tiler) = (&LatticeOptions::DEFAULT, &TilerOptions::DEFAULT);
    let g = grid.georef();
    let transform = cota_io::crs::transform_for_grid(g, grid.width(), grid.height());
    match transform {
        Ok(t) if !t.is_identity() => {
            DemandTileSource::projected(grid, t.as_ref(), lattice, tiler, DEMAND_TILES)
        }
        Ok(_) => DemandTileSource::new(grid, lattice, tiler, DEMAND_TILES),
        Err(e) => Err(ServeError::Tiling(TilesError::NotGeographic {
            crs: format!("{} ({e})", g.crs),
        })),
    }
}

pub fn run(a: &ServeArgs) -> anyhow::Result<ExitCode> {
    let t = Instant::now();
    let (stream, grid) = stream_of(a)?;
    let m = stream.meta();
    println!(
        "stream      {} ({} x {}): {} bytes in {} steps, ready in {:.0} ms",
        m.name,
        m.width,
        m.height,
        m.bytes,
        m.steps.len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let mut state = ServerState::new(stream);
    if let Some(src) = tiles_of(a, grid.as_ref())? {
        state = state.with_tiles(src);
    }
    drop(grid);
    cota_server::run(a.addr, state, |addr| {
        println!(
            "listening   http://{addr}/ (viewer), /cesium, /stream, /tiles/, /health; Ctrl-C stops"
        );
    })?;
    println!("stopped");
    Ok(ExitCode::SUCCESS)
}
