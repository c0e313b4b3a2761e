//! `cota serve`: read and mosaic DEM files like `cota mesh` (or take a
//! `.cstream`); drape `--texture` on the DEM (and choose paper 004's pair
//! with `--pair-budget-bytes`) before listening, so that a bad image stops
//! the start; listen, and make in the background what takes time:
//! the progressive stream, the tiles' hierarchy (tiles made on demand; or a
//! `cota tiles` directory with `--tiles`) and the shaded-relief imagery.
//! Until each is ready its routes answer 503 with `Retry-After`. Stops on
//! Ctrl-C or SIGTERM.

use std::net::{SocketAddr, ToSocketAddrs};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use cota_core::tiles::TilesError;
use cota_core::HeightGrid;
use cota_io::stream_file::MAGIC;
use cota_server::texture::{PAIR_URL, TEXTURE_URL};
use cota_server::tiles3d::{is_tiles3d, Tiles3dFiles};
use cota_server::{
    DemandTileSource, DirTileSource, Imagery, MbtilesTileSource, ServeError, ServeOptions,
    ServerState, StreamAsset, TextureLevel, Textures, TileSource,
};
use cota_tiles::{PyramidOptions, TileExtensions, TileSettings};

use crate::args::{ServeArgs, ServeTextureArgs, Voids};
use crate::input::{fill, load, name};

/// The extensions and encoding of tiles made on demand: normals and
/// metadata (child availability), gzipped.
const DEMAND_TILES: PyramidOptions = PyramidOptions::DEFAULT
    .with_extensions(TileExtensions::with(true, false, true))
    .with_gzip(true);

/// What the background makes from: a `.cstream` (read and checked in the
/// foreground) or a grid.
enum Source {
    Stream(Box<StreamAsset>),
    Grid(Arc<HeightGrid>, String),
}

/// The `.cstream` given alone, if that is what the input is.
fn stream_file(a: &ServeArgs) -> Option<PathBuf> {
    let [one] = a.input.files.as_slice() else {
        return None;
    };
    let mut head = [0u8; 8];
    let is_stream = std::fs::File::open(one)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
        .is_ok()
        && &head == MAGIC;
    is_stream.then(|| one.clone())
}

/// Reads the input in the foreground (errors name the file before the
/// server listens); a `.cstream` is checked by decoding it. Also what the
/// reading warned of, and the voids filled.
fn source_of(a: &ServeArgs) -> anyhow::Result<(Source, Vec<String>)> {
    if let Some(f) = stream_file(a) {
        let cap = cota_io::limits::max_file_bytes(&cota_io::ReadOptions::DEFAULT);
        let bytes = cota_io::limits::read_file_capped(&f, cap)
            .with_context(|| format!("reading {}", f.display()))?;
        let s = StreamAsset::from_stream_bytes(bytes, &f.display().to_string())?;
        return Ok((Source::Stream(Box::new(s)), Vec::new()));
    }
    let input = load(&a.input)?;
    let mut warnings = input.warnings;
    let mut grid = input.grid;
    let report = fill(&mut grid, a.voids)?;
    if report.filled > 0 {
        let how = match a.voids {
            Voids::Hole => "filled with a constant height in the stream (no tiles are made)",
            Voids::Idw => "filled by inverse-distance weighting",
            _ => "filled harmonically (smooth surfaces from the void's rim)",
        };
        warnings.push(format!(
            "{}: {} void samples (no data) in {} areas, {how} (--voids)",
            name(&input.files),
            report.filled,
            report.components
        ));
    }
    Ok((Source::Grid(Arc::new(grid), name(&input.files)), warnings))
}

/// `--bands`, `--assume-same-crs`, `--texture-max-side` and
/// `--pair-budget-bytes` need `--texture`; checked before any reading.
fn check_texture_flags(t: &ServeTextureArgs) -> anyhow::Result<()> {
    if t.texture.is_none() {
        let alone = [
            ("--bands", t.image.bands.is_some()),
            ("--assume-same-crs", t.image.assume_same_crs),
            ("--pair-budget-bytes", t.pair_budget_bytes.is_some()),
        ];
        if let Some((flag, _)) = alone.iter().find(|f| f.1) {
            anyhow::bail!("{flag}: expected --texture IMAGE with it, found none");
        }
    }
    anyhow::ensure!(
        t.texture_max_side >= 1,
        "--texture-max-side: expected 1 texel or more, found 0"
    );
    crate::pair::bands_of(&t.image)?;
    Ok(())
}

/// `--texture` draped on the grid, at most `--texture-max-side` a side, and
/// with `--pair-budget-bytes` the pair's texture level; in the foreground.
fn make_textures(t: &ServeTextureArgs, source: &Source) -> anyhow::Result<Option<Textures>> {
    let Some(image) = &t.texture else {
        return Ok(None);
    };
    let Source::Grid(grid, _) = source else {
        anyhow::bail!(
            "--texture {}: expected a DEM to drape it on, found a .cstream (it holds no grid)",
            image.display()
        );
    };
    let time = Instant::now();
    let (rgb, about) = crate::pair::drape_image_within(grid, image, &t.image, t.texture_max_side)?;
    let level = TextureLevel::from_rgb(&rgb, TEXTURE_URL, about)?;
    let m = level.meta();
    println!(
        "texture     {} (bands {}): {} x {} texels, {} bytes of PNG, ready in {:.0} ms",
        image.display(),
        m.about["bands"].as_str().unwrap_or(""),
        m.width,
        m.height,
        m.bytes,
        ms(time)
    );
    let pair = match t.pair_budget_bytes {
        Some(n) => Some(make_pair(grid, &rgb, n)?),
        None => None,
    };
    Ok(Some(Textures { image: level, pair }))
}

/// Paper 004's pair within `budget` bytes; its texture level.
fn make_pair(
    grid: &HeightGrid,
    rgb: &cota_core::texture::RgbImage,
    budget: u64,
) -> anyhow::Result<TextureLevel> {
    let time = Instant::now();
    let (png, about) = crate::pair::best_pair(grid, rgb, budget)?;
    println!(
        "pair        within {budget} bytes: {} at {} m ({} triangles) + texture at tolerance {} ({} leaves), {} bytes; chosen in {:.0} ms",
        about["hierarchy"].as_str().unwrap_or(""),
        about["tolerance_m"],
        about["triangles"],
        about["texture_tolerance"],
        about["leaves"],
        about["bytes"],
        ms(time)
    );
    Ok(TextureLevel::from_png(
        png,
        [rgb.width(), rgb.height()],
        PAIR_URL,
        about,
    ))
}

/// The addresses `--addr` names: an IP address and port, or a host name
/// and port resolved to each of its addresses.
fn addresses(addr: &str) -> anyhow::Result<Vec<SocketAddr>> {
    let mut v: Vec<SocketAddr> = addr
        .to_socket_addrs()
        .with_context(|| {
            format!(
                "--addr {addr}: expected HOST:PORT (127.0.0.1:8080, [::1]:8080, localhost:8080)"
            )
        })?
        .collect();
    v.dedup();
    anyhow::ensure!(
        !v.is_empty(),
        "--addr {addr}: the name resolves to no address"
    );
    Ok(v)
}

fn options(a: &ServeArgs) -> ServeOptions {
    let mut o = ServeOptions::default()
        .with_queue(a.queue)
        .with_cache_bytes(a.cache_mib.saturating_mul(1 << 20))
        .with_max_connections(a.max_connections)
        .with_header_timeout_s(a.header_timeout_s)
        .with_request_timeout_s(a.request_timeout_s);
    if let Some(n) = a.workers {
        o = o.with_workers(n);
    }
    o
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Encodes (or checks) the stream.
fn make_stream(source: &Source) -> Result<StreamAsset, String> {
    let t = Instant::now();
    let s = match source {
        Source::Stream(s) => s.as_ref().clone(),
        Source::Grid(grid, name) => {
            StreamAsset::from_grid(grid, name).map_err(|e| e.to_string())?
        }
    };
    let m = s.meta();
    println!(
        "stream      {} ({} x {}): {} bytes in {} steps, ready in {:.0} ms",
        m.name,
        m.width,
        m.height,
        m.bytes,
        m.steps.len(),
        ms(t)
    );
    Ok(s)
}

/// `--tiles DIR` (or an `.mbtiles` archive), opened in the foreground (an
/// unusable one stops the start).
fn open_tiles(dir: &Path) -> anyhow::Result<Arc<dyn TileSource>> {
    let ctx = || format!("--tiles {}", dir.display());
    let src: Arc<dyn TileSource> = if cota_tiles::is_mbtiles(dir) {
        Arc::new(MbtilesTileSource::open(dir).with_context(ctx)?)
    } else {
        Arc::new(DirTileSource::open(dir).with_context(ctx)?)
    };
    println!("tiles       {}", dir.display());
    Ok(src)
}

/// Tiles made on demand from `grid` (none for a stream, or a source that
/// is not geographic: said, not fatal).
fn make_tiles(
    grid: Option<&HeightGrid>,
    holes: bool,
) -> Result<Option<Arc<dyn TileSource>>, String> {
    let Some(grid) = grid else {
        println!("tiles       none (a stream holds no grid to tile; use --tiles DIR)");
        return Ok(None);
    };
    if holes {
        println!("tiles       none: {}", crate::tiles::HOLES_REFUSED);
        return Ok(None);
    }
    let t = Instant::now();
    let source = demand_source(grid);
    match source {
        Ok(src) => {
            let p = src.prepared();
            println!(
                "tiles       on demand: zooms {}..={}, {} tiles, prepared in {:.0} ms",
                p.zooms().first().map_or(0, |z| z.zoom),
                p.lattice().scheme().max_zoom,
                p.tile_count(),
                ms(t)
            );
            Ok(Some(Arc::new(src)))
        }
        Err(ServeError::Tiling(e @ TilesError::NotGeographic { .. })) => {
            println!("tiles       none: {e}");
            Ok(None)
        }
        Err(e) => Err(format!("preparing tiles on demand: {e}")),
    }
}

/// The shaded-relief imagery of `grid` (none for a stream or a projected grid).
fn make_imagery(grid: Option<&Arc<HeightGrid>>) -> Option<Imagery> {
    let t = Instant::now();
    match grid.map(|g| Imagery::new(g.clone())) {
        Some(Ok(i)) => {
            let r = i.relief();
            println!(
                "imagery     shaded relief: zooms 0..={}, prepared in {:.0} ms",
                r.max_zoom(),
                ms(t)
            );
            Some(i)
        }
        Some(Err(e)) => {
            println!("imagery     none: {e}");
            None
        }
        None => None,
    }
}

/// Makes, on one thread, the imagery (a fraction of a second), the stream,
/// then (unless `--tiles DIR` gave them) the tiles' hierarchy, each set on
/// `state` as soon as it is ready. One after the other: the stream's
/// encoder and the tiler each take several times the grid's memory at
/// their peak.
fn start_background(state: &ServerState, source: Source, tiles_given: bool, holes: bool) {
    let state = state.clone();
    std::thread::spawn(move || {
        let grid = match &source {
            Source::Grid(g, _) => Some(g),
            Source::Stream(_) => None,
        };
        state.set_imagery(Ok(make_imagery(grid)));
        state.set_stream(make_stream(&source));
        if !tiles_given {
            let tiles = make_tiles(grid.map(|g| g.as_ref()), holes);
            if let Err(e) = &tiles {
                eprintln!("cota serve: {e}");
            }
            state.set_tiles(tiles);
        }
    });
}

/// Tiles on demand from `grid`: along its own axes when it is in WGS 84
/// longitude/latitude, through its projection otherwise (a grid whose CRS
/// cannot be placed on the Earth gets none: said, not fatal).
fn demand_source(grid: &HeightGrid) -> Result<DemandTileSource, ServeError> {
    // `cota tiles`' default settings (the job's), so that its tiles are
    // the ones `cota tiles` writes by default.
    let settings = TileSettings::DEFAULT;
    let (lattice, tiler) = (&settings.lattice_options(), &settings.tiler_options());
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
    let addrs = addresses(&a.addr)?;
    check_texture_flags(&a.texture)?;
    let (source, warnings) = source_of(a)?;
    let mut state = ServerState::starting(options(a)).with_warnings(warnings);
    if let Some(textures) = make_textures(&a.texture, &source)? {
        state = state.with_textures(textures);
    }
    let three_d = a.tiles.as_deref().filter(|d| is_tiles3d(d));
    if let Some(path) = three_d {
        let files = Tiles3dFiles::open(path)
            .map_err(|e| anyhow::anyhow!(e))
            .with_context(|| format!("--tiles {}", path.display()))?;
        println!(
            "3D Tiles    {} at /3dtiles/tileset.json (/cesium?3dtiles)",
            path.display()
        );
        state = state.with_tiles3d(files);
    } else if let Some(dir) = &a.tiles {
        state.set_tiles(Ok(Some(open_tiles(dir)?)));
    }
    let holes = matches!(a.voids, Voids::Hole);
    let given = a.tiles.is_some() && three_d.is_none();
    start_background(&state, source, given, holes);
    cota_server::run(&addrs, state, |bound| {
        let urls: Vec<String> = bound.iter().map(|b| format!("http://{b}/")).collect();
        println!(
            "listening   {} (viewer), /cesium, /stream, /tiles/, /imagery/, /health; in {:.0} ms; Ctrl-C stops",
            urls.join(" and "),
            ms(t)
        );
    })?;
    println!("stopped");
    Ok(ExitCode::SUCCESS)
}
