//! Command-line flags, turned into library option structs and nothing more.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

/// cota: terrain level of detail with guaranteed error, from real DEMs.
#[derive(Debug, Parser)]
#[command(name = "cota", version, about, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Describe DEM files: format, size, CRS, cell size, height range, voids, seams.
    Info(InfoArgs),
    /// Build a mesh with a guaranteed maximum error, or within a triangle budget.
    Mesh(MeshArgs),
}

/// How to read and combine the input files.
#[derive(Debug, Args)]
pub struct InputArgs {
    /// DEM files: SRTM .hgt/.hgt.zip, GeoTIFF, PNG, ESRI .asc. Several adjacent
    /// tiles are mosaicked. With none, the bundled sample S29W072.hgt.zip is used.
    #[arg(value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// PNG height encoding. Default: terrain-rgb for colour PNGs, gray16 for grayscale.
    #[arg(long, value_enum)]
    pub encoding: Option<Encoding>,
    /// Metres per gray level for --encoding gray16.
    #[arg(long, default_value_t = 1.0, value_name = "M")]
    pub gray_scale_m: f64,
    /// Metres added to gray levels for --encoding gray16.
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "M",
        allow_negative_numbers = true
    )]
    pub gray_offset_m: f64,
    /// Cell size in metres for inputs without georeference (PNG).
    #[arg(long, default_value_t = 1.0, value_name = "M")]
    pub cell_size_m: f64,
    /// Band to read from a multi-band raster (1-based).
    #[arg(long, value_name = "N")]
    pub band: Option<u16>,
    /// Where adjacent tiles overlap and disagree: their mean, or the first file's value.
    #[arg(long, value_enum, default_value_t = Seam::Mean)]
    pub seam: Seam,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Encoding {
    TerrainRgb,
    Terrarium,
    Gray16,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Seam {
    Mean,
    First,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Voids {
    /// Fill voids harmonically from their border (continuous surface).
    Fill,
    /// Fill voids by inverse distance from their border.
    Idw,
    /// Refuse inputs with voids.
    Refuse,
}

#[derive(Debug, Args)]
pub struct InfoArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum CoordsArg {
    /// x east, y north, z up, metres, origin at the south-west sample.
    Local,
    /// x = column, y = row from the northern row, z = metres.
    Grid,
}

#[derive(Debug, Args)]
pub struct MeshArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Maximum vertical error in metres at every grid sample. Default: 1 m when
    /// neither this nor --max-triangles is given.
    #[arg(
        long,
        value_name = "M",
        conflicts_with = "max_triangles",
        allow_negative_numbers = true
    )]
    pub max_error: Option<f64>,
    /// At most this many triangles, with the smallest error that allows.
    #[arg(long, value_name = "N")]
    pub max_triangles: Option<usize>,
    /// Output mesh: .obj, .ply, .stl or .glb (written atomically). Without it only
    /// the report is printed.
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Output coordinates.
    #[arg(long, value_enum, default_value_t = CoordsArg::Local)]
    pub coords: CoordsArg,
    /// STL only: close the surface into a solid with walls down to a flat base at
    /// this height in metres (for 3D printing).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub base_m: Option<f64>,
    /// Void policy.
    #[arg(long, value_enum, default_value_t = Voids::Fill)]
    pub voids: Voids,
    /// Run the invariant checker on the mesh (coverage, conformity, heights, bound).
    #[arg(long)]
    pub check: bool,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}
