//! `export-grid`: hands the benchmark grids to other programs.
//!
//! * `export-grid raw NAME OUT`: writes grid `NAME` (`fuji513`, `puget1025`,
//!   `srtm1025`, `srtm1201`, `mosaic2`) as raw little-endian `f32`, row-major
//!   from the north-west corner, and prints `NAME WIDTH HEIGHT` on stdout. The
//!   JS and Python peers (`bench/peers-js-py.sh`) read these.
//! * `export-grid big-tiles DIR`: writes the files of the large grids
//!   ([`cota_bench::big`]) into `DIR` and prints, one line each,
//!   `NAME FILE…` for `srtm3601`, `mosaic8` and `big4097` (`bench/memory.sh`
//!   runs `cota mesh` on them).
//!
//! Run: `cargo run --release -p cota-bench --bin export-grid -- raw puget1025 /tmp/p.f32`.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use cota_bench::big::{big_files, load_mosaic2};
use cota_bench::load_cases;
use cota_core::HeightGrid;

fn grid(name: &str) -> anyhow::Result<HeightGrid> {
    if name == "mosaic2" {
        return load_mosaic2().map(|b| b.grid).map_err(anyhow::Error::msg);
    }
    for case in load_cases(|m| eprintln!("export-grid: {m}")) {
        if case.name == name {
            return Ok(case.square);
        }
        if let Some(native) = case.native {
            if name == format!("srtm{}", native.width()) {
                return Ok(native);
            }
        }
    }
    bail!("unknown or unavailable grid {name:?}; expected fuji513, puget1025, srtm1025, srtm1201 or mosaic2")
}

fn write_raw(g: &HeightGrid, out: &Path) -> anyhow::Result<()> {
    let f = std::fs::File::create(out).with_context(|| format!("creating {}", out.display()))?;
    let mut w = std::io::BufWriter::new(f);
    for h in g.heights() {
        w.write_all(&h.to_le_bytes())?;
    }
    w.flush()
        .with_context(|| format!("writing {}", out.display()))?;
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args
        .iter()
        .map(String::as_str)
        .collect::<Vec<_>>()
        .as_slice()
    {
        ["raw", name, out] => {
            let g = grid(name)?;
            write_raw(&g, Path::new(out))?;
            println!("{name} {} {}", g.width(), g.height());
        }
        ["big-tiles", dir] => {
            let dir = PathBuf::from(dir);
            let f =
                big_files(&dir, |m| eprintln!("export-grid: {m}")).map_err(anyhow::Error::msg)?;
            for (name, files) in [
                ("srtm3601", &f.tile3601),
                ("mosaic8", &f.mosaic8),
                ("big4097", &f.big4097),
            ] {
                let list: Vec<String> = files.iter().map(|p| p.display().to_string()).collect();
                println!("{name} {}", list.join(" "));
            }
        }
        _ => bail!("usage: export-grid raw NAME OUT.f32 | export-grid big-tiles DIR"),
    }
    Ok(())
}
