//! A quantized-mesh-1.0 decoder, independent of the encoder (it shares no
//! code with it), written from the specification (CesiumGS/quantized-mesh):
//! header, zig-zag delta vertices, high-water-mark indices (16-bit up to
//! 65 536 vertices, 32-bit above, after padding to 2 or 4 bytes), the four
//! edge lists, and extensions 1 (normals), 2 (water mask) and 4 (metadata).
//! Gzipped tiles are inflated first.
//!
//! Every length is checked against the bytes left, so a truncated or
//! corrupt tile gives a [`DecodeError`], never a panic or an allocation
//! larger than the input warrants.

use cota_core::mesh::check::{PlacedMesh, PlacedVertex};

/// Why bytes are not a quantized-mesh tile.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum DecodeError {
    /// The bytes end early.
    #[error("expected {needed} more bytes for the {what} at offset {at}, found {left}")]
    Truncated {
        /// What was being read.
        what: &'static str,
        /// Where.
        at: usize,
        /// Bytes needed.
        needed: usize,
        /// Bytes left.
        left: usize,
    },
    /// A decoded value is impossible.
    #[error("{0}")]
    Invalid(String),
    /// Gzip data that does not inflate.
    #[error("expected gzip data, found a corrupt stream: {0}")]
    Gzip(String),
}

/// The 88-byte header.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Header {
    /// The tile's centre, ECEF metres.
    pub center: [f64; 3],
    /// Smallest height, metres.
    pub min_height_m: f32,
    /// Largest height, metres.
    pub max_height_m: f32,
    /// Bounding sphere centre, ECEF metres.
    pub sphere_center: [f64; 3],
    /// Bounding sphere radius, metres.
    pub sphere_radius_m: f64,
    /// Horizon occlusion point, ellipsoid-scaled ECEF.
    pub horizon_occlusion_point: [f64; 3],
}

/// A decoded tile.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedTile {
    /// The header.
    pub header: Header,
    /// `u` per vertex, `0..=32767` west to east.
    pub u: Vec<u16>,
    /// `v` per vertex, `0..=32767` south to north.
    pub v: Vec<u16>,
    /// Quantized height per vertex, `0..=32767` from the minimum to the maximum.
    pub height: Vec<u16>,
    /// Triangles, counter-clockwise seen from above.
    pub triangles: Vec<[u32; 3]>,
    /// Vertices on the west, south, east and north edges.
    pub edges: [Vec<u32>; 4],
    /// Whether the indices were 32-bit.
    pub wide_indices: bool,
    /// Oct-encoded normals (extension 1).
    pub normals: Option<Vec<[u8; 2]>>,
    /// Water mask (extension 2): 1 or 65 536 bytes.
    pub water_mask: Option<Vec<u8>>,
    /// Metadata JSON (extension 4).
    pub metadata: Option<String>,
}

impl DecodedTile {
    /// The height of vertex `i` in metres, as a client computes it.
    pub fn height_m(&self, i: usize) -> f64 {
        let (lo, hi) = (
            f64::from(self.header.min_height_m),
            f64::from(self.header.max_height_m),
        );
        lo + f64::from(self.height[i]) / 32767.0 * (hi - lo)
    }

    /// Vertex `i`'s longitude and latitude (degrees) and height (metres)
    /// over `rect` (`[west, south, east, north]`, degrees), as a client
    /// computes them.
    pub fn geodetic(&self, i: usize, rect: [f64; 4]) -> [f64; 3] {
        let m = 32767.0;
        [
            rect[0] + f64::from(self.u[i]) / m * (rect[2] - rect[0]),
            rect[1] + f64::from(self.v[i]) / m * (rect[3] - rect[1]),
            self.height_m(i),
        ]
    }

    /// The tile on its lattice of `cells × cells` cells: vertex `(u, v)` at
    /// `(u·cells / 32767, (32767 − v)·cells / 32767)` cells from the north-west
    /// corner, exactly, for [`cota_core::mesh::check::check_placed_mesh`].
    pub fn to_placed(&self, cells: u64) -> PlacedMesh {
        PlacedMesh {
            den: 32767,
            vertices: (0..self.u.len())
                .map(|i| PlacedVertex {
                    x: u64::from(self.u[i]) * cells,
                    y: (32767 - u64::from(self.v[i].min(32767))) * cells,
                    z_m: self.height_m(i),
                })
                .collect(),
            triangles: self.triangles.clone(),
        }
    }
}

/// Reads little-endian values with bounds checks.
struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], DecodeError> {
        let left = self.b.len() - self.at;
        if n > left {
            return Err(DecodeError::Truncated {
                what,
                at: self.at,
                needed: n,
                left,
            });
        }
        let s = &self.b[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }

    fn f64(&mut self, what: &'static str) -> Result<f64, DecodeError> {
        let s = self.take(8, what)?;
        Ok(f64::from_le_bytes([
            s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7],
        ]))
    }

    fn f32(&mut self, what: &'static str) -> Result<f32, DecodeError> {
        let s = self.take(4, what)?;
        Ok(f32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }

    fn u32(&mut self, what: &'static str) -> Result<u32, DecodeError> {
        let s = self.take(4, what)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }

    fn u16s(&mut self, n: usize, what: &'static str) -> Result<Vec<u16>, DecodeError> {
        let s = self.take(n.saturating_mul(2), what)?;
        Ok(s.chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect())
    }

    /// `n` indices of 2 or 4 bytes.
    fn indices(
        &mut self,
        n: usize,
        wide: bool,
        what: &'static str,
    ) -> Result<Vec<u32>, DecodeError> {
        if wide {
            let s = self.take(n.saturating_mul(4), what)?;
            Ok(s.chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect())
        } else {
            Ok(self.u16s(n, what)?.into_iter().map(u32::from).collect())
        }
    }
}

fn vec3(r: &mut Reader<'_>, what: &'static str) -> Result<[f64; 3], DecodeError> {
    Ok([r.f64(what)?, r.f64(what)?, r.f64(what)?])
}

/// Inflates gzip bytes (magic `1f 8b`), or returns the bytes as they are.
///
/// # Errors
/// [`DecodeError::Gzip`] for a corrupt stream.
pub fn gunzip_if_needed(bytes: &[u8]) -> Result<std::borrow::Cow<'_, [u8]>, DecodeError> {
    if bytes.starts_with(&[0x1f, 0x8b]) {
        use std::io::Read;
        let mut out = Vec::new();
        flate2::read::MultiGzDecoder::new(bytes)
            .read_to_end(&mut out)
            .map_err(|e| DecodeError::Gzip(e.to_string()))?;
        Ok(std::borrow::Cow::Owned(out))
    } else {
        Ok(std::borrow::Cow::Borrowed(bytes))
    }
}

/// Decodes a tile (gzipped or not).
///
/// # Errors
/// [`DecodeError`] for truncated or inconsistent data.
pub fn decode(bytes: &[u8]) -> Result<DecodedTile, DecodeError> {
    let raw = gunzip_if_needed(bytes)?;
    let mut r = Reader { b: &raw, at: 0 };
    let header = Header {
        center: vec3(&mut r, "header")?,
        min_height_m: r.f32("header")?,
        max_height_m: r.f32("header")?,
        sphere_center: vec3(&mut r, "header")?,
        sphere_radius_m: r.f64("header")?,
        horizon_occlusion_point: vec3(&mut r, "header")?,
    };
    let n = r.u32("vertex count")? as usize;
    let mut arrays = [Vec::new(), Vec::new(), Vec::new()];
    for a in arrays.iter_mut() {
        let mut acc = 0i32;
        *a = r
            .u16s(n, "vertex data")?
            .into_iter()
            .map(|z| {
                acc += i32::from(z >> 1) ^ -i32::from(z & 1);
                acc as u16
            })
            .collect();
    }
    let [u, v, height] = arrays;
    if let Some(i) = (0..n).find(|&i| u[i] > 32767 || v[i] > 32767 || height[i] > 32767) {
        return Err(DecodeError::Invalid(format!(
            "vertex {i} decodes outside 0..=32767: u {}, v {}, height {}",
            u[i], v[i], height[i]
        )));
    }
    let wide = n > 65_536;
    let align = if wide { 4 } else { 2 };
    r.take((align - r.at % align) % align, "index padding")?;
    let (triangles, edges) = indices(&mut r, n, wide)?;
    let mut tile = DecodedTile {
        header,
        u,
        v,
        height,
        triangles,
        edges,
        wide_indices: wide,
        normals: None,
        water_mask: None,
        metadata: None,
    };
    extensions(&mut r, &mut tile)?;
    Ok(tile)
}

/// Triangles and the west, south, east and north edge lists.
type Indices = (Vec<[u32; 3]>, [Vec<u32>; 4]);

/// The triangles (high-water-mark decoded) and the four edge lists.
fn indices(r: &mut Reader<'_>, n: usize, wide: bool) -> Result<Indices, DecodeError> {
    let count = r.u32("triangle count")? as usize;
    let codes = r.indices(count.saturating_mul(3), wide, "triangle indices")?;
    let mut highest = 0u32;
    let mut flat = Vec::with_capacity(codes.len());
    for (k, code) in codes.into_iter().enumerate() {
        let i = highest.checked_sub(code).ok_or_else(|| {
            DecodeError::Invalid(format!(
                "index code {code} at {k} is above the high-water mark {highest}"
            ))
        })?;
        if code == 0 {
            highest += 1;
        }
        if i as usize >= n {
            return Err(DecodeError::Invalid(format!(
                "index {i} at {k} refers past the {n} vertices"
            )));
        }
        flat.push(i);
    }
    let triangles = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let mut edges: [Vec<u32>; 4] = Default::default();
    for e in edges.iter_mut() {
        let m = r.u32("edge count")? as usize;
        *e = r.indices(m, wide, "edge indices")?;
        if let Some(&bad) = e.iter().find(|&&i| i as usize >= n) {
            return Err(DecodeError::Invalid(format!(
                "edge index {bad} refers past the {n} vertices"
            )));
        }
    }
    Ok((triangles, edges))
}

fn extensions(r: &mut Reader<'_>, tile: &mut DecodedTile) -> Result<(), DecodeError> {
    while r.at < r.b.len() {
        let id = r.take(1, "extension id")?[0];
        let len = r.u32("extension length")? as usize;
        let data = r.take(len, "extension data")?;
        match id {
            1 => {
                if data.len() != 2 * tile.u.len() {
                    return Err(DecodeError::Invalid(format!(
                        "expected {} bytes of normals, found {}",
                        2 * tile.u.len(),
                        data.len()
                    )));
                }
                tile.normals = Some(data.chunks_exact(2).map(|c| [c[0], c[1]]).collect());
            }
            2 => {
                if data.len() != 1 && data.len() != 65_536 {
                    return Err(DecodeError::Invalid(format!(
                        "expected a water mask of 1 or 65536 bytes, found {}",
                        data.len()
                    )));
                }
                tile.water_mask = Some(data.to_vec());
            }
            4 => {
                let mut m = Reader { b: data, at: 0 };
                let jl = m.u32("metadata length")? as usize;
                let json = m.take(jl, "metadata")?;
                tile.metadata = Some(
                    String::from_utf8(json.to_vec())
                        .map_err(|_| DecodeError::Invalid("metadata is not UTF-8".into()))?,
                );
            }
            _ => {}
        }
    }
    Ok(())
}
