//! Errors of [`crate::crs`]: each says what was expected and what was found,
//! and how to go on. Messages name the CRS; the callers that read a file
//! ([`crate::crs::assign_src_crs`], the CLI) name the file.
//!
//! Reference: the PROJ parameters named in the messages are PROJ's
//! (<https://proj.org/usage/projections.html>, "+towgs84", "+nadgrids").

use std::path::PathBuf;

/// What went wrong turning a CRS into a map to and from WGS 84.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CrsError {
    /// The grid has no CRS (a PNG, an ESRI grid without `.prj`, a GeoTIFF
    /// without GeoKeys).
    #[error("expected a known CRS to map to longitude/latitude, found none (the input declares no CRS); pass --src-crs EPSG:N (or a '+proj=...' PROJ string)")]
    Unknown,
    /// An EPSG code with no definition.
    #[error("expected an EPSG code that cota has a PROJ definition for, found EPSG:{code} (not in crs-definitions' table); pass its PROJ string instead: --src-crs '+proj=...'")]
    UnknownEpsg {
        /// The code.
        code: u32,
    },
    /// Text that is neither `EPSG:N` nor a PROJ string.
    #[error("expected EPSG:N (e.g. EPSG:32633) or a PROJ string starting with '+proj=', found {found:?}")]
    Unparseable {
        /// The text given.
        found: String,
    },
    /// A PROJ string that proj4rs refuses.
    #[error("expected a PROJ definition proj4rs can read, found {definition:?} ({reason})")]
    BadProj {
        /// The definition.
        definition: String,
        /// proj4rs's reason.
        reason: String,
    },
    /// A datum shift by grid files (NTv2, NADCON, OSTN15), which cota does not read.
    #[error("{crs}: expected a datum shift cota can apply (a +towgs84 Helmert, or none), found grid files +nadgrids={grids}; grid-based shifts are not supported: reproject the input (e.g. gdalwarp -t_srs EPSG:4326) or pass --src-crs with a +towgs84 approximation")]
    GridShift {
        /// The CRS, as displayed.
        crs: String,
        /// The grids named.
        grids: String,
    },
    /// A datum on another ellipsoid than WGS 84's with no shift to WGS 84:
    /// its positions could be hundreds of metres off.
    #[error("{crs}: expected a datum shift to WGS 84 (+datum=, +towgs84=) for a datum on the {ellipsoid} ellipsoid, found none in {definition:?}; add +towgs84=DX,DY,DZ[,RX,RY,RZ,S] (its Helmert to WGS 84), or +nadgrids=@null to take its longitudes and latitudes as WGS 84's, with --src-crs")]
    NoDatumShift {
        /// The CRS, as displayed.
        crs: String,
        /// The ellipsoid, as named or as `a=…, b=…`.
        ellipsoid: String,
        /// The definition.
        definition: String,
    },
    /// A CRS known only by a description cota cannot turn into a definition.
    #[error("{crs}: expected a CRS with a definition (an EPSG code or PROJ parameters), found only its description{why}; pass --src-crs EPSG:N (or a '+proj=...' PROJ string) for it")]
    DescriptionOnly {
        /// The description.
        crs: String,
        /// Why the description is not enough (starts with "; " when given).
        why: String,
    },
    /// A point where the projection, or its inverse, gives no result.
    #[error("{crs}: expected ({x}, {y}) to map {direction}, found no result ({reason}); is the grid's georeference in this CRS?")]
    OutsideDomain {
        /// The CRS, as displayed.
        crs: String,
        /// The point's first coordinate.
        x: f64,
        /// The point's second coordinate.
        y: f64,
        /// "to WGS 84 longitude/latitude" or "back from WGS 84".
        direction: String,
        /// What failed.
        reason: String,
    },
    /// A projection whose inverse does not come back to where it started.
    #[error("{crs}: expected ({x}, {y}) to come back within {tolerance} of itself through WGS 84 and back, found ({back_x}, {back_y}) ({distance:.3e} away); the projection is not invertible there")]
    RoundTrip {
        /// The CRS, as displayed.
        crs: String,
        /// The start.
        x: f64,
        /// The start.
        y: f64,
        /// Where the round trip ended.
        back_x: f64,
        /// Where the round trip ended.
        back_y: f64,
        /// The distance, in CRS units.
        distance: f64,
        /// The tolerance, in CRS units.
        tolerance: f64,
    },
    /// `--src-crs` says one thing and the file another.
    #[error("{}: the file declares its CRS as {file}, which contradicts --src-crs {flag} ({why}); drop --src-crs to use the file's own CRS, or correct the file's georeference (e.g. gdal_edit.py -a_srs) if --src-crs is right", path.display())]
    Contradiction {
        /// The file.
        path: PathBuf,
        /// The file's CRS, as displayed.
        file: String,
        /// The flag's CRS, as displayed.
        flag: String,
        /// How they differ.
        why: String,
    },
}
