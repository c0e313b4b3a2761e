//! Coordinate reference systems: from a grid's [`Crs`](cota_core::Crs) to its map to and
//! from WGS 84 longitude/latitude ([`cota_core::GeoTransform`]).
//!
//! References:
//! * PROJ's definitions and transformation pipeline (<https://proj.org>):
//!   PROJ strings (`+proj=utm +zone=33 +datum=WGS84`), `+towgs84` Helmert
//!   shifts (position-vector convention), `+nadgrids`.
//! * The EPSG Geodetic Parameter Dataset (<https://epsg.org>): codes and
//!   names; the PROJ strings of its codes come from the `crs-definitions`
//!   crate.
//! * The GeoTIFF specification's GeoKeys (OGC 19-008r4, §7) for CRSs a
//!   GeoTIFF defines by parameters (`crate::read::geotiff`).
//!
//! Crates, chosen for being pure Rust (no C PROJ library, no `proj.db`):
//! * `proj4rs` 0.3 does the projection math: a port of PROJ 4's
//!   `pj_transform` with the projections DEMs come in (tmerc/utm with the
//!   Poder/Engsager algorithm PROJ uses, lcc, laea, aea, merc, stere, …) and
//!   3- and 7-parameter Helmert datum shifts. Maintained (3Liz; 0.3.0 is
//!   from 2026), WebAssembly-ready, MIT/Apache-2.0. Its results match PROJ
//!   9's to a millimetre or better on the CRSs of `tests/crs.rs`.
//! * `crs-definitions` 0.6 maps EPSG codes to PROJ strings (about 6 000
//!   codes, CC0), with only its `proj4` feature (no 4 MB of WKT). It is the
//!   version proj4rs itself uses.
//!
//! What it does not do: grid-based datum shifts (NTv2, NADCON, OSTN15),
//! time-dependent (plate-motion) transformations, vertical datums. The
//! datums of the ITRF family (NAD83, ETRS89, GDA, SIRGAS, …) are taken as
//! WGS 84 (see [`resolve`]).
//!
//! Parts:
//! * [`transform_for`] ([`resolve`]): the map of a CRS; [`describe`] its
//!   name, [`definition`] its PROJ string.
//! * [`ProjTransform`] ([`project`]): a PROJ string through proj4rs.
//! * [`parse_crs`] ([`parse`]): `--src-crs` text.
//! * [`src_crs_for`], [`assign_src_crs`] ([`assign`]): `--src-crs` against
//!   the files' own CRSs.
//! * [`footprint()`], [`check_round_trip`], [`transform_for_grid`]
//!   ([`footprint`](mod@footprint)): where a grid lies, and whether its map inverts.
//! * [`epsg`]: EPSG definitions and names; [`params`]: PROJ string tokens.

pub mod assign;
pub mod epsg;
mod error;
pub mod footprint;
pub mod params;
pub mod parse;
pub mod project;
pub mod resolve;

pub use self::assign::{assign_src_crs, src_crs_for, SAME_POSITION_M};
pub use self::error::CrsError;
pub use self::footprint::{
    check_round_trip, footprint, sample_corners, transform_for_grid, FOOTPRINT_STEPS_PER_SIDE,
};
pub use self::parse::parse_crs;
pub use self::project::ProjTransform;
pub use self::resolve::{
    definition, describe, transform_and_tolerance, transform_for, HELMERT_ROUND_TRIP_TOLERANCE_M,
    ROUND_TRIP_TOLERANCE_M,
};
