//! Where a grid's CRS coordinates lie on the Earth: the map between them and
//! WGS 84 longitude/latitude, in both directions.
//!
//! No paper: a format adaptation. Tiling (papers `000_ebf7e3a88dffd361.txt`
//! and `001_49f2c365e8c41172.txt` over the geographic lattice of
//! [`crate::tiles`]) needs every source sample's longitude and latitude and,
//! for every lattice point, the source position under it. Geographic grids
//! map by their affine transform alone ([`LonLat`]); projected ones through a
//! projection that `cota-io` builds from the CRS (pure Rust, `proj4rs`), so
//! that this crate needs no projection library.

use std::fmt;

/// A map between CRS coordinates `(x, y)` and WGS 84 longitude/latitude in
/// degrees. Both directions return `None` outside the map's domain (a point
/// the projection cannot take, or that has no inverse).
pub trait GeoTransform: Send + Sync + fmt::Debug {
    /// WGS 84 `[longitude, latitude]`, degrees, of the CRS position `(x, y)`.
    fn to_lonlat(&self, x: f64, y: f64) -> Option<[f64; 2]>;

    /// The CRS position `[x, y]` of WGS 84 `(lon, lat)`, degrees.
    #[allow(
        clippy::wrong_self_convention,
        reason = "the pair to_lonlat/from_lonlat names the two directions of the map"
    )]
    fn from_lonlat(&self, lon: f64, lat: f64) -> Option<[f64; 2]>;

    /// True when CRS coordinates are longitude/latitude on WGS 84 already (the
    /// map is the identity), so callers may use the affine transform alone.
    fn is_identity(&self) -> bool {
        false
    }
}

/// The identity: coordinates that are WGS 84 longitude/latitude in degrees
/// (EPSG:4326, and geographic CRSs whose datum is taken as WGS 84).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LonLat;

impl GeoTransform for LonLat {
    fn to_lonlat(&self, x: f64, y: f64) -> Option<[f64; 2]> {
        Some([x, y])
    }

    fn from_lonlat(&self, lon: f64, lat: f64) -> Option<[f64; 2]> {
        Some([lon, lat])
    }

    fn is_identity(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn identity_maps_both_ways() {
        let t: &dyn GeoTransform = &LonLat;
        assert_eq!(t.to_lonlat(10.5, -3.25), Some([10.5, -3.25]));
        assert_eq!(t.from_lonlat(10.5, -3.25), Some([10.5, -3.25]));
        assert!(t.is_identity());
    }
}
