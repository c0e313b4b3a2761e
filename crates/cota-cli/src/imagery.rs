//! `cota tiles --imagery`: shaded-relief PNG tiles beside the terrain
//! (`OUT/imagery/{z}/{x}/{y}.png`, `OUT/imagery/imagery.json`), the tiles
//! `cota serve` sends at `/imagery/` ([`cota_io::relief`]).

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use cota_core::relief::{Relief, ReliefOptions};
use cota_core::HeightGrid;

/// Writes the relief tiles of `grid` (zooms 0 to where a pixel is a DEM
/// cell) into `out/imagery`; says how many on standard error.
pub fn write(grid: &HeightGrid, out: &Path) -> anyhow::Result<()> {
    let t = Instant::now();
    let relief =
        Relief::new(Arc::new(grid.clone()), &ReliefOptions::DEFAULT).context("--imagery")?;
    let dir = out.join("imagery");
    // At most these: a tile without data is not written.
    let most: usize = (0..=relief.max_zoom())
        .map(|z| relief.tiles_at(z).count())
        .sum();
    let pb = crate::progress::bar(most as u64, "imagery");
    let n = cota_io::relief::write_relief_tiles(&relief, &dir, relief.max_zoom(), &|n| {
        pb.set_position(n as u64)
    })
    .context("--imagery")?;
    pb.set_position(most as u64);
    drop(pb);
    if crate::progress::quiet() {
        return Ok(());
    }
    eprintln!(
        "imagery     {n} shaded-relief tiles, zooms 0..={} in {} ({:.1} s)",
        relief.max_zoom(),
        dir.display(),
        t.elapsed().as_secs_f64()
    );
    Ok(())
}
