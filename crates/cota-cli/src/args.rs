//! Command-line flags, turned into library option structs and nothing more.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};
use cota_core::compare::Tolerance;
use cota_core::quadtree::QuadOptions;
use cota_core::{CriterionKind, Crs, Mode};

/// cota: terrain level of detail with guaranteed error, from real DEMs.
#[derive(Debug, Parser)]
#[command(name = "cota", version, about, propagate_version = true)]
pub struct Cli {
    /// Show no progress and no text report: only warnings and errors (and
    /// the report when asked for with --json; `cota info` still describes).
    /// Progress is drawn only when stderr is a terminal.
    #[arg(long, global = true)]
    pub quiet: bool,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Describe DEM files: format, size, CRS, cell size, height range, voids, seams.
    Info(InfoArgs),
    /// Build a mesh with a guaranteed maximum error, or within a triangle budget.
    Mesh(Box<MeshArgs>),
    /// Regenerate paper 000's Table 1 and Table 2: bitree vs restricted quadtree.
    Compare(CompareArgs),
    /// Paper 004: the best (mesh, texture) pair under a byte budget, as a textured GLB.
    Pair(PairArgs),
    /// Progressive compact stream (paper 000): encode a DEM, decode any prefix.
    #[command(subcommand)]
    Stream(StreamCommand),
    /// Cesium quantized-mesh-1.0 tile pyramid: error bound per zoom, no seams.
    Tiles(TilesArgs),
    /// Serve the terrain over HTTP: browser viewer, CesiumJS page, stream, tiles.
    Serve(ServeArgs),
}

/// The help heading of the reading flags.
const READING: &str = "Reading DEMs";

/// The input files and how to read and combine them.
#[derive(Debug, Clone, Args)]
pub struct InputArgs {
    /// DEM files: SRTM .hgt/.hgt.zip, GeoTIFF, PNG or WebP terrain tiles
    /// (placed by Web-Mercator bounds when named z/x/y.ext), PMTiles archives
    /// (with --input-zoom and --bbox), NumPy .npy/.npz, USGS .dem, ESRI .asc.
    /// Several adjacent tiles are mosaicked. With none, the bundled sample
    /// S29W072.hgt.zip is used. `-` reads one DEM from standard input (its
    /// format detected from the content; a raw .hgt by its size), within
    /// --max-samples.
    #[arg(value_name = "FILE")]
    pub files: Vec<PathBuf>,
    #[command(flatten)]
    pub read: ReadArgs,
}

/// How to read DEMs, combine them and keep a window of them: the one set
/// of reading flags every command that reads DEMs takes (`info`, `mesh`,
/// `compare`, `pair`, `stream encode`, `tiles`, `serve`).
#[derive(Debug, Clone, Args)]
pub struct ReadArgs {
    /// PNG height encoding. Default: terrain-rgb for colour PNGs, gray16 for grayscale.
    #[arg(long, value_enum)]
    #[arg(help_heading = READING)]
    pub encoding: Option<Encoding>,
    /// Metres per gray level for --encoding gray16.
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "M",
        allow_negative_numbers = true
    )]
    #[arg(help_heading = READING)]
    pub gray_scale_m: f64,
    /// Metres added to gray levels for --encoding gray16.
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "M",
        allow_negative_numbers = true
    )]
    #[arg(help_heading = READING)]
    pub gray_offset_m: f64,
    /// Cell size in metres for inputs without georeference (PNG).
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "M",
        allow_negative_numbers = true
    )]
    #[arg(help_heading = READING)]
    pub cell_size_m: f64,
    /// Band to read from a multi-band raster (1-based).
    #[arg(long, value_name = "N")]
    #[arg(help_heading = READING)]
    pub band: Option<u16>,
    /// The array to read from a NumPy .npz (default: the only 2-D array, or
    /// one named elevation, dem, z, height or heights).
    #[arg(long, value_name = "NAME")]
    #[arg(help_heading = READING)]
    pub array: Option<String>,
    /// PMTiles archives: the zoom level of the tiles to read (with --bbox).
    /// `--zoom` is its former name, still accepted with a warning.
    #[arg(
        long = "input-zoom",
        alias = "zoom",
        value_name = "Z",
        requires = "bbox"
    )]
    #[arg(help_heading = READING)]
    pub zoom: Option<u8>,
    /// The box to read (west, south, east, north). PMTiles archives (with
    /// --input-zoom): in degrees, every tile of that zoom touching it is read and
    /// mosaicked. Other inputs: only the samples whose centres lie in it are
    /// kept (after mosaicking), in the input's CRS units: degrees of
    /// longitude and latitude for SRTM and geographic rasters, the
    /// projection's units (metres) for projected ones.
    #[arg(
        long,
        value_name = "W,S,E,N",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    #[arg(help_heading = READING)]
    pub bbox: Option<Vec<f64>>,
    /// Keep only a window of the input (after mosaicking, before the void
    /// fill): first column, first row (row 0 is the northern row), width,
    /// height, in samples.
    #[arg(long, value_name = "COL,ROW,W,H", value_parser = parse_crop, allow_hyphen_values = true, conflicts_with = "bbox")]
    #[arg(help_heading = READING)]
    pub crop: Option<Crop>,
    /// Where adjacent tiles overlap and disagree: their mean, or the first file's value.
    #[arg(long, value_enum, default_value_t = Seam::Mean)]
    #[arg(help_heading = READING)]
    pub seam: Seam,
    /// Largest disagreement in metres between adjacent tiles where they
    /// overlap; above it the mosaic warns on stderr (or fails with --strict),
    /// naming the two files and the worst disagreement.
    #[arg(
        long = "seam-tolerance",
        value_name = "M",
        default_value_t = 5.0,
        allow_negative_numbers = true
    )]
    #[arg(help_heading = READING)]
    pub seam_tolerance_m: f64,
    /// Fail (exit 1) instead of warning when adjacent tiles disagree by more
    /// than --seam-tolerance.
    #[arg(long)]
    #[arg(help_heading = READING)]
    pub strict: bool,
    /// Largest grid one file may declare, in samples; larger files are refused
    /// before anything is allocated. Default: from the machine's memory (16
    /// bytes per sample, at most 2^30); a gzipped .hgt at most one 3601² tile.
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    #[arg(help_heading = READING)]
    pub max_samples: Option<u64>,
    /// Accept heights beyond ±12,000 m (refused by default: feet,
    /// centimetres or an undeclared nodata, not metres). Heights are held as
    /// f32, to within 0.49 mm up to 16,384 m and half a unit in the last
    /// place beyond (1 m at 2·10⁷ m): the report says when that exceeds a
    /// millimetre. Never beyond ±10⁹ m.
    #[arg(long)]
    pub any_height: bool,
    /// The CRS of inputs that declare none: EPSG:N (e.g. EPSG:32633) or a
    /// PROJ string ('+proj=utm +zone=33 +datum=WGS84'). For ESRI grids
    /// without a .prj, PNG/WebP/NumPy arrays, GeoTIFFs without GeoKeys, and
    /// grids whose coordinates cota only guessed to be degrees. A file that
    /// declares a different CRS is refused, naming both.
    #[arg(long, value_name = "CRS", value_parser = parse_src_crs)]
    #[arg(help_heading = READING)]
    pub src_crs: Option<Crs>,
}

impl ReadArgs {
    /// True when only a window of the input is kept (`--bbox`, `--crop`,
    /// or the tiles of `--input-zoom`).
    pub fn windowed(&self) -> bool {
        self.bbox.is_some() || self.zoom.is_some() || self.crop.is_some()
    }
}

/// `--src-crs`: EPSG:N or a PROJ string, checked (`cota_io::crs::parse_crs`).
fn parse_src_crs(text: &str) -> Result<Crs, String> {
    cota_io::crs::parse_crs(text).map_err(|e| e.to_string())
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

/// The tile format of `cota tiles`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TileFormatArg {
    /// Cesium quantized-mesh-1.0: OUT/layer.json and OUT/{z}/{x}/{y}.terrain.
    QuantizedMesh,
    /// 3D Tiles 1.1 terrain (CesiumJS's Cesium3DTilesTerrainProvider,
    /// 3DTilesRendererJS): OUT/tileset.json, subtrees and
    /// OUT/{root}/{z}/{x}/{y}.glb.
    #[value(name = "3dtiles")]
    Tiles3d,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Voids {
    /// Fill voids harmonically from their border (continuous surface).
    Fill,
    /// Fill voids by inverse distance from their border.
    Idw,
    /// Refuse inputs with voids.
    Refuse,
    /// Leave voids out: no triangle touches a void, so the mesh has holes
    /// where the data has (`cota mesh` only; conforming bitree meshes).
    Hole,
}

#[derive(Debug, Args)]
pub struct InfoArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Print one JSON object instead of text (with --each, an array of them).
    #[arg(long)]
    pub json: bool,
    /// Describe each file on its own (unrelated files), instead of
    /// mosaicking them into one region.
    #[arg(long)]
    pub each: bool,
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
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub max_triangles: Option<usize>,
    /// Output mesh: .obj, .ply, .stl or .glb (written atomically). Without it only
    /// the report is printed. `-` writes to standard output (with --format;
    /// no atomic rename there: a failure part-way leaves a partial stream;
    /// binary formats are refused on a terminal), and the report goes to
    /// stderr.
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// The output format, for `-o -` (standard output); with a file name it
    /// must agree with the extension.
    #[arg(long, value_enum)]
    pub format: Option<MeshFormatArg>,
    #[command(flatten)]
    pub force: ForceArgs,
    /// Output coordinates.
    #[arg(long, value_enum, default_value_t = CoordsArg::Local)]
    pub coords: CoordsArg,
    /// Vertical exaggeration: the heights written (and --base-m) are
    /// multiplied by F; the report's errors stay in true metres. Not with
    /// --quantize.
    #[arg(
        long,
        value_name = "F",
        default_value_t = 1.0,
        allow_negative_numbers = true
    )]
    pub z_scale: f64,
    /// STL only: close the surface into a solid with walls down to a flat base at
    /// this height in metres (for 3D printing).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub base_m: Option<f64>,
    /// STL only: close the surface into a solid whose flat base lies MM
    /// millimetres of the model below its lowest point, whatever the
    /// terrain's heights (a coast at 0 m, a basin below sea level). Needs a
    /// print scale (--scale or --size-mm).
    #[arg(
        long,
        value_name = "MM",
        allow_negative_numbers = true,
        conflicts_with = "base_m"
    )]
    pub base_mm: Option<f64>,
    /// STL only: print scale, model length to true length, as 1:N or a
    /// factor (1:100000 = 0.00001: 1 km becomes 10 mm). The STL is then in
    /// millimetres, heights (times --z-scale, from 0 m) at the same scale.
    /// Needs --coords local.
    #[arg(long, value_name = "1:N", value_parser = parse_scale, conflicts_with = "size_mm")]
    pub scale: Option<f64>,
    /// STL only: print size: the longer horizontal side of the model in
    /// millimetres; the other side and the heights (times --z-scale, from
    /// 0 m) at the same scale. The STL is then in millimetres. Needs
    /// --coords local.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    pub size_mm: Option<f64>,
    /// Void policy.
    #[arg(long, value_enum, default_value_t = Voids::Fill)]
    pub voids: Voids,
    /// Run the invariant checker on the mesh (coverage, conformity, heights, bound).
    #[arg(long)]
    pub check: bool,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// The mesh: the bitree's (right triangles of a hierarchy), or a TIN:
    /// irregular triangles, fewer of them for the same guaranteed error
    /// (decimated from the bitree's mesh; --max-error or --max-triangles,
    /// --mode conforming, --criterion max-error, no --strip).
    #[arg(long, value_enum, default_value_t = MeshKindArg::Bitree)]
    pub mesh: MeshKindArg,
    /// With --mesh tin: mesh the border from the border samples alone (each
    /// side simplified within the bound on its own), so that tiles sharing a
    /// side and meshed at the same bound share their vertices there exactly.
    #[arg(long)]
    pub lock_border: bool,
    /// A grid whose width or height minus one is odd (web tiles: 256, 512):
    /// `extend` meshes it on its grid extended by repeating the last row and
    /// column up to the hierarchy's 2^k+1 square, then clips the mesh back to
    /// the real samples (a border as coarse as a 2^k+1 grid's; bitree,
    /// conforming, --max-error only); `keep` meshes the grid's own hierarchy
    /// (a border at unit resolution).
    #[arg(long, value_enum, default_value_t = OddSpansArg::Extend)]
    pub odd_spans: OddSpansArg,
    /// The hierarchy: the bitree, or the restricted quadtree baseline (Pajarola
    /// 1998; --criterion max-error with --mode conforming only, no budget).
    #[arg(long, value_enum, default_value_t = HierarchyArg::Bitree)]
    pub hierarchy: HierarchyArg,
    /// Quadtree leaves (with --hierarchy quadtree): fans around their centre,
    /// or also 2 halves without the centre where the bound allows.
    #[arg(long, value_enum, default_value_t = QuadVariant::Templates)]
    pub quadtree_leaves: QuadVariant,
    /// Write the .glb as one triangle strip (mode 5) made from the bitree
    /// (papers 000, 001), and report its references.
    #[arg(long)]
    pub strip: bool,
    /// How the strip is made [default with --strip: cells]. cells: long
    /// rows of 1x1 cells re-triangulated (diagonal flipped, the same error at
    /// every sample) and stripped row by row, the rest guided; the fewest
    /// references, the mesh written is then the re-triangulated one.
    /// guided: greedy growth along the bitree traversal, mesh unchanged.
    /// traversal: the papers' strip, the leaves in traversal order. Without
    /// --strip, only reports the strip's references (strip_refs).
    #[arg(long, value_enum)]
    pub strip_method: Option<StripMethodArg>,
    /// .glb only: quantized attributes (KHR_mesh_quantization): 16-bit
    /// positions (columns and rows exact, heights on a power-of-two step),
    /// 8-bit normals, 16-bit indices; about half the size. Heights move by at
    /// most half the step: the report measures the mesh as written and its
    /// bound is the requested one plus half the step (--check proves that).
    #[arg(long)]
    pub quantize: bool,
    #[command(flatten)]
    pub refine: RefineArgs,
    #[command(flatten)]
    pub texture: TextureArgs,
}

/// `--force`, shared by every command that writes files.
#[derive(Debug, Clone, Copy, Args)]
pub struct ForceArgs {
    /// Replace an output file even when it is read-only (refused otherwise).
    /// A symbolic link is written through: its target is replaced, the link
    /// kept.
    #[arg(long)]
    pub force: bool,
}

/// A mesh file format (`--format`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MeshFormatArg {
    /// Wavefront OBJ (text).
    Obj,
    /// Binary PLY.
    Ply,
    /// Binary STL.
    Stl,
    /// Binary glTF.
    Glb,
}

impl MeshFormatArg {
    /// The library's format.
    pub fn format(self) -> cota_io::export::MeshFormat {
        use cota_io::export::MeshFormat;
        match self {
            MeshFormatArg::Obj => MeshFormat::Obj,
            MeshFormatArg::Ply => MeshFormat::Ply,
            MeshFormatArg::Stl => MeshFormat::Stl,
            MeshFormatArg::Glb => MeshFormat::Glb,
        }
    }
}

/// A print scale: `1:N` or a positive factor.
fn parse_scale(s: &str) -> Result<f64, String> {
    let bad = || format!("expected 1:N (e.g. 1:100000) or a positive factor, found {s:?}");
    let v = match s.split_once(':') {
        Some((a, b)) => {
            let a: f64 = a.trim().parse().map_err(|_| bad())?;
            let b: f64 = b.trim().parse().map_err(|_| bad())?;
            a / b
        }
        None => s.trim().parse().map_err(|_| bad())?,
    };
    if !(v.is_finite() && v > 0.0) {
        return Err(bad());
    }
    Ok(v)
}

/// How `cota mesh --strip` makes its strip (`cota_core::strip::StripMethod`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StripMethodArg {
    /// Rows of re-triangulated unit cells, the rest guided (`mesh --strip`'s default).
    Cells,
    /// Greedy growth guided by the bitree traversal.
    Guided,
    /// The papers' strip: leaves in traversal order.
    Traversal,
}

impl StripMethodArg {
    /// The library's method.
    pub fn method(self) -> cota_core::strip::StripMethod {
        use cota_core::strip::StripMethod;
        match self {
            StripMethodArg::Cells => StripMethod::Cells,
            StripMethodArg::Guided => StripMethod::Guided,
            StripMethodArg::Traversal => StripMethod::Traversal,
        }
    }
}

/// What `cota mesh` does with a grid whose span is odd.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum OddSpansArg {
    /// Extend the grid to its hierarchy's square and clip the mesh back.
    Extend,
    /// Mesh the grid's own hierarchy.
    Keep,
}

/// The kind of mesh `cota mesh` makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MeshKindArg {
    /// The bitree's conforming mesh (paper 000).
    Bitree,
    /// An irregular triangulation (`cota_core::tin`).
    Tin,
}

/// The hierarchy `cota mesh` uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum HierarchyArg {
    /// Right-triangle bitree (paper 000).
    Bitree,
    /// Restricted quadtree (Pajarola 1998), the baseline of `cota compare`.
    Quadtree,
}

/// Fictitious points and refinement criteria (`cota mesh`). The default,
/// `--mode conforming --criterion max-error`, uses the fast error-map path.
#[derive(Debug, Args)]
#[command(next_help_heading = "Refinement")]
pub struct RefineArgs {
    /// conforming: every vertex has its real height. fictitious: points needed
    /// only to complete the hierarchy get the height interpolated on their
    /// diagonal and are not transmitted (paper 000), without T-junctions.
    /// fictitious-faithful: the paper's variant, with hanging vertices.
    #[arg(long, value_enum, default_value_t = ModeArg::Conforming)]
    pub mode: ModeArg,
    /// What drives refinement. max-error and euclidean use --max-error (metres);
    /// curvature, light and paper003 use --tolerance; view uses --max-error-px.
    #[arg(long, value_enum, default_value_t = CriterionArg::MaxError)]
    pub criterion: CriterionArg,
    /// Tolerance of curvature and light (1/m, accumulated curvature) and of
    /// paper003 (1/m2). Default: 1e-4 of the grid's total accumulated
    /// curvature (paper003: divided by the terrain's diagonal in metres).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub tolerance: Option<f64>,
    /// Observer position in metres, local frame (x east, y north, z up, origin
    /// at the south-west sample). Required by view, paper001 and paper003.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub observer: Option<[f64; 3]>,
    /// View direction (view) or direction of motion (paper003).
    #[arg(long, value_name = "DX,DY,DZ", value_parser = parse_direction, allow_hyphen_values = true, default_value = "0,1,0")]
    pub look: [f64; 3],
    /// Vertical field of view in degrees (view).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 60.0,
        allow_negative_numbers = true
    )]
    pub fov_deg: f64,
    /// Viewport height in pixels (view).
    #[arg(
        long,
        value_name = "PX",
        default_value_t = 1080.0,
        allow_negative_numbers = true
    )]
    pub viewport_px: f64,
    /// Largest projected vertical error in pixels (view).
    #[arg(
        long,
        value_name = "PX",
        default_value_t = 1.0,
        allow_negative_numbers = true
    )]
    pub max_error_px: f64,
    /// Direction towards the light (light).
    #[arg(long, value_name = "DX,DY,DZ", value_parser = parse_direction, allow_hyphen_values = true, default_value = "1,1,1")]
    pub light: [f64; 3],
    /// Weight of pure curvature in [0, 1] (light): accept when K·(alpha + (1 − alpha)·I) <= T.
    #[arg(
        long,
        value_name = "A",
        default_value_t = 0.5,
        allow_negative_numbers = true
    )]
    pub alpha: f64,
    /// Size factor: fraction of the terrain's diagonal (size, paper001).
    #[arg(
        long,
        value_name = "F",
        default_value_t = 0.01,
        allow_negative_numbers = true
    )]
    pub size_factor: f64,
    /// Distance factor: fraction of the largest distance (paper001).
    #[arg(
        long,
        value_name = "F",
        default_value_t = 0.8,
        allow_negative_numbers = true
    )]
    pub distance_factor: f64,
    /// Curvature factor: fraction of the grid's accumulated curvature (paper001).
    #[arg(
        long,
        value_name = "F",
        default_value_t = 0.2,
        allow_negative_numbers = true
    )]
    pub curvature_factor: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModeArg {
    /// Every vertex carries its sample's height (no fictitious points).
    Conforming,
    /// Fictitious points, watertight: no T-junction, same surface.
    Fictitious,
    /// Fictitious points as in paper 000: hanging vertices (line triangles).
    FictitiousFaithful,
}

impl ModeArg {
    /// The library's mode.
    pub fn mode(self) -> Mode {
        match self {
            ModeArg::Conforming => Mode::Conforming,
            ModeArg::Fictitious => Mode::Fictitious { watertight: true },
            ModeArg::FictitiousFaithful => Mode::Fictitious { watertight: false },
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CriterionArg {
    /// Exact vertical error <= --max-error at every sample.
    MaxError,
    /// 3D distance of the samples to the triangle's plane <= --max-error (paper 000).
    Euclidean,
    /// Accumulated curvature <= --tolerance (papers 002-004).
    Curvature,
    /// Longest edge <= --size-factor x terrain diagonal (paper 001).
    Size,
    /// Curvature masked by illumination (paper 002): --light, --alpha, --tolerance.
    Light,
    /// Screen-space error <= --max-error-px from --observer looking --look.
    View,
    /// Near AND large AND curved (paper 001): --observer and the factors.
    Paper001,
    /// Curvature x cos(theta) / distance <= --tolerance (paper 003): --observer, --look.
    Paper003,
}

impl CriterionArg {
    /// The library's criterion.
    pub fn kind(self) -> CriterionKind {
        match self {
            CriterionArg::MaxError => CriterionKind::MaxError,
            CriterionArg::Euclidean => CriterionKind::Euclidean,
            CriterionArg::Curvature => CriterionKind::Curvature,
            CriterionArg::Size => CriterionKind::Size,
            CriterionArg::Light => CriterionKind::Light,
            CriterionArg::View => CriterionKind::View,
            CriterionArg::Paper001 => CriterionKind::Paper001,
            CriterionArg::Paper003 => CriterionKind::Paper003,
        }
    }
}

/// Parses `X,Y,Z`.
fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("expected three numbers X,Y,Z, found {s:?} ({e})"))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
        _ => Err(format!("expected three finite numbers X,Y,Z, found {s:?}")),
    }
}

/// A direction: three finite numbers, not all zero.
fn parse_direction(s: &str) -> Result<[f64; 3], String> {
    let v = parse_vec3(s)?;
    if v.iter().all(|c| *c == 0.0) {
        return Err(format!(
            "expected a direction DX,DY,DZ (not all zero), found {s:?}"
        ));
    }
    Ok(v)
}

/// A bitree mode compared by `cota compare`.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum BitreeMode {
    /// The conforming extraction of `cota mesh` (every vertex real).
    Conforming,
    /// Fictitious points, no T-junction.
    Fictitious,
    /// Fictitious points as in paper 000 (hanging vertices).
    Faithful,
}

impl BitreeMode {
    /// The library's mode.
    pub fn mode(self) -> Mode {
        match self {
            BitreeMode::Conforming => Mode::Conforming,
            BitreeMode::Fictitious => Mode::Fictitious { watertight: true },
            BitreeMode::Faithful => Mode::Fictitious { watertight: false },
        }
    }
}

/// A restricted-quadtree variant compared by `cota compare`.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum QuadVariant {
    /// Every leaf is a fan around its centre (the 16 templates, papers 002-004).
    Templates,
    /// Leaves without finer neighbours may be 2 triangles without their centre
    /// (Pajarola 1998's unselected block centres).
    CentreWhenNeeded,
}

impl QuadVariant {
    /// The library's options.
    pub fn options(self) -> QuadOptions {
        QuadOptions::DEFAULT.with_centre_when_needed(matches!(self, QuadVariant::CentreWhenNeeded))
    }
}

/// A window of a grid: first column, first row, width, height (samples).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crop {
    pub col: usize,
    pub row: usize,
    pub width: usize,
    pub height: usize,
}

fn parse_crop(s: &str) -> Result<Crop, String> {
    let v: Vec<usize> = s
        .split(',')
        .map(|p| p.trim().parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("expected COL,ROW,W,H as four whole numbers, found {s:?} ({e})"))?;
    match v[..] {
        [col, row, width, height] => Ok(Crop {
            col,
            row,
            width,
            height,
        }),
        _ => Err(format!(
            "expected COL,ROW,W,H as four whole numbers, found {s:?}"
        )),
    }
}

/// A tolerance of `cota compare`: metres (`5`, `5m`) or a percentage of the
/// height range (`5%`), 0 or more.
fn parse_tolerance(s: &str) -> Result<Tolerance, String> {
    let t = s.trim();
    let bad = || {
        format!(
            "expected metres (5) or a percentage of the height range (5%), 0 or more, found {s:?}"
        )
    };
    let (number, make): (&str, fn(f64) -> Tolerance) = match t.strip_suffix('%') {
        Some(p) => (p, Tolerance::PercentOfRange),
        None => (t.strip_suffix('m').unwrap_or(t), Tolerance::Metres),
    };
    let v: f64 = number.trim().parse().map_err(|_| bad())?;
    if !(v.is_finite() && v >= 0.0) {
        return Err(bad());
    }
    Ok(make(v))
}

#[derive(Debug, Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Error tolerances: plain numbers are metres, a number with a `%`
    /// suffix is a percentage of the grid's height range (paper 000's Table
    /// 1); lists may mix them (`0%,1%,5,20`). Each row of the report says
    /// which. Before issue 33 plain numbers were percentages: write `7%`
    /// for the former `7`.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0%,1%,2%,7%,10%,14%,50%",
        value_name = "M|PCT%",
        value_parser = parse_tolerance,
        allow_hyphen_values = true
    )]
    pub tolerances: Vec<Tolerance>,
    /// Bitree modes to compare with the quadtree.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "conforming,fictitious,faithful"
    )]
    pub modes: Vec<BitreeMode>,
    /// Restricted-quadtree variants to compare.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "templates,centre-when-needed"
    )]
    pub quadtree: Vec<QuadVariant>,
    /// Void policy.
    #[arg(long, value_enum, default_value_t = Voids::Fill)]
    pub voids: Voids,
    /// Run the invariant checker on every mesh.
    #[arg(long)]
    pub check: bool,
    /// How the bitree strips are made. guided (default) strips the meshes
    /// as compared; cells re-triangulates unit cells of the bitree meshes
    /// (fewer references, but the quadtree's are not), traversal is the
    /// papers' strip.
    #[arg(long, value_enum, default_value_t = StripMethodArg::Guided)]
    pub strip_method: StripMethodArg,
    /// Print one JSON object instead of tables.
    #[arg(long)]
    pub json: bool,
}

/// `cota stream encode` / `cota stream decode`.
#[derive(Debug, Subcommand)]
pub enum StreamCommand {
    /// Encode DEM files as a progressive .cstream (coarse to fine, lossless by default).
    Encode(StreamEncodeArgs),
    /// Decode a .cstream, or a prefix of it, to a mesh.
    Decode(StreamDecodeArgs),
}

#[derive(Debug, Args)]
pub struct StreamEncodeArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output stream file (written atomically).
    #[arg(short, long, value_name = "OUT.cstream")]
    pub output: std::path::PathBuf,
    #[command(flatten)]
    pub force: ForceArgs,
    /// Error of the last step in metres (0: the lossless E = 0 mesh).
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub max_error: f64,
    /// Height quantum in metres; heights are sent as multiples of it (lossless
    /// when the data sit on that lattice: 1 for SRTM, 0.1 for decimetre floats).
    #[arg(long, value_name = "Q", default_value_t = 1.0)]
    pub quantum_m: f64,
    /// Void policy.
    #[arg(long, value_enum, default_value_t = Voids::Fill)]
    pub voids: Voids,
    /// progressive: coarse-to-fine steps of decreasing error over the bitree's
    /// error map, down to --max-error. conforming, fictitious,
    /// fictitious-faithful: coarse-to-fine steps of the refinement of `cota
    /// mesh --mode M` at decreasing tolerances, down to --max-error;
    /// fictitious points are never sent.
    #[arg(long, value_enum, default_value_t = StreamModeArg::Progressive)]
    pub mode: StreamModeArg,
    /// Step tolerances in metres, decreasing, each above --max-error (e.g.
    /// 64,16,4); the last step is always --max-error. Default: powers of two
    /// from the coarse mesh's error down to the quantum.
    #[arg(long, value_name = "M,M,...", value_delimiter = ',')]
    pub thresholds: Option<Vec<f64>>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// What `cota stream encode` streams.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StreamModeArg {
    /// Coarse-to-fine steps over the exact error map (every prefix a mesh).
    Progressive,
    /// Steps of the conforming refinement at decreasing tolerances.
    Conforming,
    /// Steps of the refinement with fictitious points, watertight.
    Fictitious,
    /// Steps of the refinement with fictitious points as in paper 000
    /// (hanging vertices).
    FictitiousFaithful,
}

impl StreamModeArg {
    /// The refinement mode streamed, `None` for the error-map steps.
    pub fn mode(self) -> Option<Mode> {
        match self {
            StreamModeArg::Progressive => None,
            StreamModeArg::Conforming => Some(Mode::Conforming),
            StreamModeArg::Fictitious => Some(Mode::Fictitious { watertight: true }),
            StreamModeArg::FictitiousFaithful => Some(Mode::Fictitious { watertight: false }),
        }
    }

    /// The name reported: `progressive` or the mode's.
    pub fn name(self) -> &'static str {
        self.mode().map_or("progressive", |m| m.name())
    }
}

#[derive(Debug, Args)]
pub struct StreamDecodeArgs {
    /// The stream to decode; `-` reads standard input (frame by frame: bytes
    /// past --max-bytes or --max-error are read and dropped, never held).
    #[arg(value_name = "IN.cstream")]
    pub input: std::path::PathBuf,
    /// Use only the steps that fit in the first N bytes of the file.
    #[arg(long, value_name = "N", conflicts_with = "max_error")]
    pub max_bytes: Option<u64>,
    /// Largest grid the stream's head may announce, in samples; a larger one
    /// is refused before anything is allocated. Default: from the machine's
    /// memory (16 bytes per sample, at most 2^30).
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub max_samples: Option<u64>,
    /// Stop at the first step whose stated max error is at most M metres.
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub max_error: Option<f64>,
    /// Refuse a cut stream (a partial download). Without it, the complete
    /// steps of a cut stream are decoded and a warning says what is missing.
    #[arg(long)]
    pub strict: bool,
    /// Output mesh: .obj, .ply, .stl or .glb (written atomically). Without it
    /// only the report is printed. `-` writes to standard output (with
    /// --format; not atomic; binary formats refused on a terminal), and the
    /// report goes to stderr.
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<std::path::PathBuf>,
    /// The output format, for `-o -` (standard output); with a file name it
    /// must agree with the extension.
    #[arg(long, value_enum)]
    pub format: Option<MeshFormatArg>,
    #[command(flatten)]
    pub force: ForceArgs,
    /// Output coordinates.
    #[arg(long, value_enum, default_value_t = CoordsArg::Local)]
    pub coords: CoordsArg,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The image options shared by `cota pair` and `cota mesh --texture`.
#[derive(Debug, Args)]
pub struct ImageArgs {
    /// Bands of the image as R,G,B (1-based), e.g. 3,2,1 for Landsat true
    /// colour, or one band as gray. Default: 1,2,3 (band 1 for 1-2 bands).
    #[arg(long, value_name = "R,G,B")]
    pub bands: Option<String>,
    /// Drape even when the CRS rule cannot tell that the image's CRS is the
    /// DEM's (cota does not reproject).
    #[arg(long)]
    pub assume_same_crs: bool,
}

/// `cota mesh --texture`.
#[derive(Debug, Args)]
#[command(next_help_heading = "Texture")]
pub struct TextureArgs {
    /// .glb only: drape this image (GeoTIFF, PNG or JPEG with a world file,
    /// or stretched over the DEM) on the mesh: TEXCOORD_0, the image
    /// resampled bilinearly onto the DEM's extent and embedded as PNG, an
    /// unlit material.
    #[arg(long, value_name = "IMAGE")]
    pub texture: Option<PathBuf>,
    #[command(flatten)]
    pub image: ImageArgs,
}

/// Which pair `cota pair` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Pick {
    /// The exact optimum over the two lists.
    Optimum,
    /// The paper's greedy scan.
    Greedy,
}

/// Which hierarchies make the mesh list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Hierarchies {
    Both,
    Bitree,
    Quadtree,
}

#[derive(Debug, Args)]
pub struct PairArgs {
    /// The DEM (any format `cota mesh` reads; voids filled harmonically);
    /// `-` reads it from standard input.
    pub dem: PathBuf,
    /// The image: GeoTIFF, or PNG/JPEG with a world file or over the DEM's extent.
    pub image: PathBuf,
    /// The whole GLB must fit in this many bytes.
    #[arg(long, value_name = "N")]
    pub budget_bytes: u64,
    /// Weight of the mesh's distortion D(M) (m2).
    #[arg(long, value_name = "A", default_value_t = 1.0)]
    pub alpha: f64,
    /// Weight of the texture's distortion D(T) (levels2).
    #[arg(long, value_name = "B", default_value_t = 1.0)]
    pub beta: f64,
    /// Only pairs whose mesh has no more triangles than the texture has
    /// leaves (paper 004's advice).
    #[arg(long)]
    pub polygons_within_texels: bool,
    /// Write the optimum pair, or the paper's greedy choice.
    #[arg(long, value_enum, default_value_t = Pick::Optimum)]
    pub pick: Pick,
    /// Hierarchies of the mesh list.
    #[arg(long, value_enum, default_value_t = Hierarchies::Both)]
    pub hierarchies: Hierarchies,
    /// Vertical bounds of the mesh list, metres. Default: the height range
    /// halved 1 to 10 times, and 0.
    #[arg(long, value_name = "M,...", value_delimiter = ',')]
    pub mesh_tolerances_m: Option<Vec<f64>>,
    /// Tolerances of the texture list: sigma_R + sigma_G + sigma_B, levels.
    #[arg(
        long,
        value_name = "T,...",
        value_delimiter = ',',
        default_value = "0,2,4,8,12,16,24,32,48,64,96,128"
    )]
    pub texture_tolerances: Vec<f64>,
    /// Output .glb (written atomically). Without it, only the report.
    #[arg(short, long, value_name = "OUT.glb")]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub force: ForceArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub image_args: ImageArgs,
    #[command(flatten)]
    pub read: ReadArgs,
}

/// Flags of `cota tiles`.
#[derive(Debug, Args)]
pub struct TilesArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output directory: OUT/layer.json and OUT/{z}/{x}/{y}.terrain; or, for
    /// a name ending in .mbtiles, one MBTiles archive of the same tiles
    /// (built as OUT.partial, renamed when complete). With --format 3dtiles,
    /// a name ending in .3tz (or .3dtiles.zip) is one 3D Tiles Archive: the
    /// pyramid made in OUT.parts (resumed from there), packed into
    /// OUT.partial, renamed when complete.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Tile format: quantized-mesh, or 3dtiles (GLB tiles with
    /// CESIUM_tile_edges, implicit tiling, float32 positions unless
    /// --meshopt; a directory or a .3tz archive, from zoom 0).
    #[arg(long, value_enum, default_value_t = TileFormatArg::QuantizedMesh,
        conflicts_with_all = ["gzip", "watermask", "metadata", "imagery", "plan", "shard", "reduce"])]
    pub format: TileFormatArg,
    /// Coarsest zoom written (0: the two root tiles).
    #[arg(long, default_value_t = 0, value_name = "A")]
    pub min_zoom: u8,
    /// Finest zoom. Default: the zoom whose lattice is as fine as the source.
    #[arg(long, value_name = "B")]
    pub max_zoom: Option<u8>,
    /// cesium-terrain-builder's error per zoom times Q: 6378137·2π·0.25·Q/(65·2)/2^z metres.
    #[arg(long, value_name = "Q", conflicts_with = "max_error_m_at_max_zoom")]
    pub error_factor: Option<f64>,
    /// The error bound at the finest zoom in metres, doubled at each zoom above.
    #[arg(long, value_name = "E")]
    pub max_error_m_at_max_zoom: Option<f64>,
    /// Lattice cells across a tile at the finest zoom (a power of two).
    #[arg(long, default_value_t = 64, value_name = "S")]
    pub tile_cells: u32,
    /// Write oct-encoded vertex normals (extension 1).
    #[arg(long)]
    pub normals: bool,
    /// Write a water mask, water at or below 0 m (extension 2).
    #[arg(long)]
    pub watermask: bool,
    /// Write metadata: child availability and the geometric error (extension 4).
    #[arg(long)]
    pub metadata: bool,
    /// Gzip every tile (serve with Content-Encoding: gzip).
    #[arg(long)]
    pub gzip: bool,
    /// With --format 3dtiles: u16 positions over each tile's box
    /// (KHR_mesh_quantization) and positions, indices and edges compressed
    /// with EXT_meshopt_compression (both required extensions; CesiumJS
    /// reads them). Default: off (float32 positions, plain indices).
    #[arg(long)]
    pub meshopt: bool,
    /// With --format 3dtiles: no skirts. By default each GLB carries a
    /// second primitive, a skirt hanging below the tile's edges, that closes
    /// the cracks between tiles of different levels in 3D Tiles clients that
    /// build no skirts (3DTilesRendererJS, loaders.gl); CesiumJS reads only
    /// the first primitive and builds its own from CESIUM_tile_edges, so a
    /// pyramid for CesiumJS alone can leave them out (fewer bytes).
    #[arg(long)]
    pub no_skirts: bool,
    /// Also write shaded-relief imagery beside the terrain: PNG tiles
    /// OUT/imagery/{z}/{x}/{y}.png (hillshade over a hypsometric tint, the
    /// same geographic tiling and TMS rows) and OUT/imagery/imagery.json,
    /// as `cota serve` sends them at /imagery/. Whole-input runs only.
    #[arg(long, conflicts_with_all = ["plan", "shard", "reduce"])]
    pub imagery: bool,
    /// Redo tiles already in OUT, and replace read-only files there
    /// (refused otherwise).
    #[arg(long)]
    pub force: bool,
    /// Decode every tile again and check it (bound at every lattice sample,
    /// conformity, edge lists) before writing it.
    #[arg(long)]
    pub check: bool,
    /// What to do with voids.
    #[arg(long, value_enum, default_value_t = Voids::Fill)]
    pub voids: Voids,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// The plan step of --shards N shards: reads the input one shard's part at
    /// a time (the whole input where shards must read every file), writes
    /// OUT/.cota-shards-N.json (what the shards need of the whole) and the band
    /// corners, and prints each shard's tiles, zoom by zoom. Shards run after
    /// it read only their files and hold only their part. Parts already done
    /// by --plan --part I are not read again.
    #[arg(long, conflicts_with_all = ["shard", "reduce"])]
    pub plan: bool,
    /// With --plan: only part I of the plan step (0-based, I < N; shard I's
    /// part read for the statistics and band corners) into
    /// OUT/.cota-plan-I-of-N.bin, after the layout (OUT/.cota-layout-N.json,
    /// made when missing). Idempotent; the parts run as separate processes, then
    /// --plan --shards N merges them.
    #[arg(long, value_name = "I", requires = "plan", conflicts_with = "layout")]
    pub part: Option<u32>,
    /// With --plan: only the plan step's layout (each file read alone for its
    /// shape), OUT/.cota-layout-N.json, before running the --part I processes.
    #[arg(long, requires = "plan")]
    pub layout: bool,
    /// Number of shards for --plan and --reduce.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub shards: u32,
    /// Write only shard I of N (0-based) and its record OUT/.cota-shard-I-of-N.json;
    /// idempotent. After the plan step (--plan) only its part of the input and
    /// lattice; without it the whole. Then --reduce --shards N writes layer.json.
    #[arg(long, value_name = "I/N", value_parser = parse_shard, conflicts_with = "reduce")]
    pub shard: Option<(u32, u32)>,
    /// Check the records of --shards N shards in OUT, write layer.json, remove
    /// the records (reads no input: the shards recorded it).
    #[arg(long)]
    pub reduce: bool,
    /// Make the pyramid even when its estimate (printed before the work
    /// starts) is past 1,000,000 tiles or more memory than the machine has
    /// available; refused without it.
    #[arg(long)]
    pub yes: bool,
}

#[derive(Debug, Args)]
pub struct ServeArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// A tile directory written by `cota tiles` (layer.json and
    /// {z}/{x}/{y}.terrain), or an .mbtiles archive it wrote, served at
    /// /tiles/. Without it, tiles are made on demand from the input and
    /// kept. A 3D Tiles pyramid (`--format 3dtiles`: a directory with
    /// tileset.json, or a .3tz archive) is served at /3dtiles/ instead, the
    /// CesiumJS page showing it at /cesium?3dtiles; quantized-mesh tiles
    /// are then made on demand.
    #[arg(long, value_name = "DIR")]
    pub tiles: Option<PathBuf>,
    /// Address and port to listen on: an IP address (`127.0.0.1:8080`,
    /// `[::1]:8080`, `0.0.0.0:8080`) or a host name (`localhost:8080`:
    /// every address it resolves to, IPv4 and IPv6). Port 0: any free port.
    #[arg(long, default_value = "127.0.0.1:8080", value_name = "HOST:PORT")]
    pub addr: String,
    /// What to do with voids (no data) before encoding.
    #[arg(long, value_enum, default_value_t = Voids::Fill)]
    pub voids: Voids,
    /// Memory for tiles kept after they are sent (terrain and imagery,
    /// least recently used dropped first), MiB.
    #[arg(long, default_value_t = 256, value_name = "MIB")]
    pub cache_mib: usize,
    /// Threads that make tiles. Default: the machine's cores, at most 8.
    #[arg(long, value_name = "N")]
    pub workers: Option<usize>,
    /// Tiles that may wait for a worker; past them requests get 503 with
    /// Retry-After.
    #[arg(long, default_value_t = 64, value_name = "N")]
    pub queue: usize,
    /// Connections open at once; one more is answered 503 and closed.
    #[arg(long, default_value_t = 512, value_name = "N")]
    pub max_connections: usize,
    /// Seconds a client has to send a request's headers (and the most a
    /// kept-alive connection may stay idle).
    #[arg(long, default_value_t = 10, value_name = "S")]
    pub header_timeout_s: u64,
    /// Seconds the server takes at most to answer one request (then 503).
    #[arg(long, default_value_t = 30, value_name = "S")]
    pub request_timeout_s: u64,
    #[command(flatten)]
    pub texture: ServeTextureArgs,
}

/// `cota serve --texture`.
#[derive(Debug, Args)]
#[command(next_help_heading = "Texture")]
pub struct ServeTextureArgs {
    /// Drape this image on the terrain in the viewer (GeoTIFF, or PNG/JPEG
    /// with a world file or stretched over the DEM; in the DEM's CRS):
    /// resampled at start onto the DEM's extent and served at
    /// /texture.png. T in the viewer switches between it and the height
    /// colours.
    #[arg(long, value_name = "IMAGE")]
    pub texture: Option<PathBuf>,
    #[command(flatten)]
    pub image: ImageArgs,
    /// Largest side of the served texture, texels (the image's own
    /// resolution over the DEM when that is less).
    #[arg(long, default_value_t = 4096, value_name = "TEXELS")]
    pub texture_max_side: usize,
    /// Also choose paper 004's (mesh, texture) pair within this many bytes
    /// of textured GLB, as `cota pair --budget-bytes` does, and serve its
    /// texture level at /texture-pair.png (the viewer shows it and the
    /// chosen mesh's figures).
    #[arg(long, value_name = "N")]
    pub pair_budget_bytes: Option<u64>,
}

/// `I/N` with `I < N`.
fn parse_shard(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected I/N with 0 <= I < N (e.g. 0/4), found {s:?}");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (u32, u32) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if i >= n {
        return Err(bad());
    }
    Ok((i, n))
}
