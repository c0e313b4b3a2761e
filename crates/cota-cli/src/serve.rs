//! `cota serve`: read and mosaic DEM files like `cota mesh` (or take a
//! `.cstream`), encode the progressive stream, and serve it with the viewer,
//! the CesiumJS page and, with `--tiles`, a `cota tiles` directory
//! (`cota_server`). Stops on Ctrl-C or SIGTERM.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use cota_io::stream_file::MAGIC;
use cota_server::{DirTileSource, ServerState, StreamAsset};

use crate::args::{InputArgs, Voids};
use crate::input::{fill, load, name};

#[derive(Debug, Args)]
pub struct ServeArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// A tile directory written by `cota tiles` (layer.json and
    /// {z}/{x}/{y}.terrain), served at /layer.json and /tiles/.
    #[arg(long, value_name = "DIR")]
    pub tiles: Option<PathBuf>,
    /// Address and port to listen on (port 0: any free port).
    #[arg(long, default_value = "127.0.0.1:8080", value_name = "IP:PORT")]
    pub addr: SocketAddr,
    /// What to do with voids (no data) before encoding.
    #[arg(long, value_enum, default_value_t = Voids::Fill)]
    pub voids: Voids,
}

/// The stream of the inputs: a `.cstream` as it is, DEMs encoded losslessly.
fn stream_of(a: &ServeArgs) -> anyhow::Result<StreamAsset> {
    if let [one] = a.input.files.as_slice() {
        let mut head = [0u8; 8];
        let is_stream = std::fs::File::open(one)
            .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
            .is_ok()
            && &head == MAGIC;
        if is_stream {
            let bytes = std::fs::read(one).with_context(|| format!("reading {}", one.display()))?;
            return Ok(StreamAsset::from_stream_bytes(
                bytes,
                &one.display().to_string(),
            )?);
        }
    }
    let input = load(&a.input)?;
    let mut grid = input.grid;
    fill(&mut grid, a.voids)?;
    Ok(StreamAsset::from_grid(&grid, &name(&input.files))?)
}

pub fn run(a: &ServeArgs) -> anyhow::Result<ExitCode> {
    let t = Instant::now();
    let stream = stream_of(a)?;
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
    if let Some(dir) = &a.tiles {
        let src = DirTileSource::open(dir).with_context(|| format!("--tiles {}", dir.display()))?;
        println!("tiles       {}", dir.display());
        state = state.with_tiles(Arc::new(src));
    }
    cota_server::run(a.addr, state, |addr| {
        println!("listening   http://{addr}/ (viewer), /cesium, /stream, /health; Ctrl-C stops");
    })?;
    println!("stopped");
    Ok(ExitCode::SUCCESS)
}
