//! Output coordinates and the georeference metadata written beside them.
//!
//! [`Frame`] turns a mesh vertex (column, row, metres) into the output frame
//! chosen by [`Coords`]:
//! * [`Coords::LocalMetres`]: `x = col·dx`, `y = (H−1−row)·dy`, `z = z_m`, x east,
//!   y north, z up, origin at the grid's south-west sample, `[dx, dy]` =
//!   [`HeightGrid::cell_size_m`]. For geographic grids that is the conversion of
//!   degrees to metres at the grid's centre latitude, applied to the whole grid:
//!   a local tangent-plane approximation, good to a fraction of a percent over a
//!   1° tile (the east–west scale varies with cos(latitude) across the tile).
//! * [`Coords::Grid`]: `x = col`, `y = row`, `z = z_m`. Here y points south, the
//!   frame is mirrored, and [`Frame::orient`] reverses each triangle so normals
//!   still point up by the right-hand rule.
//!
//! [`GeoInfo`] gathers what places the output on the Earth (CRS, the affine
//! from samples to CRS coordinates, the CRS coordinates of the south-west
//! sample, the cell size in metres, the coordinate mode) for the writers to
//! store as comments (OBJ, PLY), header text (STL) or `asset.extras` (glTF).

use cota_core::{HeightGrid, MeshVertex, PixelIs};

use super::options::Coords;

/// The map from grid samples to output coordinates.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Frame {
    coords: Coords,
    dx: f64,
    dy: f64,
    last_row: f64,
}

impl Frame {
    /// The frame for `grid` in mode `coords`.
    pub(crate) fn new(grid: &HeightGrid, coords: Coords) -> Self {
        let [dx, dy] = grid.cell_size_m();
        Frame {
            coords,
            dx,
            dy,
            last_row: grid.height() as f64 - 1.0,
        }
    }

    /// Output position of the (possibly fractional) grid point (`col`, `row`) at height `z_m`.
    #[inline]
    pub(crate) fn point(&self, col: f64, row: f64, z_m: f64) -> [f64; 3] {
        match self.coords {
            Coords::LocalMetres => [col * self.dx, (self.last_row - row) * self.dy, z_m],
            Coords::Grid => [col, row, z_m],
        }
    }

    /// The frame's horizontal axes as affine maps of the sample position:
    /// `x = a[0]·col + a[1]`, `y = b[0]·row + b[1]` (z is the height itself).
    pub(crate) fn axes(&self) -> ([f64; 2], [f64; 2]) {
        match self.coords {
            Coords::LocalMetres => ([self.dx, 0.0], [-self.dy, self.last_row * self.dy]),
            Coords::Grid => ([1.0, 0.0], [1.0, 0.0]),
        }
    }

    /// Output position of a mesh vertex.
    #[inline]
    pub(crate) fn vertex(&self, v: &MeshVertex) -> [f64; 3] {
        self.point(f64::from(v.col), f64::from(v.row), f64::from(v.z_m))
    }

    /// True when the frame is mirrored relative to east/north/up.
    #[inline]
    pub(crate) fn mirrored(&self) -> bool {
        self.coords == Coords::Grid
    }

    /// A triangle given counter-clockwise from above in east/north/up, in the
    /// winding that keeps its right-hand normal pointing up in this frame.
    #[inline]
    pub(crate) fn orient<T: Copy>(&self, t: [T; 3]) -> [T; 3] {
        if self.mirrored() {
            [t[0], t[2], t[1]]
        } else {
            t
        }
    }
}

/// Where the output sits on the Earth, for the file's metadata.
#[derive(Debug, Clone)]
pub(crate) struct GeoInfo {
    /// The CRS as text ("EPSG:4326", "unknown", a description).
    pub crs: String,
    /// True when the grid's georeference came from its file.
    pub georeferenced: bool,
    /// True for longitude/latitude CRSs.
    pub geographic: bool,
    /// Output coordinate mode.
    pub coords: Coords,
    /// Affine from sample (col, row) to CRS (x, y), GDAL order:
    /// `x = a[0] + col·a[1] + row·a[2]`, `y = a[3] + col·a[4] + row·a[5]`.
    pub sample_to_crs: [f64; 6],
    /// The grid's own transform: origin, pixel size, pixel-is.
    pub origin: [f64; 2],
    /// Pixel size in CRS units (x, y; y negative for north-up grids).
    pub pixel_size: [f64; 2],
    /// "area" or "point".
    pub pixel_is: &'static str,
    /// CRS coordinates of the south-west sample (the local-metres origin).
    pub sw_origin_crs: [f64; 2],
    /// Cell size in metres `[dx, dy]` used for local metres.
    pub cell_size_m: [f64; 2],
    /// Grid width and height in samples.
    pub grid_size: [usize; 2],
}

impl GeoInfo {
    /// Collects the metadata of `grid` for output mode `coords`.
    pub(crate) fn new(grid: &HeightGrid, coords: Coords) -> Self {
        let g = grid.georef();
        let (x0, y0) = g.sample_xy(0.0, 0.0);
        let (sw_x, sw_y) = g.sample_xy(0.0, grid.height() as f64 - 1.0);
        GeoInfo {
            crs: sanitize(&g.crs.to_string()),
            georeferenced: g.known,
            geographic: g.crs.is_geographic(),
            coords,
            sample_to_crs: [x0, g.pixel_x, 0.0, y0, 0.0, g.pixel_y],
            origin: [g.origin_x, g.origin_y],
            pixel_size: [g.pixel_x, g.pixel_y],
            pixel_is: match g.pixel_is {
                PixelIs::Area => "area",
                PixelIs::Point => "point",
            },
            sw_origin_crs: [sw_x, sw_y],
            cell_size_m: grid.cell_size_m(),
            grid_size: [grid.width(), grid.height()],
        }
    }

    /// One-line description of the axes of the output frame.
    pub(crate) fn axes(&self) -> &'static str {
        match self.coords {
            Coords::LocalMetres => {
                "x east, y north, z up, metres; origin at the grid's south-west sample"
            }
            Coords::Grid => {
                "x = column, y = row from the northern row (south), z up in metres; \
                 winding reversed so normals point up"
            }
        }
    }

    /// How the cell size was obtained (mirrors `GeoRef::pixel_size_m_at`).
    fn cell_size_note(&self) -> &'static str {
        match self.crs.as_str() {
            _ if self.geographic => "degrees converted to metres at the grid's centre latitude",
            "EPSG:3857" | "EPSG:900913" | "EPSG:3785" => {
                "Web Mercator units scaled to true metres at the grid's centre latitude"
            }
            _ => "CRS units taken as metres",
        }
    }

    /// The metadata as `key: value` lines (OBJ `#` and PLY `comment` lines).
    pub(crate) fn comment_lines(&self) -> Vec<String> {
        let a = self.sample_to_crs;
        vec![
            "cota terrain mesh".to_string(),
            format!("coords: {} ({})", self.coords, self.axes()),
            format!("crs: {}", self.crs),
            format!("georeferenced: {}", self.georeferenced),
            format!(
                "sample_to_crs: x = {} + col*{} + row*{}, y = {} + col*{} + row*{}",
                a[0], a[1], a[2], a[3], a[4], a[5]
            ),
            format!(
                "sw_origin_crs: {} {}",
                self.sw_origin_crs[0], self.sw_origin_crs[1]
            ),
            format!(
                "cell_size_m: {} {} ({})",
                self.cell_size_m[0],
                self.cell_size_m[1],
                self.cell_size_note()
            ),
            format!("grid_size: {} x {}", self.grid_size[0], self.grid_size[1]),
        ]
    }

    /// The metadata as a JSON object (glTF `asset.extras`).
    pub(crate) fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "generator": "cota",
            "coords": self.coords.name(),
            "axes": self.axes(),
            "crs": self.crs,
            "crs_geographic": self.geographic,
            "georeferenced": self.georeferenced,
            "sample_to_crs": self.sample_to_crs,
            "sample_to_crs_doc": "x = a0 + col*a1 + row*a2, y = a3 + col*a4 + row*a5 (GDAL order, sample centres)",
            "georef": {
                "origin": self.origin,
                "pixel_size": self.pixel_size,
                "pixel_is": self.pixel_is,
            },
            "sw_origin_crs": self.sw_origin_crs,
            "cell_size_m": self.cell_size_m,
            "cell_size_note": self.cell_size_note(),
            "grid_size": self.grid_size,
            "up_axis": "z in the mesh data; the node rotates it to glTF's +y",
        })
    }

    /// The 80-byte binary STL header: a short ASCII note, zero-padded. Never
    /// starts with `solid` (which readers take for ASCII STL).
    pub(crate) fn stl_header(&self, units_per_m: f64) -> [u8; 80] {
        let scale = match units_per_m == 1.0 {
            true => String::new(),
            false => format!(" x{units_per_m}"),
        };
        let text = format!(
            "cota terrain {}{scale}; {}; SW {} {}",
            self.coords, self.crs, self.sw_origin_crs[0], self.sw_origin_crs[1]
        );
        let mut header = [0u8; 80];
        for (dst, src) in header.iter_mut().zip(text.bytes()) {
            *dst = if src.is_ascii_graphic() || src == b' ' {
                src
            } else {
                b'?'
            };
        }
        header
    }
}

/// Replaces control characters (newlines would break OBJ/PLY comments).
fn sanitize(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}
