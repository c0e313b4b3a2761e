//! The progressive stream as the server holds it: the framed `.cstream` bytes
//! (`cota_io::stream_file`, paper `000_ebf7e3a88dffd361.txt` §3) in memory,
//! their ETag, and a small description for the viewer (`/meta.json`).
//!
//! Every prefix of the stream that ends on a step boundary decodes to a
//! coarser crack-free mesh, so clients fetch it with `Range` requests,
//! coarse first.

use axum::body::Bytes;
use cota_core::stream::{encode, EncodedStream, StreamOptions};
use cota_core::{GeoRef, HeightGrid};
use cota_io::stream_file::{decode_stream_bytes, step_end_offsets, stream_bytes, StreamLimit};
use serde::Serialize;

use crate::error::{Result, ServeError};

/// One step of the stream, as the viewer sees it.
#[derive(Debug, Clone, Serialize)]
pub struct StepMeta {
    /// Bytes of the stream up to the end of this step.
    pub end_offset: u64,
    /// The stated max error of the prefix ending here, metres.
    pub max_error_m: f64,
    /// Triangles of that prefix's mesh.
    pub triangles: usize,
}

/// What `/meta.json` says about the stream.
#[derive(Debug, Clone, Serialize)]
pub struct StreamMeta {
    /// What was read (file names).
    pub name: String,
    /// Grid width, samples.
    pub width: usize,
    /// Grid height, samples.
    pub height: usize,
    /// Ground size of a cell at the grid's centre, metres (x east, y north).
    pub cell_size_m: [f64; 2],
    /// Lowest and highest height, metres.
    pub height_range_m: [f64; 2],
    /// Longitude/latitude of the north-west and south-east samples, degrees,
    /// when the grid is geographic.
    pub lon_lat_bounds: Option<[f64; 4]>,
    /// Bytes of the whole stream.
    pub bytes: u64,
    /// The steps, coarse to fine.
    pub steps: Vec<StepMeta>,
}

/// The stream the server sends.
#[derive(Debug, Clone)]
pub struct StreamAsset {
    bytes: Bytes,
    etag: String,
    meta: StreamMeta,
}

/// FNV-1a, 64 bits.
pub(crate) fn fnv64(b: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &x in b {
        h ^= x as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

fn lon_lat_bounds(g: &GeoRef, width: usize, height: usize) -> Option<[f64; 4]> {
    if !(g.known && g.crs.is_geographic()) {
        return None;
    }
    let (w, n) = g.sample_xy(0.0, 0.0);
    let (e, s) = g.sample_xy(width as f64 - 1.0, height as f64 - 1.0);
    Some([w, n, e, s])
}

impl StreamAsset {
    /// Encodes `grid` (no voids) losslessly on a 1 m lattice: the error steps
    /// of `cota_core::stream::encode`, framed.
    ///
    /// # Errors
    /// [`ServeError::BadStream`] when the grid cannot be encoded.
    pub fn from_grid(grid: &HeightGrid, name: &str) -> Result<Self> {
        let enc = encode(grid, &StreamOptions::default()).map_err(|e| ServeError::BadStream {
            name: name.into(),
            reason: e.to_string(),
        })?;
        let range = grid.valid_range().unwrap_or((0.0, 0.0));
        Ok(Self::from_encoded(
            &enc,
            grid.georef(),
            name,
            [range.0.floor() as f64, range.1.ceil() as f64],
        ))
    }

    /// Frames an encoded stream.
    pub fn from_encoded(
        enc: &EncodedStream,
        georef: &GeoRef,
        name: &str,
        height_range_m: [f64; 2],
    ) -> Self {
        let bytes = stream_bytes(enc, georef);
        let ends = step_end_offsets(enc, georef);
        let (w, h) = (enc.header.width as usize, enc.header.height as usize);
        let steps = enc
            .steps
            .iter()
            .zip(ends)
            .map(|(s, end_offset)| StepMeta {
                end_offset,
                max_error_m: s.max_error_m,
                triangles: s.triangles,
            })
            .collect();
        let meta = StreamMeta {
            name: name.into(),
            width: w,
            height: h,
            cell_size_m: georef.pixel_size_m_at((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0),
            height_range_m,
            lon_lat_bounds: lon_lat_bounds(georef, w, h),
            bytes: bytes.len() as u64,
            steps,
        };
        Self::new(bytes, meta)
    }

    /// A `.cstream` file's bytes, checked by decoding every step.
    ///
    /// # Errors
    /// [`ServeError::BadStream`] naming `name` for anything the reader refuses
    /// (magic, version, checksum, truncation, a step that does not decode).
    pub fn from_stream_bytes(bytes: Vec<u8>, name: &str) -> Result<Self> {
        let d =
            decode_stream_bytes(&bytes, &StreamLimit::ALL).map_err(|e| ServeError::BadStream {
                name: name.into(),
                reason: e.to_string(),
            })?;
        let hd = d.decoder.header();
        let (w, h) = (hd.width as usize, hd.height as usize);
        let z = d.decoder.heights_m().unwrap_or_default();
        let lo = z.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = z.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let steps = d
            .steps
            .iter()
            .map(|s| StepMeta {
                end_offset: s.end_offset,
                max_error_m: s.info.max_error_m,
                triangles: s.info.triangles,
            })
            .collect();
        let g = &d.georef;
        let meta = StreamMeta {
            name: name.into(),
            width: w,
            height: h,
            cell_size_m: g.pixel_size_m_at((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0),
            height_range_m: [lo.floor() as f64, hi.ceil() as f64],
            lon_lat_bounds: lon_lat_bounds(g, w, h),
            bytes: bytes.len() as u64,
            steps,
        };
        Ok(Self::new(bytes, meta))
    }

    fn new(bytes: Vec<u8>, meta: StreamMeta) -> Self {
        let etag = format!("\"{:016x}\"", fnv64(&bytes));
        StreamAsset {
            bytes: Bytes::from(bytes),
            etag,
            meta,
        }
    }

    /// The framed stream.
    pub fn bytes(&self) -> &Bytes {
        &self.bytes
    }

    /// The strong ETag, quoted.
    pub fn etag(&self) -> &str {
        &self.etag
    }

    /// The description served at `/meta.json`.
    pub fn meta(&self) -> &StreamMeta {
        &self.meta
    }
}
